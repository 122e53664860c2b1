"""Reproduce the paper's measurements (``planner stats``): Figs. 3-5 and Table I.

Writes (atomically) into the output folder:

* ``lattice_table.csv``: per-lattice properties (:func:`planner.analysis.measure.lattice_table`).
* ``fig3_neighbour_distances.{png,csv}``: ordered distances to adjacent lattice points.
* ``fig4_distance_distributions.png``, ``fig4_distance_stats.csv``, ``fig4_ratios.csv``.
* ``table1.csv`` / ``table1.md``: **the paper's Table I protocol**: each real scan as one
  gravity-aligned map, no rotation, cell volume 0.125 m^3; voxel count, MSE per dimension,
  RMS distance error sqrt(3 x MSE/dim) and eq. 13's mean distance; the hex prism at the
  paper's height and at its optimal height.
* ``rotations.csv`` (resumable), ``fig5_summary.csv``, ``fig5_distortion_cdf.png``,
  ``fig5_voxel_count_cdf.png``: **the Fig. 5 protocol**: the same K uniform random rotations
  for every lattice, with uniform random points as the reference data set.
* ``metadata.json``: commit, package versions, CPU, date.

Real data is read from ``../shared/data`` (relative to the current folder or the source
checkout); absent scans are skipped with a message.
"""

from __future__ import annotations

import csv
import io
import json
import sys
import time
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from planner.analysis.measure import (
    NAMED,
    adjacency_offsets,
    distance_distributions,
    distribution_stats,
    exact_extent,
    format_table,
    lattice_table,
    neighbour_distances,
    optimal_hex_height,
    quantization_metrics,
    random_rotations,
    rotation_summary,
    table1,
)
from planner.analysis.metadata import run_metadata
from planner.analysis.style import LATTICE_COLORS
from planner.budget import require
from planner.errors import PlannerError
from planner.fsutil import atomic_path, write_text_atomic
from planner.io import load_points
from planner.lattice import Lattice
from planner.progress import Progress

DATASETS = {
    "octomap_scan": "octomap/scan.dat.bz2",
    "pcl_room": "pcl_room/room_scan1.pcd",
    "velodyne": "velodyne/251370668.pcd",
}
UNIFORM = "uniform_random"
COLORS = LATTICE_COLORS
ADJ_LABEL = {
    "face": "face-adjacent cells (share a face)",
    "full": "all touching cells (face, edge or vertex)",
    "paper": "paper's Delta cells (eqs. 3-7)",
}
ROT_FIELDS = ["dataset", "cell_volume", "rotation", "seed", "n_points", "lattice",
              "distortion", "mse_per_dim", "voxel_count"]
TABLE1_HEADERS = {
    "dataset": "map", "lattice": "lattice", "height": "prism height (m)",
    "cell_volume": "cell volume (m^3)", "voxel_count": "voxel count",
    "rel_voxel_count": "voxels vs cubic (%)", "mse_per_dim": "MSE / dimension (m^2)",
    "rms_distance_error": "RMS distance error sqrt(3 MSE/dim) (m)",
    "mean_distance_eq13": "mean distance, eq. 13 (m)",
}


def default_data_dir() -> Path:
    """``../shared/data`` from the current folder, else from the source checkout."""
    here = Path.cwd() / ".." / "shared" / "data"
    checkout = Path(__file__).resolve().parents[2]
    if here.is_dir() or not (checkout / "pyproject.toml").is_file():
        return here
    return checkout / ".." / "shared" / "data"


def write_csv(path: Path, rows: Sequence[dict], fields: Sequence[str] | None = None) -> None:
    """Write ``rows`` (dicts) as CSV atomically; floats with 10 significant digits."""
    fields = list(fields or (rows[0] if rows else []))
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=fields, extrasaction="ignore", lineterminator="\n")
    w.writeheader()
    for r in rows:
        w.writerow({k: (f"{v:.10g}" if isinstance(v, float) else v) for k, v in r.items()})
    write_text_atomic(path, buf.getvalue())


