"""Reproduce the paper's Figs. 3-5 and a Table I-style summary on public real scans.

    python benchmarks/paper.py [--out results/paper] [--rotations 100] [--quick]

Writes (atomically: temporary file + os.replace) into ``--out``:

* ``lattice_table.csv``: per-lattice properties (``planner.measure.lattice_table``).
* ``fig3_neighbour_distances.{png,csv}``: ordered distances to adjacent lattice points.
* ``fig4_distance_distributions.png``, ``fig4_distance_stats.csv``, ``fig4_ratios.csv``:
  distances from a cell centre to points uniform in the cell and in its adjacent cells.
* ``rotations.csv`` (resumable: one row per rotation, lattice, dataset and cell volume;
  finished rotations are skipped on re-run), ``table1.csv``, ``fig5_distortion_cdf.png``,
  ``fig5_voxel_count_cdf.png``.

Real data is read from ``../shared/data`` relative to the repository root; scans that are
absent (or unreadable without ``planner.io``) are skipped with a message.
"""

from __future__ import annotations

import argparse
import bz2
import csv
import io
import os
import sys
import tempfile
import time
from collections.abc import Callable, Sequence
from pathlib import Path

import numpy as np

from planner.lattice import Lattice
from planner.measure import (
    NAMED,
    adjacency_offsets,
    distance_distributions,
    distribution_stats,
    exact_extent,
    format_table,
    lattice_table,
    neighbour_distances,
    quantization_metrics,
    random_rotations,
    table1_summary,
)

DATA_DIR = Path(__file__).resolve().parents[1] / ".." / "shared" / "data"
DATASETS = {
    "octomap_scan": "octomap/scan.dat.bz2",
    "pcl_room": "pcl_room/room_scan1.pcd",
    "velodyne": "velodyne/251370668.pcd",
}
COLORS = {"cubic": "tab:blue", "bcc": "tab:orange", "fcc": "tab:green",
          "mcc": "tab:red", "hex": "tab:purple"}
ADJ_LABEL = {
    "face": "face-adjacent cells (share a face)",
    "full": "all touching cells (face, edge or vertex)",
    "paper": "paper's Delta cells (eqs. 3-7)",
}
ROT_FIELDS = ["dataset", "cell_volume", "rotation", "seed", "n_points", "lattice",
              "distortion", "mse_per_dim", "voxel_count"]


# -- atomic output -----------------------------------------------------------------------
def _atomic(path: Path, write: Callable[[Path], None]) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    os.close(fd)
    try:
        write(Path(tmp))
        mask = os.umask(0)
        os.umask(mask)
        os.chmod(tmp, 0o666 & ~mask)  # mkstemp creates 0600; give the usual permissions
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def write_csv(path: Path, rows: Sequence[dict], fields: Sequence[str] | None = None) -> None:
    """Write ``rows`` (dicts) as CSV atomically; floats with 10 significant digits."""
    fields = list(fields or (rows[0] if rows else []))
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=fields, extrasaction="ignore", lineterminator="\n")
    w.writeheader()
    for r in rows:
        w.writerow({k: (f"{v:.10g}" if isinstance(v, float) else v) for k, v in r.items()})
    _atomic(path, lambda p: p.write_text(buf.getvalue()))


def save_fig(fig, path: Path) -> None:
    """Save a matplotlib figure as PNG atomically."""
    _atomic(path, lambda p: fig.savefig(p, format="png", dpi=110, bbox_inches="tight"))


# -- data --------------------------------------------------------------------------------
def load_scan(path: Path) -> np.ndarray | None:
    """(N, 3) float64 points of one scan (metres) with non-finite and exact-origin
    (no-return) points dropped; ``None`` (with a message) when it cannot be read."""
    if not path.exists():
        print(f"  skip {path.name}: {path} not found", file=sys.stderr)
        return None
    try:
        from planner.io import load_points
    except ImportError:
        load_points = None
    if load_points is not None:
        pts = np.asarray(load_points(path), dtype=float)
    elif path.name.endswith(".dat.bz2"):
        with bz2.open(path, "rt") as f:
            pts = np.loadtxt(f, dtype=float, ndmin=2)[:, :3]
    else:
        print(f"  skip {path.name}: planner.io not available yet", file=sys.stderr)
        return None
    pts = pts[np.isfinite(pts).all(axis=1)]
    return np.ascontiguousarray(pts[np.any(pts != 0.0, axis=1)])


