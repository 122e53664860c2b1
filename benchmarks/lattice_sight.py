"""Non-cubic lattices at cubic's cost per check: the sight walk per lattice against the cubic
integer walk, and A* + smoothing and Lazy Theta* per lattice against cubic-26 on real maps.

Usage::

    python benchmarks/lattice_sight.py                  # both tables (office, geb079)
    python benchmarks/lattice_sight.py --maps office    # one map
    python benchmarks/lattice_sight.py --maps DA1 Complex --segments 0   # Warframe maps
    python benchmarks/lattice_sight.py --segments 20000 --queries 32 --repeat 3
    python benchmarks/lattice_sight.py --segments 20000 --maps --by-length   # set-up vs cells
    python benchmarks/lattice_sight.py --smoke          # tiny sizes, seconds

Sight table: random centre-to-centre sight lines (2 to 40 cells long) in an empty box of
each lattice at unit cell volume, walked by the line-of-sight test every search and the
smoothing call apply (``planner.search.sight_many``: one compiled call per batch of lines);
thread CPU time per cell looked up, against the cubic lattice's (goal <= 1.5). Every lattice
runs the same number of lines, in batches of :data:`BATCH`; the lattices take turns batch by
batch, each batch keeping its fastest of ``--repeat`` rounds, and the ``ratio`` line pairs
the lattice's batches with cubic's.

Planning table: the same queries (world points, quantized on each lattice; kept when a
path exists on every lattice) on each lattice at the same cell volume and robot radius; per
query the CPU time (thread time) of ``search`` + ``shortcut`` (A* with smoothing, what
``planner plan --shortcut`` pays; the smoothing's part, ``sm s``, and its lookups,
``sm look``, also shown) and of a Lazy Theta* ``search``; per lattice the sum of
its queries' times over cubic's on the same queries (goals: BCC and MCC A* + smoothing
<= 0.8, Lazy Theta* <= 1.5 on every lattice), and a ``ratio`` line per lattice and method
(the per-query ratios against cubic's, ``benchmarks/harness.py``). A time ratio is the
product of two: the expansions (``exp``, set by the lattice's geometry on the map) and the
cost per expansion (``ns/exp``: the A* search's part alone, then Lazy Theta*'s), what the
engine's speed per check decides. Each query's time on each
lattice is its fastest of ``--repeat`` rounds, every lattice and method taking turns on one
query before the next (one process). First-call compilation happens before any timed run.
No assertion on time: it prints. The maps: bundled names, ``geb079`` (0.08 m cells, robot
radius 0.2 m) and the Warframe maps under ``DATA/warframe`` (cell edge 2 voxels, radius 1
voxel: the setting of the held-out A1 check the goals were set on).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import harness  # noqa: E402  (the sibling module)

from planner import search as S  # noqa: E402
from planner.lattice import NAMED_LATTICES, Lattice  # noqa: E402
from planner.world import World  # noqa: E402
from planner.world.build import build_world  # noqa: E402

BATCH = 2500  # sight lines per timed call: one call costs some 20-40 us, under 0.5 ns per cell
GOALS = {"astar": {"bcc": "<= 0.8", "mcc": "<= 0.8"}, "lazy": "<= 1.5"}


def geb079_path(data: Path) -> Path:
    return data / "octomap" / "geb079.bt"


def map_source(map_name: str, data: Path) -> tuple[Path | str, dict]:
    """The map's file (or bundled name) and its world options (cell volume, robot radius)."""
    if map_name == "geb079":
        return geb079_path(data), dict(cell_volume=0.08 ** 3, radius=0.2)
    wf = data / "warframe" / f"{map_name}.3dmap"
    if wf.is_file():
        return wf, dict(cell_volume=2.0 ** 3, radius=1.0)
    return map_name, {}


def each_map(maps, data: Path, table) -> None:
    """``table(name)`` for each map of ``maps`` that can be read; a line for each one
    whose file is missing."""
    for m in maps:
        src = map_source(m, data)[0]
        if isinstance(src, Path) and not src.is_file():
            print(f"\nskipped map: no {m} at {src}")
            continue
        table(m)


def empty_world(lat: Lattice) -> World:
    """An empty box of ``lat``, 120 m across around the origin: room for every sight line
    of :func:`sight_lines` at unit cell volume."""
    return World(lat, np.zeros((0, 3), np.int64), np.array([[-60.0] * 3, [60.0] * 3]))