def save_fig(fig, path: Path) -> None:
    """Save a matplotlib figure as PNG atomically."""
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format="png", dpi=110, bbox_inches="tight")


# -- data --------------------------------------------------------------------------------
def load_scan(path: Path) -> np.ndarray | None:
    """(N, 3) float64 points of one scan (metres) with non-finite and exact-origin
    (no-return) points dropped; ``None`` (with a message) when it cannot be read."""
    if not path.exists():
        print(f"  skip {path.name}: {path} not found", file=sys.stderr)
        return None
    try:
        pts = np.asarray(load_points(path), dtype=float)
    except PlannerError as exc:
        print(f"  skip {path.name}: {exc}", file=sys.stderr)
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
    with Progress(len(NAMED), "lattices", label="Fig. 4") as bar:
        for name in NAMED:
            bar.step(0)
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
            bar.step()
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
    todo = sum((ds, float(v), i, seed, len(p)) not in done
               for ds, p in scans.items() for v in volumes for i in range(len(rots)))
    with Progress(todo, "rotations", label="Fig. 5") as bar:
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
                    bar.step()
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
        k = len({r["rotation"] for r in rows})
        fig, axes = plt.subplots(nr, nc, figsize=(5.2 * nc, 3.6 * nr), squeeze=False)
        for a, ds in enumerate(scans):
            for b, vol in enumerate(volumes):
                ax = axes[a][b]
                for i, name in enumerate(NAMED):
                    v = np.sort([r[metric] for r in rows if r["dataset"] == ds
                                 and r["cell_volume"] == float(vol) and r["lattice"] == name])
                    if len(v) and k == 1:  # one rotation: a CDF would be one vertical line
                        ax.plot(v, np.full(len(v), i), "o", ms=8, color=COLORS[name],
                                label=name)
                    elif len(v):
                        ax.step(np.r_[v[0], v], np.arange(len(v) + 1) / len(v),
                                where="post", color=COLORS[name], label=name)
                ax.set_title(f"{ds} ({len(scans[ds])} points), cell {vol:g} m$^3$", fontsize=9)
                ax.set_xlabel(xlabel)
                ax.xaxis.set_major_locator(plt.MaxNLocator(5))  # no crowded labels
                if k == 1:
                    ax.set_yticks(range(len(NAMED)), list(NAMED))
                    ax.set_ylim(-0.6, len(NAMED) - 0.4)
                else:
                    ax.set_ylabel("cumulative fraction of rotations")
                    ax.legend(fontsize=7)
                ax.grid(alpha=0.3)
        what = metric.replace("_", " ")
        fig.suptitle(f"Fig. 5 (rotated protocol): CDF over {k} uniform random rotations of "
                     f"{what}, same rotations for every lattice" if k > 1 else
                     f"Fig. 5 (rotated protocol), one random rotation: {what} per lattice "
                     f"(--rotations K > 1 draws the CDF over K rotations)")
        fig.tight_layout()
        save_fig(fig, out / fname)
        plt.close(fig)


# -- Table I -----------------------------------------------------------------------------
def table1_protocol(out: Path, scans: dict[str, np.ndarray], cell_volume: float) -> list[dict]:
    """The paper's Table I protocol on every scan: no rotation, one cell volume."""
    rows = []
    real = [ds for ds in scans if ds != UNIFORM]
    with Progress(len(real), "scans", label="Table I") as bar:
        for ds in real:
            bar.step(0)
            rows += [{"dataset": ds, **r} for r in table1(scans[ds], cell_volume)]
            bar.step()
    write_csv(out / "table1.csv", rows)
    write_text_atomic(out / "table1.md", table1_markdown(rows, cell_volume) + "\n")
    return rows


def table1_markdown(rows: list[dict], cell_volume: float) -> str:
    """Table I as a labelled Markdown table."""
    return (f"Table I protocol: each map as recorded (gravity-aligned, no rotation), cell "
            f"volume {cell_volume:g} m^3. The hex prism is listed at the paper's height "
            f"3^(-1/6) V^(1/3) and at its optimal height {optimal_hex_height(1):.4f} "
            "V^(1/3).\n\n"
            + format_table(rows, list(TABLE1_HEADERS), headers=list(TABLE1_HEADERS.values()),
                           markdown=True))