# -- experiments -------------------------------------------------------------------------
def fig3(out: Path, plt) -> list[dict]:
    rows = []
    fig, ax = plt.subplots(figsize=(8, 5))
    for name in NAMED:
        lat = Lattice.named(name, 1.0)
        face = neighbour_distances(lat, "face")
        full = neighbour_distances(lat, "full")
        more = neighbour_distances(lat, "full+2")
        n_full = len(full)
        ranks = np.arange(1, len(more) + 1)
        for i, d in enumerate(more):
            kind = ("face" if i < len(face) else "edge/vertex") if i < n_full else "next shells"
            rows.append({"lattice": name, "rank": i + 1, "distance": float(d), "set": kind})
        c = COLORS[name]
        ax.plot(ranks[:n_full], full, "-", color=c, lw=1.5, label=f"{name} ({len(face)} face"
                f" + {n_full - len(face)} edge/vertex)")
        ax.plot(ranks[: len(face)], face, "o", color=c, ms=4)
        ax.plot(ranks[len(face):n_full], full[len(face):], "o", mfc="white", color=c, ms=4)
        ax.plot(ranks[n_full - 1:], more[n_full - 1:], "--", color=c, alpha=0.25, lw=1)
        ax.plot(ranks[n_full:], more[n_full:], ".", color=c, alpha=0.25)
    ax.set_xlabel("neighbour rank (ordered by distance)")
    ax.set_ylabel("distance to neighbour lattice point (m, cell volume 1 m$^3$)")
    ax.set_title("Fig. 3: ordered distances to adjacent lattice points\n"
                 "filled = face-adjacent, open = edge/vertex-adjacent, faint = next 2 shells")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="lower right")
    save_fig(fig, out / "fig3_neighbour_distances.png")
    plt.close(fig)
    write_csv(out / "fig3_neighbour_distances.csv", rows)
    return rows


def fig4(out: Path, plt, n: int, seed: int) -> tuple[list[dict], list[dict]]:
    kinds = ("face", "full", "paper")
    stats, dists = [], {}
    for name in NAMED:
        lat = Lattice.named(name, 1.0)
        dd = distance_distributions(lat, n, seed=seed, kinds=kinds)
        dists[name] = dd
        for key, d in dd.items():
            offs = None if key == "cell" else adjacency_offsets(lat, key)
            lo, hi = exact_extent(lat, offs)
            stats.append({"lattice": name, "set": key,
                          "n_cells": 1 if offs is None else len(offs),
                          **distribution_stats(d), "exact_min": lo, "exact_max": hi,
                          "exact_range": hi - lo})
    write_csv(out / "fig4_distance_stats.csv", stats)

    by = {(s["lattice"], s["set"]): s for s in stats}
    ratios = []
    combos = [("cell", "cell"), ("face", "face"), ("full", "full"), ("paper", "paper"),
              ("face", "full")]
    for fcc_set, cub_set in combos:
        f, c = by[("fcc", fcc_set)], by[("cubic", cub_set)]
        ratios.append({
            "fcc_set": fcc_set, "cubic_set": cub_set,
            "fcc_cells": f["n_cells"], "cubic_cells": c["n_cells"],
            "std_ratio": f["std"] / c["std"],
            "range90_ratio": f["range90"] / c["range90"],
            "range_ratio": f["exact_range"] / c["exact_range"],
        })
    write_csv(out / "fig4_ratios.csv", ratios)

    from matplotlib.lines import Line2D

    fig, axes = plt.subplots(1, 3, figsize=(16, 4.8), sharey=True)
    bins = np.linspace(0, 2.7, 136)
    for ax, kind in zip(axes, kinds, strict=True):
        for name in NAMED:
            c = COLORS[name]
            ax.hist(dists[name]["cell"], bins=bins, density=True, histtype="step", color=c,
                    lw=1.2)
            ax.hist(dists[name][kind], bins=bins, density=True, histtype="step", color=c,
                    lw=1.2, ls="--")
        counts = ", ".join(f"{nm} {by[(nm, kind)]['n_cells']}" for nm in NAMED)
        ax.set_title(f"adjacent = {ADJ_LABEL[kind]}\ncells: {counts}", fontsize=9)
        ax.set_xlabel("distance from cell centre (m, cell volume 1 m$^3$)")
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("probability density (1/m)")
    handles = [Line2D([], [], color=COLORS[nm], label=nm) for nm in NAMED] + [
        Line2D([], [], color="k", label="own cell"),
        Line2D([], [], color="k", ls="--", label="adjacent cells"),
    ]
    fig.legend(handles=handles, loc="center left", bbox_to_anchor=(1.0, 0.5), fontsize=9)
    fig.suptitle("Fig. 4: distances from the cell centre to points uniform in the cell (solid)"
                 " and in the adjacent cells (dashed)", y=1.06)
    save_fig(fig, out / "fig4_distance_distributions.png")
    plt.close(fig)
    return stats, ratios