def sight_lines(lat: Lattice, n: int, seed: int = 0,
                length: float | None = None) -> tuple[np.ndarray, np.ndarray]:
    """``n`` random centre-to-centre sight lines (in index space of ``lat``, around the
    box centre) of 2 to 40 cell spacings, or of ``length`` cell spacings each; their
    ends are rounded to cell centres."""
    rng = np.random.default_rng(seed)
    step = 2 * lat.packing_radius
    p = lat.quantize(rng.uniform(-5, 5, (n, 3)) * step)
    d = rng.normal(size=(n, 3))
    spans = rng.uniform(2, 40, n) if length is None else np.full(n, float(length))
    d *= (spans * step / np.linalg.norm(d, axis=1))[:, None]
    q = lat.quantize(lat.to_world(p) + d)
    return p, q


def sight_table(n: int, repeat: int) -> None:
    batch = min(BATCH, n)
    nb = max(1, n // batch)
    n = nb * batch
    print(f"\nsight walk per lattice: {n:,} random centre-to-centre lines of 2-40 cells, empty "
          f"box, unit cell volume; thread CPU ns per cell looked up (batches of {batch} lines, "
          f"one call each,\nthe lattices in turn, each batch its fastest of {repeat} rounds); "
          "ratio against the cubic integer walk (goal <= 1.5)")
    print(f"{'lattice':8s} {'cells/line':>10s} {'ns/cell':>8s} {'vs cubic':>8s}")
    # A search first, before the walks' kernel loads: the cubic walk's speed depends on
    # what the process loaded before it (7.2 ns per cell when the walks load first, 6.4
    # after a search, on the machine measured; the other walks do not change). Measured
    # after a search: the state inside a planning process, and the stronger baseline.
    S.search(World(Lattice.named("cubic", 1.0), np.zeros((0, 3), np.int64), [[0, 0, 0], [4] * 3]),
             np.zeros(3, np.int64), np.full(3, 3, np.int64))
    cases = {}
    for name in NAMED_LATTICES:
        lat = Lattice.named(name, 1.0)
        w = empty_world(lat)
        ps, qs = sight_lines(lat, n)
        S.sight_many(w, ps[:10], qs[:10])  # compile / load
        cases[name] = (w, ps.reshape(nb, batch, 3), qs.reshape(nb, batch, 3),
                       np.zeros(nb, np.int64), np.zeros(nb, np.int64))

    def side(name):
        w, ps, qs, cells, free = cases[name]

        def run(i):
            r, t = harness.cpu_result(lambda: S.sight_many(w, ps[i], qs[i]))
            cells[i], free[i] = r.lookups.sum(), r.free.sum()
            return t
        return run

    best = harness.interleaved({k: side(k) for k in cases}, range(nb), repeat)
    ns = {}
    for name, (_, _, _, cells, free) in cases.items():
        assert free.sum() == n  # an empty box: every line is in sight
        ns[name] = 1e9 * best[name] / cells
        tot = 1e9 * best[name].sum() / cells.sum()
        base = 1e9 * best["cubic"].sum() / cases["cubic"][3].sum()
        print(f"{name:8s} {cells.sum() / n:10.1f} {tot:8.1f} {tot / base:8.2f}")
        harness.record(f"sight/{name}", dict(lines=n, batch=batch,
                                             cells_per_line=cells.sum() / n,
                                             ns_per_cell=tot, vs_cubic=tot / base))
    for name in cases:
        if name != "cubic":
            print(harness.ratio_line(f"sight walk ns per cell {name}/cubic", ns[name],
                                     ns["cubic"], goal="<= 1.5",
                                     note=f"per batch of {batch} lines"))


def length_table(n: int, repeat: int, lengths=(2, 10, 20, 40)) -> None:
    """The sight walk's time per line split into a part per line (the set-up) and a part
    per cell looked up: per lattice, ``n`` random lines of each length in ``lengths``
    (cell spacings), thread CPU ns per line (one batch each, its fastest of ``repeat``),
    and a least-squares line through (cells per line, ns per line)."""
    print(f"\nsight walk by line length: {n:,} random lines of each length (cell spacings), "
          f"empty box, unit cell volume; thread CPU ns per line, fastest of {repeat}; the "
          "fit: ns per line = set-up + slope x cells")
    print(f"{'lattice':8s} " + " ".join(f"{'L' + str(k):>8s}" for k in lengths)
          + f" {'set-up':>8s} {'ns/cell':>8s}")
    for name in NAMED_LATTICES:
        lat = Lattice.named(name, 1.0)
        w = empty_world(lat)
        cells, ns = [], []
        for k in lengths:
            p, q = sight_lines(lat, n, seed=k, length=k)
            S.sight_many(w, p[:10], q[:10])  # compile / load
            best = np.inf
            for _ in range(repeat):
                r, t = harness.cpu_result(lambda w=w, p=p, q=q: S.sight_many(w, p, q))
                best = min(best, t)
            cells.append(r.lookups.mean())
            ns.append(1e9 * best / n)
        slope, setup = np.polyfit(cells, ns, 1)
        print(f"{name:8s} " + " ".join(f"{x:8.0f}" for x in ns)
              + f" {setup:8.0f} {slope:8.2f}")
        harness.record(f"sight_by_length/{name}", dict(ns_per_line=ns, cells_per_line=cells,
                                                       setup_ns=setup, ns_per_cell=slope))


def map_worlds(map_name: str, data: Path) -> dict[str, World]:
    """The map on every lattice."""
    src, kw = map_source(map_name, data)
    return {name: build_world(src, name, **kw) for name in NAMED_LATTICES}


def query_points(worlds: dict[str, World], n: int, seed: int = 0) -> np.ndarray:
    """``n`` start/goal pairs (n, 2, 3) m at least a quarter of the box diagonal apart,
    connected on every lattice (A* finds a path): drawn among the cubic world's cells of its
    largest 26-connected free component (random points of a scan's box are mostly in
    pockets no path reaches)."""
    from scipy import ndimage

    rng = np.random.default_rng(seed)
    w0 = worlds["cubic"]
    step = 2 * w0.lattice.packing_radius
    lo = np.ceil(w0.bounds[0] / step).astype(np.int64)
    hi = np.floor(w0.bounds[1] / step).astype(np.int64)
    axes = [np.arange(a, b + 1) for a, b in zip(lo, hi, strict=True)]
    cells = np.stack(np.meshgrid(*axes, indexing="ij"), -1).reshape(-1, 3)
    free = w0.is_free(cells).reshape([len(a) for a in axes])
    labels, _ = ndimage.label(free, structure=np.ones((3, 3, 3)))
    sizes = np.bincount(labels.ravel())
    sizes[0] = 0
    pool = cells[labels.ravel() == sizes.argmax()]
    span = np.linalg.norm(w0.bounds[1] - w0.bounds[0])
    out = []
    for _ in range(20_000):
        if len(out) == n:
            break
        pts = w0.lattice.to_world(pool[rng.integers(len(pool), size=2)])
        pts += rng.uniform(-0.5, 0.5, (2, 3)) * step
        if np.linalg.norm(pts[0] - pts[1]) < span / 4:
            continue
        if not all(w.is_free(w.lattice.quantize(pts)).all() for w in worlds.values()):
            continue
        if all(S.search(w, *w.lattice.quantize(pts)).found for w in worlds.values()):
            out.append(pts)
    return np.array(out)


def plan_table(map_name: str, n: int, repeat: int, data: Path) -> None:
    worlds = map_worlds(map_name, data)
    pts = query_points(worlds, n)
    cv = worlds["cubic"].lattice.cell_volume
    print(f"\n{map_name}: cell volume {cv:.3g} m^3, {len(pts)} queries solved on every lattice; "
          f"thread CPU s per lattice (sum over queries of each query's fastest of {repeat} "
          "rounds)")
    cases = {}
    for name, w in worlds.items():
        q = w.lattice.quantize(pts.reshape(-1, 3)).reshape(-1, 2, 3)
        S.search(w, q[0, 0], q[0, 1], method="lazy-theta")  # compile / load
        r = S.search(w, q[0, 0], q[0, 1])
        if r.found:
            S.shortcut(w, r.cells)
        cases[name] = (w, q, {})  # info: (query, method) -> (found, expansions)

    def astar_smooth(name):
        w, q, info = cases[name]

        def run(i):
            r, t = harness.cpu_result(lambda: S.search(w, q[i, 0], q[i, 1]))
            before, ts = w.cell_checks, 0.0
            if r.found:
                _, ts = harness.cpu_result(lambda: S.shortcut(w, r.cells))
            info[i, "astar"] = (r.found, r.expansions)
            info[i, "search"] = min(info.get((i, "search"), t), t)  # the search's part
            # the smoothing's part: its fastest round, and its lookups
            info[i, "smooth"] = (min(info.get((i, "smooth"), (ts,))[0], ts),
                                 w.cell_checks - before)
            return t + ts
        return run

    def lazy(name):
        w, q, info = cases[name]

        def run(i):
            r, t = harness.cpu_result(lambda: S.search(w, q[i, 0], q[i, 1],
                                                       method="lazy-theta"))
            info[i, "lazy"] = (r.found, r.expansions)
            return t
        return run

    sides = {}
    for name in cases:
        sides[name, "astar"] = astar_smooth(name)
        sides[name, "lazy"] = lazy(name)
    best = harness.interleaved(sides, range(len(pts)), repeat)
    print(f"{'lattice':8s} {'found':>5s} {'A*+sm s':>8s} {'vs cubic':>8s} {'med q':>6s} "
          f"{'A* exp':>9s} {'ns/exp':>6s} {'sm s':>6s} {'sm look':>7s} {'LT* s':>8s} "
          f"{'vs cubic':>8s} {'med q':>6s} {'LT* exp':>9s} {'ns/exp':>6s}")
    ba, bl = best["cubic", "astar"], best["cubic", "lazy"]
    for name, (_, q, info) in cases.items():
        a, lz = best[name, "astar"], best[name, "lazy"]
        found = sum(info[i, "astar"][0] and info[i, "lazy"][0] for i in range(len(q)))
        sm_s, sm_look = (sum(info[i, "smooth"][k] for i in range(len(q))) for k in (0, 1))
        a_exp = sum(info[i, "astar"][1] for i in range(len(q)))
        lz_exp = sum(info[i, "lazy"][1] for i in range(len(q)))
        search_s = sum(info[i, "search"] for i in range(len(q)))
        print(f"{name:8s} {found:5d} {a.sum():8.4f} {a.sum() / ba.sum():8.2f} "
              f"{np.median(a / ba):6.2f} {a_exp:9d} {1e9 * search_s / max(a_exp, 1):6.0f} "
              f"{sm_s:6.4f} {sm_look:7d} {lz.sum():8.3f} {lz.sum() / bl.sum():8.2f} "
              f"{np.median(lz / bl):6.2f} {lz_exp:9d} {1e9 * lz.sum() / max(lz_exp, 1):6.0f}")
        harness.record(f"plan/{map_name}/{name}", dict(
            cell_volume=cv, queries=len(q), found=found, astar_smooth_s=a.sum(),
            astar_smooth_vs_cubic=a.sum() / ba.sum(), astar_smooth_median=np.median(a / ba),
            astar_expansions=a_exp, astar_search_s=search_s,
            smooth_s=sm_s, smooth_lookups=sm_look, lazy_s=lz.sum(),
            lazy_vs_cubic=lz.sum() / bl.sum(), lazy_median=np.median(lz / bl),
            lazy_expansions=lz_exp))
    for name in cases:
        if name == "cubic":
            continue
        print(harness.ratio_line(f"A*+smoothing time {name}/cubic, {map_name}",
                                 best[name, "astar"], ba, goal=GOALS["astar"].get(name, ""),
                                 note="per query"))
        print(harness.ratio_line(f"Lazy Theta* time {name}/cubic, {map_name}",
                                 best[name, "lazy"], bl, goal=GOALS["lazy"], note="per query"))


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    harness.add_arguments(ap, repeat=3, data=True, json=True)
    ap.add_argument("--segments", type=int, default=20_000, help="sight lines per lattice")
    ap.add_argument("--maps", nargs="*", default=["office", "geb079"],
                    help="maps of the planning table (bundled names, geb079, or Warframe "
                         "names under DATA/warframe)")
    ap.add_argument("--queries", type=int, default=32,
                    help="queries per map (one long query can decide a sum over 8)")
    ap.add_argument("--by-length", action="store_true",
                    help="also the sight walk's time per line by line length, split into a "
                         "set-up per line and a cost per cell (2,500 lines per length)")
    a = ap.parse_args(argv)
    if a.smoke:
        a.segments, a.queries, a.repeat = 5000, 2, 1
        a.maps = [m for m in a.maps if not isinstance(map_source(m, a.data)[0], Path)]
    with harness.session("non-cubic lattices at cubic's cost per check: sight walk and "
                         "planning per lattice", smoke=a.smoke, json=a.json,
                         command=harness.command_line("lattice_sight.py", argv)):
        if a.segments:
            sight_table(a.segments, a.repeat)
        if a.by_length or a.smoke:  # (the smoke run keeps this path exercised)
            length_table(500 if a.smoke else 2500, max(a.repeat, 1))
        each_map(a.maps, a.data, lambda m: plan_table(m, a.queries, a.repeat, a.data))
    return 0


if __name__ == "__main__":
    sys.exit(main())