# -- main --------------------------------------------------------------------------------
def reproduce(out: Path, *, rotations: int = 100, volumes: Sequence[float] = (0.125, 0.001),
              samples: int = 10**6, seed: int = 0, data: Path | None = None,
              quick: bool = False, table1_volume: float = 0.125, jobs: int = 1) -> int:
    """Run every experiment and write the outputs into ``out``; returns an exit status.

    ``quick`` is a CI-sized run: at most 4 rotations, 5e4 samples, scans subsampled to
    2e4 points.
    """
    k, n, n_table = rotations, samples, 10**6
    if quick:
        k, n, n_table = min(k, 4), min(n, 50_000), 100_000
    # per sample: its point, its cell and the error vectors (float64 / int64 triples)
    require(float(n) * 3 * 8 * 6, f"{n} samples per distribution (--samples)",
            error=PlannerError)
    require(float(k) * 4 * 8 * 4, f"{k} rotations (--rotations)", error=PlannerError)
    data = default_data_dir() if data is None else Path(data)

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out.mkdir(parents=True, exist_ok=True)
    meta = run_metadata(jobs=jobs)
    write_text_atomic(out / "metadata.json", json.dumps(meta, indent=1) + "\n")
    print("run: " + ", ".join(f"{k_}={v}" for k_, v in meta.items() if k_ != "packages"))
    np.set_printoptions(precision=4)

    print("== Lattice properties (cell volume 1 m^3)")
    table = lattice_table(1.0, n_points=n_table, seed=seed)
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
    stats, ratios = fig4(out, plt, n, seed)
    print(format_table(stats, ["lattice", "set", "n_cells", "mean", "std", "p5", "p95",
                               "range90", "exact_min", "exact_max", "exact_range"]))
    print("\n  FCC / cubic (range90 = p95 - p5 of the sample; range = exact max - min):")
    print(format_table(ratios))

    print("\n== Real scans")
    scans = {}
    for ds, rel in DATASETS.items():
        pts = load_scan(data / rel)
        if pts is None:
            continue
        if quick and len(pts) > 20_000:
            pts = pts[np.random.default_rng(seed).choice(len(pts), 20_000, replace=False)]
        scans[ds] = pts
        print(f"  {ds}: {len(pts)} points from {rel}")
    if not scans:
        print("  no real scans available: skipping Fig. 5 and Table I")
        return 0
    print(f"\n== Table I (paper's protocol): each scan as recorded, no rotation, "
          f"cell volume {table1_volume:g} m^3")
    t1 = table1_protocol(out, scans, table1_volume)
    print(format_table(t1, list(TABLE1_HEADERS)))
    print("  rms_distance_error = sqrt(3 x mse_per_dim) (the paper's 'distance error' column);"
          " mean_distance_eq13 = mean |Q(x) - x|")

    print(f"\n== Fig. 5 (rotated protocol): {k} uniform random rotations, "
          "the same for every lattice; uniform random points as the reference")
    first = next(iter(scans.values()))
    lo, hi = first.min(axis=0), first.max(axis=0)
    scans[UNIFORM] = np.random.default_rng(seed).uniform(lo, hi, (len(first), 3))
    rows = rotation_experiment(out, scans, volumes, k, seed)
    fig5(out, plt, rows, scans, volumes)
    summ = rotation_summary(rows)
    write_csv(out / "fig5_summary.csv", summ)
    print("  medians over rotations; rel_* = % change vs cubic (negative = better)")
    print(format_table(summ, ["dataset", "cell_volume", "lattice", "rotations", "voxel_count",
                            "rel_voxel_count", "mse_per_dim", "rel_mse_per_dim",
                            "distortion", "rel_distortion"]))
    print(f"\nwrote {out}")
    return 0