def _read_rotations(path: Path) -> list[dict]:
    if not path.exists():
        return []
    with path.open(newline="") as f:
        rows = list(csv.DictReader(f))
    good = []
    for r in rows:
        try:
            good.append({"dataset": r["dataset"], "cell_volume": float(r["cell_volume"]),
                         "rotation": int(r["rotation"]), "seed": int(r["seed"]),
                         "n_points": int(r["n_points"]), "lattice": r["lattice"],
                         "distortion": float(r["distortion"]),
                         "mse_per_dim": float(r["mse_per_dim"]),
                         "voxel_count": int(r["voxel_count"])})
        except (KeyError, TypeError, ValueError):
            continue
    return good


def rotation_experiment(out: Path, scans: dict[str, np.ndarray], volumes: Sequence[float],
                        k: int, seed: int) -> list[dict]:
    """Quantize every scan under the same ``k`` random rotations to every lattice at every
    cell volume; resumable through ``rotations.csv``. Returns the rows for this config."""
    path = out / "rotations.csv"
    rows = _read_rotations(path)
    # A rotation counts as done only when all lattices are present for it.
    count: dict[tuple, int] = {}
    for r in rows:
        key = (r["dataset"], r["cell_volume"], r["rotation"], r["seed"], r["n_points"])
        count[key] = count.get(key, 0) + 1
    done = {key for key, c in count.items() if c >= len(NAMED)}
    rows = [r for r in rows
            if (r["dataset"], r["cell_volume"], r["rotation"], r["seed"], r["n_points"]) in done]
    rots = random_rotations(k, seed)
    skipped = 0
    t0 = time.perf_counter()
    for ds, pts in scans.items():
        for vol in volumes:
            lats = [Lattice.named(name, vol) for name in NAMED]
            for i, rot in enumerate(rots):
                key = (ds, float(vol), i, seed, len(pts))
                if key in done:
                    skipped += 1
                    continue
                p = pts @ rot.T
                for lat in lats:
                    m = quantization_metrics(lat, p)
                    rows.append({"dataset": ds, "cell_volume": float(vol), "rotation": i,
                                 "seed": seed, "n_points": len(pts), "lattice": lat.name,
                                 "distortion": m["distortion"],
                                 "mse_per_dim": m["mse_per_dim"],
                                 "voxel_count": m["voxel_count"]})
                write_csv(path, rows, ROT_FIELDS)
    if skipped:
        print(f"  resumed: {skipped} (dataset, volume, rotation) runs already in {path.name}")
    print(f"  rotation experiment: {time.perf_counter() - t0:.1f} s")
    want = {(ds, float(v), len(p)) for ds, p in scans.items() for v in volumes}
    return [r for r in rows if r["seed"] == seed and r["rotation"] < k
            and (r["dataset"], r["cell_volume"], r["n_points"]) in want]


def fig5(out: Path, plt, rows: list[dict], scans: dict[str, np.ndarray],
         volumes: Sequence[float]) -> None:
    for metric, fname, xlabel in (
        ("distortion", "fig5_distortion_cdf.png", "distortion E, mean |Q(x) - x| (m)"),
        ("voxel_count", "fig5_voxel_count_cdf.png", "voxel count (occupied cells)"),
    ):
        nr, nc = len(scans), len(volumes)
        fig, axes = plt.subplots(nr, nc, figsize=(5.2 * nc, 3.6 * nr), squeeze=False)
        for a, ds in enumerate(scans):
            for b, vol in enumerate(volumes):
                ax = axes[a][b]
                for name in NAMED:
                    v = np.sort([r[metric] for r in rows if r["dataset"] == ds
                                 and r["cell_volume"] == float(vol) and r["lattice"] == name])
                    if len(v):
                        ax.step(np.r_[v[0], v], np.arange(len(v) + 1) / len(v),
                                where="post", color=COLORS[name], label=name)
                ax.set_title(f"{ds} ({len(scans[ds])} points), cell {vol:g} m$^3$", fontsize=9)
                ax.set_xlabel(xlabel)
                ax.set_ylabel("cumulative fraction of rotations")
                ax.grid(alpha=0.3)
                ax.legend(fontsize=7)
        k = len({r["rotation"] for r in rows})
        fig.suptitle(f"Fig. 5: CDF over {k} uniform random rotations of {metric.replace('_', ' ')}")
        fig.tight_layout()
        save_fig(fig, out / fname)
        plt.close(fig)


