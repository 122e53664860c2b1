"""Occupied voxel list speed: build, inflation, exact inflation, membership, vs a Python set.

For each data set and named lattice it reports

* ``build s``: :meth:`OccupiedVoxelList.from_points` on the whole cloud (quantize + sort);
* ``cells``, ``B/cell``: occupied cells and bytes held per cell;
* ``inflate s``, ``inflated``: :meth:`OccupiedVoxelList.inflate` with radius
  ``--diameters`` cell diameters, where one *cell diameter* is ``cell_volume ** (1/3)``
  (the edge of a cube of the cell's volume; 0.24 m for geb079 at 0.08**3 and 3 diameters);
* ``exact s``, ``exact``, ``over``: :func:`exact_inflation` (tight set for the points) and
  the over-blocking ratio ``inflated / exact``;
* ``contains s``: ``contains`` of ``--queries`` random cells in the map's index box;
* ``py build s`` / ``py infl s`` and ratios: a set of index tuples built from the quantized
  points, inflated by adding every stencil offset in Python loops. Runs longer than
  ``--baseline-seconds`` are measured on a prefix of the cells and extrapolated linearly
  (marked ``~``).

A separate table times building from 10^6 uniform random points, and one times
:func:`exact_box_inflation` on the geb079 OctoMap leaves as solid boxes (``--box-radius``,
default 0.2 m, at the leaves' own resolution cubed): wall and CPU seconds (CPU time is less
disturbed by other processes on a shared machine), blocked cells, and for comparison the
exact inflation of the leaf centres as points. Compilation is excluded (a warm-up call per
lattice first; numba caches to disk).

A last table times the whole world build of geb079 at 0.08**3 m^3 cells, radius
``--box-radius``, unknown space blocked (:func:`planner.build_world`: load, exact box
inflation, unknown-space classification and inflation), wall and CPU seconds, best of
``--repeats``, after a warm-up build at the same cell volume. With ``--stages``, one more
build per lattice is split into its compiled stages (CPU seconds of each kernel, the rest
being numpy and Python between them); ``--edge`` sets the cell edge (default 0.08 m).

Times are this thread's CPU seconds (``benchmarks/harness.py``; the box table also gives
wall seconds); the stages are the CPU seconds of the package's public build steps in one
more build (:mod:`cProfile` with a CPU clock, inclusive times): the exact inflation of
obstacle boxes (:func:`planner.voxels.inflate.box_inflation_grid`) and points
(:func:`~planner.voxels.inflate.point_inflation_grid`), the unknown space's classification
and inflation (:func:`planner.voxels.unknown.unknown_box_grid`), the world's bit sets
(:meth:`planner.world.cells` ``block_marked`` and ``in_bounds_bits``), the rest being
numpy and Python between them (reading the map included).

Run: ``python benchmarks/voxels_speed.py [--lattices fcc bcc] [--baseline-seconds 60]``
(``--only-boxes`` / ``--only-world`` for one table alone;
``--only-world --stages --edge 0.02 --lattices fcc cubic`` for the stages at 2 cm;
``--smoke``: random points, and the world table on the bundled office map, seconds).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import harness  # noqa: E402  (the sibling module)

from planner.io import load_obstacles, load_points  # noqa: E402
from planner.lattice import NAMED_LATTICES, Lattice  # noqa: E402
from planner.voxels import (  # noqa: E402
    OccupiedVoxelList,
    exact_box_inflation,
    exact_inflation,
    inflation_stencil,
)

DATA = harness.DATA
RATIOS: list[str] = []  # ratio lines, printed at the end


def _datasets(data: Path) -> list[tuple[str, np.ndarray | None, float]]:
    """(label, points (N, 3) or None when absent, cell volume m^3)."""
    out = []
    geb = data / "octomap" / "geb079.bt"
    out.append(("geb079.bt", load_points(geb) if geb.exists() else None, 0.08**3))
    scans = [data / "pcl_room" / f"room_scan{i}.pcd" for i in (1, 2)]
    room = np.concatenate([load_points(p) for p in scans]) if all(
        p.exists() for p in scans) else None
    out.append(("room_scan1+2", room, 0.05**3))
    return out


def _timed(fn, *args, **kw):
    """``fn(*args, **kw)`` and its thread CPU seconds."""
    return harness.cpu_result(lambda: fn(*args, **kw))


def _warm_up(lat: Lattice) -> None:
    """Compile every kernel once (also fills numba's on-disk cache)."""
    pts = np.random.default_rng(0).uniform(0, 1, size=(50, 3))
    occ = OccupiedVoxelList.from_points(pts, lat)
    occ.inflate(0.3)
    exact_inflation(pts, lat, 0.3)
    occ.contains(occ.indices)


def _py_build(points: np.ndarray, lat: Lattice) -> tuple[set, float]:
    t0 = harness.cpu_clock()
    cells = {tuple(r) for r in lat.quantize(points).tolist()}
    return cells, harness.cpu_clock() - t0


def _py_inflate(cells: set, stencil: np.ndarray, cap: float) -> tuple[int | None, float, bool]:
    """Inflate a set of tuples in pure Python. Returns (cells or None, seconds, extrapolated)."""
    offs = [tuple(o) for o in stencil.tolist()]
    todo = list(cells)
    out: set = set()
    t0 = harness.cpu_clock()
    done = 0
    step = 2000
    while done < len(todo):
        for c in todo[done: done + step]:
            x, y, z = c
            for dx, dy, dz in offs:
                out.add((x + dx, y + dy, z + dz))
        done = min(done + step, len(todo))
        el = harness.cpu_clock() - t0
        if done < len(todo) and el / done * len(todo) > cap and el > 0.2 * cap:
            return None, el / done * len(todo), True
    return len(out), harness.cpu_clock() - t0, False


def _row(label: str, name: str, points: np.ndarray, vol: float, args) -> dict:
    lat = Lattice.named(name, vol)
    _warm_up(lat)
    occ, t_build = _timed(OccupiedVoxelList.from_points, points, lat)
    r = args.diameters * vol ** (1 / 3)
    inflated, t_infl = _timed(occ.inflate, r)
    exact, t_exact = _timed(exact_inflation, points, lat, r)
    rng = np.random.default_rng(1)
    w = inflated.indices
    q = rng.integers(w.min(0), w.max(0) + 1, size=(args.queries, 3))
    hits, t_cont = _timed(inflated.contains, q)
    row = {"data": label, "lattice": name, "points": len(points), "build": t_build,
           "cells": len(occ), "bpc": occ.nbytes / len(occ), "radius": r, "inflate": t_infl,
           "inflated": len(inflated), "exact_s": t_exact, "exact": len(exact),
           "over": len(inflated) / len(exact), "contains": t_cont,
           "hit_rate": float(hits.mean())}
    if args.baseline_seconds > 0:
        cells, t_pb = _py_build(points, lat)
        assert len(cells) == len(occ)
        n, t_pi, extrap = _py_inflate(cells, inflation_stencil(lat, r), args.baseline_seconds)
        assert n is None or n == len(inflated)
        row.update(py_build=t_pb, py_infl=t_pi, py_extrap=extrap)
        RATIOS.append(harness.single_ratio(f"Python set build / ours, {label} {name}", t_pb,
                                           t_build, note="CPU"))
        RATIOS.append(harness.single_ratio(
            f"Python set inflation / ours, {label} {name}", t_pi, t_infl,
            note="CPU" + (", Python side extrapolated from a prefix" if extrap else "")))
    return row


def _fmt(rows: list[dict], baseline: bool) -> str:
    head = ["data", "lattice", "build s", "cells", "B/cell", "radius m", "inflate s",
            "inflated", "exact s", "exact", "over", "contains s"]
    if baseline:
        head += ["py build s", "x", "py infl s", "x"]
    lines = [head]
    for r in rows:
        line = [r["data"], r["lattice"], f"{r['build']:.3f}", f"{r['cells']:,}",
                f"{r['bpc']:.0f}", f"{r['radius']:.3f}", f"{r['inflate']:.3f}",
                f"{r['inflated']:,}", f"{r['exact_s']:.3f}", f"{r['exact']:,}",
                f"{r['over']:.2f}", f"{r['contains']:.3f}"]
        if baseline:
            mark = "~" if r["py_extrap"] else ""
            line += [f"{r['py_build']:.3f}", f"{r['py_build'] / r['build']:.0f}",
                     f"{mark}{r['py_infl']:.1f}", f"{mark}{r['py_infl'] / r['inflate']:.0f}"]
        lines.append(line)
    widths = [max(len(x[i]) for x in lines) for i in range(len(head))]
    out = ["  ".join(x.rjust(w) for x, w in zip(line, widths, strict=True)) for line in lines]
    out.insert(1, "  ".join("-" * w for w in widths))
    return "\n".join(out)


def _random_build(names: list[str], n: int) -> str:
    pts = np.random.default_rng(2).uniform(0, 20, size=(n, 3))
    lines = [f"build from {n:,} uniform random points in a 20 m cube, cell volume 0.1**3:"]
    for name in names:
        lat = Lattice.named(name, 0.1**3)
        _warm_up(lat)
        occ, t = _timed(OccupiedVoxelList.from_points, pts, lat)
        lines.append(f"  {name:6s} {t:.3f} s  ({len(occ):,} cells)")
    return "\n".join(lines)


def _box_table(data: Path, names: list[str], radius: float) -> str:
    """exact_box_inflation of the geb079 leaves (solid boxes) per lattice."""
    geb = data / "octomap" / "geb079.bt"
    if not geb.exists():
        return f"geb079.bt: not found under {data}, box table skipped"
    obst = load_obstacles(geb)
    half = obst.box_sizes[:, None] / 2  # OctoMap leaves, pruned ones larger
    lo, hi = obst.boxes - half, obst.boxes + half
    vol = obst.resolution**3
    sizes = ", ".join(f"{n:,} of {s:g} m" for s, n in zip(
        *np.unique(obst.box_sizes, return_counts=True), strict=True))
    lines = [f"exact box inflation, geb079.bt: {len(lo):,} occupied leaves ({sizes}) as "
             f"boxes, radius {radius:g} m, cell volume {vol:.3g} m^3:",
             f"  {'lattice':7s} {'wall s':>7s} {'cpu s':>7s} {'cells':>11s}   "
             f"{'centres-as-points s':>19s} {'cells':>11s}"]
    for name in names:
        lat = Lattice.named(name, vol)
        exact_box_inflation(lo[:50], hi[:50], lat, radius)  # compile / load kernels
        exact_inflation(obst.boxes[:50], lat, radius)
        t0, c0 = time.perf_counter(), harness.cpu_clock()
        boxes = exact_box_inflation(lo, hi, lat, radius)
        wall, cpu = time.perf_counter() - t0, harness.cpu_clock() - c0
        pts, t_pts = _timed(exact_inflation, obst.boxes, lat, radius)  # centres only
        lines.append(f"  {name:7s} {wall:7.3f} {cpu:7.3f} {len(boxes):11,}   {t_pts:19.3f} "
                     f"{len(pts):11,}")
    return "\n".join(lines)


# The build's stages: (module file, function) of the package's public build steps, and a
# label; several functions may share a label. Timed inclusively by cProfile (CPU clock).
_STAGES = [
    ("planner/voxels/inflate.py", "box_inflation_grid", "obstacle boxes: exact inflation"),
    ("planner/voxels/inflate.py", "point_inflation_grid", "obstacle points: exact inflation"),
    ("planner/voxels/unknown.py", "unknown_box_grid", "unknown space: cells and inflation"),
    ("planner/world/cells.py", "block_marked", "world bits: from the grids"),
    ("planner/world/cells.py", "in_bounds_bits", "world bits: in bounds"),
]


def _stage_seconds(build) -> tuple[float, dict[str, float]]:
    """CPU seconds of ``build()`` and of each stage of :data:`_STAGES` in it (cProfile's
    inclusive time per function, with this process's CPU clock)."""
    import cProfile
    import pstats

    prof = cProfile.Profile(time.process_time)
    c0 = time.process_time()
    prof.runcall(build)
    total = time.process_time() - c0
    spent: dict[str, float] = {}
    stats = pstats.Stats(prof).stats  # (file, line, function) -> (cc, nc, tt, ct, callers)
    for (path, _line, func), (_cc, _nc, _tt, ct, _callers) in stats.items():
        for suffix, name, label in _STAGES:
            if func == name and path.replace("\\", "/").endswith(suffix):
                spent[label] = spent.get(label, 0.0) + ct
    return total, spent


def _world_table(data: Path, names: list[str], radius: float, repeats: int,
                 edge: float = 0.08, stages: bool = False, source=None) -> str:
    """:func:`planner.build_world` on geb079.bt at ``edge**3`` m^3 cells (0.08 m: the map's
    resolution cubed), radius ``radius``, unknown space blocked: load + quantize + exact
    inflation of the leaves + unknown-space classification and its inflation, per lattice
    (best of ``repeats``); with ``stages``, one more build split into its stages."""
    from planner import build_world

    geb = data / "octomap" / "geb079.bt" if source is None else source
    if source is None and not geb.exists():
        return f"geb079.bt: not found under {data}, world table skipped"
    vol = edge**3
    map_label = Path(str(geb)).name
    lines = [f"build_world({map_label}, cell volume {edge:g}**3 m^3, radius {radius:g} m, unknown "
             f"blocked), best of {repeats}, CPU:",
             f"  {'lattice':7s} {'wall s':>7s} {'cpu s':>7s} {'blocked':>11s} {'unknown':>11s}"]
    split = []
    cpu_by: dict[str, float] = {}
    for name in names:
        # Compile / load kernels and derive the lattice geometry at this scale first.
        build_world(geb, name, cell_volume=vol, radius=radius, bounds=[[0, 0, 0], [1, 1, 1]])
        best = (np.inf, np.inf)
        for _ in range(repeats):
            t0, c0 = time.perf_counter(), harness.cpu_clock()
            w = build_world(geb, name, cell_volume=vol, radius=radius)
            best = min(best, (time.perf_counter() - t0, harness.cpu_clock() - c0))
        lines.append(f"  {name:7s} {best[0]:7.3f} {best[1]:7.3f} {w.n_blocked:11,} "
                     f"{w.n_unknown:11,}")
        cpu_by[name] = best[1]
        del w
        if stages:
            split.append((name, *_stage_seconds(
                lambda n=name: build_world(geb, n, cell_volume=vol, radius=radius))))
    if split:
        labels = list(dict.fromkeys(label for _, _, label in _STAGES))
        lines += ["", "CPU seconds per stage of one more build ('rest': numpy and Python "
                  "between the kernels, reading the map included):",
                  f"  {'stage':36s}" + "".join(f" {n:>7s}" for n, _, _ in split)]
        for label in labels + ["rest", "total"]:
            row = []
            for _, total, spent in split:
                v = {"total": total, "rest": total - sum(spent.values())}.get(
                    label, spent.get(label, 0.0))
                row.append(f" {v:7.2f}")
            lines.append(f"  {label:36s}" + "".join(row))
    first = names[0]
    for name in names[1:]:
        RATIOS.append(harness.single_ratio(f"world build CPU {name} / {first}, {map_label}",
                                           cpu_by[name], cpu_by[first], note="best of "
                                           f"{repeats}"))
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--data", type=Path, default=DATA, help="shared data folder")
    p.add_argument("--lattices", nargs="+", default=list(NAMED_LATTICES))
    p.add_argument("--diameters", type=float, default=3.0,
                   help="inflation radius in cell diameters (cell_volume ** (1/3))")
    p.add_argument("--queries", type=int, default=10**6, help="random contains() queries")
    p.add_argument("--random-points", type=int, default=10**6)
    p.add_argument("--baseline-seconds", type=float, default=60.0,
                   help="cap per Python-set inflation before extrapolating (0: no baseline)")
    p.add_argument("--box-radius", type=float, default=0.2,
                   help="radius (m) of the geb079 exact box inflation table")
    p.add_argument("--only-boxes", action="store_true", help="only the box inflation table")
    p.add_argument("--only-world", action="store_true", help="only the geb079 world table")
    p.add_argument("--repeats", type=int, default=3, help="world builds per lattice (best)")
    p.add_argument("--edge", type=float, default=0.08, help="cell edge (m) of the world table")
    p.add_argument("--stages", action="store_true",
                   help="world table: CPU seconds per stage of one more build")
    harness.add_arguments(p, repeat=None)
    args = p.parse_args(argv)
    with harness.session("occupied voxel lists and world builds", smoke=args.smoke):
        code = _smoke(args) if args.smoke else _run(args)
        for line in RATIOS:
            print(line)
        return code


def _smoke(args) -> int:
    """Random points on two lattices, the world table (with stages) on the bundled office."""
    names = ["cubic", "bcc"]
    pts = np.random.default_rng(3).uniform(0, 5, size=(20_000, 3))
    args.queries, args.baseline_seconds = 10_000, 1.0
    rows = [_row("random", name, pts, 0.1**3, args) for name in names]
    print(_fmt(rows, True))
    print()
    print(_random_build(names, 10_000))
    print()
    print(_world_table(args.data, names, 0.2, 1, edge=0.2, stages=True, source="office"))
    return 0


def _run(args) -> int:
    if args.only_boxes:
        print(_box_table(args.data, args.lattices, args.box_radius))
        return 0
    if args.only_world:
        print(_world_table(args.data, args.lattices, args.box_radius, args.repeats, args.edge,
                           args.stages))
        return 0
    rows = []
    for label, pts, vol in _datasets(args.data):
        if pts is None:
            print(f"{label}: not found under {args.data}, skipped")
            continue
        print(f"{label}: {len(pts):,} points, cell volume {vol:.3g} m^3 "
              f"(cell diameter {vol ** (1 / 3):.3f} m)", flush=True)
        for name in args.lattices:
            rows.append(_row(label, name, pts, vol, args))
    if rows:
        print()
        print(_fmt(rows, args.baseline_seconds > 0))
        print("\nover = inflated / exact; ~ = Python baseline extrapolated from a prefix; "
              "x = baseline time / ours")
    print()
    print(_random_build(args.lattices, args.random_points))
    print()
    print(_box_table(args.data, args.lattices, args.box_radius))
    print()
    print(_world_table(args.data, args.lattices, args.box_radius, args.repeats))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
