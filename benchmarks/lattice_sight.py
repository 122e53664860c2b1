"""Non-cubic lattices at cubic's cost per check: the sight walk per lattice against the cubic
integer walk, and A* + smoothing and Lazy Theta* per lattice against cubic-26 on real maps.

Usage::

    python benchmarks/lattice_sight.py                  # both tables (office, geb079)
    python benchmarks/lattice_sight.py --maps office    # one map
    python benchmarks/lattice_sight.py --segments 20000 --queries 8 --repeat 3

Sight table: random centre-to-centre sight lines (2 to 40 cells long) in an empty box of
each lattice at unit cell volume, walked by the line-of-sight function every search and the
smoothing call (``planner.search._los.los``); time per cell looked up, against the cubic
lattice's (goal <= 1.5). Every lattice runs the same number of lines, in a compiled loop.

Planning table: the same queries (world points, quantized on each lattice; kept when a
path exists on every lattice) on each lattice at the same cell volume and robot radius; per
query the CPU time (thread time) of ``search`` + ``shortcut`` (A* with smoothing, what
``planner plan --shortcut`` pays) and of a Lazy Theta* ``search``; per lattice the sum of
its queries' times over cubic's on the same queries (goals: BCC and MCC A* + smoothing
<= 0.8, Lazy Theta* <= 1.5 on every lattice). Each query's time on each lattice is its
fastest of ``--repeat`` passes, the lattices in turn within each pass (one process).
First-call compilation happens before any timed run. No assertion on time: it prints.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np
from numba import njit

from planner import search as S
from planner.lattice import NAMED_LATTICES, Lattice
from planner.search._los import los, new_scratch
from planner.world import World
from planner.world.build import build_world

ROOT = Path(__file__).resolve().parents[1]
GEB079 = ROOT / ".." / "shared" / "data" / "octomap" / "geb079.bt"


# Compiled per run, not cached on disk: a cached kernel outside the package would keep the
# machine code of the package's walk it was compiled with.
@njit
def _walk_all(occ, walk, ps, qs, sc):  # pragma: no cover - compiled
    """Walk every sight line ps[i] -> qs[i]; returns (lines in sight, cells looked up)."""
    free = 0
    cells = 0
    for i in range(ps.shape[0]):
        ok, n = los(occ, walk, ps[i], qs[i], sc, np.int64(i + 1))
        free += ok
        cells += n
    return free, cells


def sight_lines(lat: Lattice, n: int, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """``n`` random centre-to-centre sight lines of 2 to 40 cells (in index space of
    ``lat``, around the box centre)."""
    rng = np.random.default_rng(seed)
    step = 2 * lat.packing_radius
    p = lat.quantize(rng.uniform(-5, 5, (n, 3)) * step)
    d = rng.normal(size=(n, 3))
    d *= (rng.uniform(2, 40, n) * step / np.linalg.norm(d, axis=1))[:, None]
    q = lat.quantize(lat.to_world(p) + d)
    return p, q


def sight_table(n: int, repeat: int) -> None:
    print(f"\nsight walk per lattice: {n:,} random centre-to-centre lines of 2-40 cells, empty "
          f"box, unit cell volume; CPU ns per cell looked up, fastest of {repeat} passes\n"
          "(the lattices in turn); ratio against the cubic integer walk (goal <= 1.5)")
    print(f"{'lattice':8s} {'cells/line':>10s} {'ns/cell':>8s} {'vs cubic':>8s}")
    cases = []
    for name in NAMED_LATTICES:
        lat = Lattice.named(name, 1.0)
        w = World(lat, np.zeros((0, 3), np.int64), np.array([[-60.0] * 3, [60.0] * 3]))
        chk = w.checker
        ps, qs = sight_lines(lat, n)
        sc = new_scratch(100.0, chk.walk)
        _walk_all(chk.occupancy, chk.walk, ps[:10], qs[:10], sc)  # compile / load
        cases.append((name, chk, ps, qs, sc, []))
    for _ in range(max(1, repeat)):
        for _, chk, ps, qs, sc, runs in cases:
            t = time.process_time()
            free, cells = _walk_all(chk.occupancy, chk.walk, ps, qs, sc)
            runs.append((time.process_time() - t, cells, free))
    base = None
    for name, _, ps, _, _, runs in cases:
        sec = min(r[0] for r in runs)
        cells = runs[0][1]
        assert runs[0][2] == len(ps)  # an empty box: every line is in sight
        ns = 1e9 * sec / cells
        base = ns if base is None else base
        print(f"{name:8s} {cells / len(ps):10.1f} {ns:8.1f} {ns / base:8.2f}")


def _worlds(map_name: str) -> tuple[dict[str, World], np.ndarray]:
    """The map on every lattice and random free query pairs (world points)."""
    if map_name == "geb079":
        src, kw = GEB079, dict(cell_volume=0.08 ** 3, radius=0.2)
    else:
        src, kw = map_name, {}
    worlds = {name: build_world(src, name, **kw) for name in NAMED_LATTICES}
    return worlds, kw


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


def _timed(fn) -> tuple[float, object]:
    t = time.thread_time()
    r = fn()
    return time.thread_time() - t, r


def plan_table(map_name: str, n: int, repeat: int) -> None:
    worlds, kw = _worlds(map_name)
    pts = query_points(worlds, n)
    cv = worlds["cubic"].lattice.cell_volume
    print(f"\n{map_name}: cell volume {cv:.3g} m^3, {len(pts)} queries solved on every lattice; "
          f"CPU s per lattice (sum over queries of each query's fastest of {repeat} passes)")
    cases = []
    for name, w in worlds.items():
        q = w.lattice.quantize(pts.reshape(-1, 3)).reshape(-1, 2, 3)
        S.search(w, q[0, 0], q[0, 1], method="lazy-theta")  # compile / load
        r = S.search(w, q[0, 0], q[0, 1])
        if r.found:
            S.shortcut(w, r.cells)
        cases.append((name, w, q, np.full((len(q), 2), np.inf), []))
    for _ in range(max(1, repeat)):
        for _, w, q, best, info in cases:
            info.clear()
            for i, (s, g) in enumerate(q):
                def astar_smooth(w=w, s=s, g=g):
                    r = S.search(w, s, g)
                    return r, (S.shortcut(w, r.cells) if r.found else r.cells)
                ta, (ra, sm) = _timed(astar_smooth)
                tl, rl = _timed(lambda w=w, s=s, g=g: S.search(w, s, g, method="lazy-theta"))
                best[i, 0] = min(best[i, 0], ta)
                best[i, 1] = min(best[i, 1], tl)
                info.append((ra.found, rl.found, ra.expansions, rl.expansions))
    print(f"{'lattice':8s} {'found':>5s} {'A*+sm s':>8s} {'vs cubic':>8s} {'med q':>6s} "
          f"{'A* exp':>9s} {'LT* s':>8s} {'vs cubic':>8s} {'med q':>6s} {'LT* exp':>9s}")
    base = cases[0][3]
    for name, _, _, best, info in cases:
        found = sum(a and b for a, b, _, _ in info)
        ra = best[:, 0].sum() / base[:, 0].sum()
        rl = best[:, 1].sum() / base[:, 1].sum()
        print(f"{name:8s} {found:5d} {best[:, 0].sum():8.3f} {ra:8.2f} "
              f"{np.median(best[:, 0] / base[:, 0]):6.2f} {sum(x[2] for x in info):9d} "
              f"{best[:, 1].sum():8.3f} {rl:8.2f} {np.median(best[:, 1] / base[:, 1]):6.2f} "
              f"{sum(x[3] for x in info):9d}")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--segments", type=int, default=20_000, help="sight lines per lattice")
    ap.add_argument("--maps", nargs="*", default=["office", "geb079"],
                    help="maps of the planning table (bundled names or geb079)")
    ap.add_argument("--queries", type=int, default=8, help="queries per map")
    ap.add_argument("--repeat", type=int, default=3, help="passes; each query its fastest")
    a = ap.parse_args(argv)
    if a.segments:
        sight_table(a.segments, a.repeat)
    for m in a.maps:
        if m == "geb079" and not GEB079.is_file():
            print(f"\nno geb079 at {GEB079}; skipped")
            continue
        plan_table(m, a.queries, a.repeat)
    return 0


if __name__ == "__main__":
    sys.exit(main())