# -- main --------------------------------------------------------------------------------
def main(argv: Sequence[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", type=Path, default=Path("results/paper"), help="output directory")
    ap.add_argument("--rotations", type=int, default=100, help="random rotations (default 100)")
    ap.add_argument("--volumes", type=float, nargs="+", default=[0.125, 0.001],
                    help="cell volumes for the scan experiment, m^3 (default 0.125 0.001)")
    ap.add_argument("--samples", type=int, default=10**6,
                    help="uniform samples per distribution for Fig. 4 (default 1e6)")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--data", type=Path, default=DATA_DIR, help="real data directory")
    ap.add_argument("--quick", action="store_true",
                    help="CI-sized run: 4 rotations, 5e4 samples, scans subsampled to 2e4 points")
    args = ap.parse_args(argv)
    if args.rotations < 1 or args.samples < 100 or any(v <= 0 for v in args.volumes):
        ap.error("--rotations >= 1, --samples >= 100 and positive --volumes required")
    k, n, n_table = args.rotations, args.samples, 10**6
    if args.quick:
        k, n, n_table = min(k, 4), min(n, 50_000), 100_000

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out = args.out
    out.mkdir(parents=True, exist_ok=True)
    np.set_printoptions(precision=4)

    print("== Lattice properties (cell volume 1 m^3)")
    table = lattice_table(1.0, n_points=n_table, seed=args.seed)
    write_csv(out / "lattice_table.csv", table)
    print(format_table(table, ["lattice", "n_face", "n_full", "face_max", "full_max",
                               "packing_radius", "covering_radius", "nsm_exact", "nsm_mc",
                               "mean_error", "points_per_s"]))

    print("\n== Fig. 3: neighbour distances (cell volume 1 m^3)")
    f3 = fig3(out, plt)
    for name in NAMED:
        d = [r["distance"] for r in f3 if r["lattice"] == name and r["set"] != "next shells"]
        print(f"  {name:5s} {len(d):2d} touching neighbours, distances "
              f"{np.unique(np.round(d, 4))}")

    print(f"\n== Fig. 4: distance distributions ({n} uniform samples each, cell volume 1 m^3)")
    stats, ratios = fig4(out, plt, n, args.seed)
    print(format_table(stats, ["lattice", "set", "n_cells", "mean", "std", "p5", "p95",
                               "range90", "exact_min", "exact_max", "exact_range"]))
    print("\n  FCC / cubic (range90 = p95 - p5 of the sample; range = exact max - min):")
    print(format_table(ratios))

    print(f"\n== Fig. 5 / Table I: {k} uniform random rotations (Shoemake), same for all lattices")
    scans = {}
    for ds, rel in DATASETS.items():
        pts = load_scan(args.data / rel)
        if pts is None:
            continue
        if args.quick and len(pts) > 20_000:
            pts = pts[np.random.default_rng(args.seed).choice(len(pts), 20_000, replace=False)]
        scans[ds] = pts
        print(f"  {ds}: {len(pts)} points from {rel}")
    if not scans:
        print("  no real scans available: skipping Fig. 5 and Table I")
        return 0
    rows = rotation_experiment(out, scans, args.volumes, k, args.seed)
    fig5(out, plt, rows, scans, args.volumes)
    t1 = table1_summary(rows)
    write_csv(out / "table1.csv", t1)
    print("  medians over rotations; rel_* = % change vs cubic (negative = better)")
    print(format_table(t1, ["dataset", "cell_volume", "lattice", "rotations", "voxel_count",
                            "rel_voxel_count", "mse_per_dim", "rel_mse_per_dim",
                            "distortion", "rel_distortion"]))
    print(f"\nwrote {out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
