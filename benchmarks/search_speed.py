"""Search engine speed: numba A* vs networkx A* (graph build included) vs plain Python A*.

Usage::

    python benchmarks/search_speed.py                 # sampled Warframe + geb079 table
    python benchmarks/search_speed.py --all-warframe  # all 30,000 Warframe queries, mismatches
    python benchmarks/search_speed.py --da1 1000      # time 1,000 DA1 queries

Cubic lattice, 26 neighbours, safe rule (= MovingAI no corner cutting). networkx and the
Python baseline run on a cropped world (the start/goal box padded by ``--pad`` cells) so
that their graphs stay small; the numba search runs on the same cropped world for the
ratio columns. No assertions on time anywhere: this prints figures.
"""

from __future__ import annotations

import argparse
import heapq
import math
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
from numba import njit

from planner import search as S
from planner.lattice import Lattice
from planner.world import World

ROOT = Path(__file__).resolve().parents[1]
WARFRAME = ROOT / ".." / "shared" / "data" / "warframe"
MAPS = ("Simple", "Complex", "DA1")
GEB079 = ROOT / ".." / "shared" / "data" / "octomap" / "geb079.bt"


def load_warframe(name: str) -> tuple[World, np.ndarray]:
    path = WARFRAME / f"{name}.3dmap"
    dims = np.loadtxt(path, max_rows=1, usecols=(1, 2, 3), dtype=np.int64)
    blocked = np.loadtxt(path, skiprows=1, dtype=np.int64, ndmin=2)
    scen = np.loadtxt(f"{path}.3dscen", skiprows=2, ndmin=2)
    return World(Lattice.named("cubic", 1.0), blocked, np.array([[0, 0, 0], dims - 1.0])), scen


def python_astar(world: World, s: np.ndarray, gl: np.ndarray, neighbors: str = "full"):
    """Plain Python heapq A* over the implicit graph, same moves / rule / heuristic.

    Returns (cost, expansions)."""
    moves, mcost, _, _, _, per_move = S.move_stencils(world.lattice, neighbors, False)
    hm = S.move_heuristic(world.lattice, neighbors).tolist()
    mv = [tuple(m) for m in moves.tolist()]
    need = [[tuple(c) for c in pm.tolist()] for pm in per_move]
    cost = mcost.tolist()
    blocked = set(map(tuple, world.blocked.tolist()))
    g_ = world.lattice.generator.tolist()
    lo, hi = (x.tolist() for x in world._tol_bounds())
    freec: dict = {}

    def free(c):
        f = freec.get(c)
        if f is None:
            x = [g_[r][0] * c[0] + g_[r][1] * c[1] + g_[r][2] * c[2] for r in range(3)]
            f = c not in blocked and all(lo[r] <= x[r] <= hi[r] for r in range(3))
            freec[c] = f
        return f

    goal = tuple(gl.tolist())

    def h(c):
        d = (goal[0] - c[0], goal[1] - c[1], goal[2] - c[2])
        return max(0.0, max(f[0] * d[0] + f[1] * d[1] + f[2] * d[2] for f in hm))

    start = tuple(s.tolist())
    gs = {start: 0.0}
    closed = set()
    heap = [(h(start), 0.0, start)]
    while heap:
        _, _, u = heapq.heappop(heap)
        if u in closed:
            continue
        if u == goal:
            return gs[u], len(closed) + 1
        closed.add(u)
        gu = gs[u]
        for m, d in enumerate(mv):
            if not all(free((u[0] + c[0], u[1] + c[1], u[2] + c[2])) for c in need[m]):
                continue
            v = (u[0] + d[0], u[1] + d[1], u[2] + d[2])
            gv = gu + cost[m]
            if gv < gs.get(v, math.inf):
                gs[v] = gv
                heapq.heappush(heap, (gv + h(v), -gv, v))
    return math.inf, len(closed)


def crop(world: World, s: np.ndarray, g: np.ndarray, pad: int) -> World:
    """Same world restricted to the start/goal box padded by ``pad`` cells."""
    lat = world.lattice
    cs, cg = lat.to_world(np.stack([s, g]))
    step = 2 * lat.packing_radius
    lo = np.maximum(np.minimum(cs, cg) - pad * step, world.bounds[0])
    hi = np.minimum(np.maximum(cs, cg) + pad * step, world.bounds[1])
    c = world.blocked_centres()
    keep = np.all((c >= lo - step) & (c <= hi + step), axis=1)
    return World(lat, world.blocked[keep], np.array([lo, hi], float))


def numba_batch(world: World, queries: np.ndarray) -> dict:
    """Run the numba A* over the queries; expansions/s over the kernel time."""
    exp = checks = 0
    ksec = 0.0
    bad = []
    t0 = time.perf_counter()
    for q in queries:
        r = S.search(world, q[:3].astype(np.int64), q[3:6].astype(np.int64))
        exp += r.expansions
        checks += r.cell_checks
        ksec += r.seconds
        if len(q) > 6 and (not r.found or abs(r.cost - q[6]) > 1e-6 * q[6]):
            bad.append((q[:6].astype(int).tolist(), q[6], r.cost))
    wall = time.perf_counter() - t0
    return dict(n=len(queries), exp=exp, checks=checks, ksec=ksec, wall=wall, bad=bad)


@njit(cache=True)
def _minimal_astar(free, d1, d2, s, gl, moves, mcost, g, pos, heap, hf):  # pragma: no cover
    """The smallest compiled A* we could write for cubic-26 with the safe rule: dense g /
    position arrays over the whole map (memory proportional to the box: the design the
    product avoids), octile heuristic, binary heap. A floor for the per-expansion cost on
    this machine, not a planner. Returns (expansions, cost)."""
    hn = 1
    heap[0] = s
    hf[0] = 0.0
    g[s] = 0.0
    pos[s] = 0
    exp = 0
    ga, gb, gc = gl // (d1 * d2), (gl // d2) % d1, gl % d2
    r3, r2 = math.sqrt(3.0), math.sqrt(2.0)
    d0 = free.shape[0] // (d1 * d2)
    while hn > 0:
        x = heap[0]
        if x == gl:
            return exp, g[x]
        hn -= 1
        if hn > 0:
            y, yf = heap[hn], hf[hn]
            i = 0
            while True:
                c = 2 * i + 1
                if c >= hn:
                    break
                if c + 1 < hn and hf[c + 1] < hf[c]:
                    c += 1
                if not hf[c] < yf:
                    break
                heap[i], hf[i] = heap[c], hf[c]
                pos[heap[i]] = i
                i = c
            heap[i], hf[i] = y, yf
            pos[y] = i
        pos[x] = -1
        exp += 1
        a, b, cc = x // (d1 * d2), (x // d2) % d1, x % d2
        for m in range(moves.shape[0]):
            a2, b2, c2 = a + moves[m, 0], b + moves[m, 1], cc + moves[m, 2]
            if a2 < 0 or b2 < 0 or c2 < 0 or a2 >= d0 or b2 >= d1 or c2 >= d2:
                continue
            t = (a2 * d1 + b2) * d2 + c2
            if free[t] == 0 or pos[t] == -1:
                continue
            ok = True
            for da in range(min(0, moves[m, 0]), max(0, moves[m, 0]) + 1):
                for db in range(min(0, moves[m, 1]), max(0, moves[m, 1]) + 1):
                    for dc in range(min(0, moves[m, 2]), max(0, moves[m, 2]) + 1):
                        if free[((a + da) * d1 + b + db) * d2 + cc + dc] == 0:
                            ok = False
            if not ok:
                continue
            gt = g[x] + mcost[m]
            if gt < g[t]:
                g[t] = gt
                x0, x1, x2 = abs(ga - a2), abs(gb - b2), abs(gc - c2)
                lo = min(x0, min(x1, x2))
                hi = max(x0, max(x1, x2))
                f = gt + (r3 - r2) * lo + (r2 - 1.0) * (x0 + x1 + x2 - lo - hi) + hi
                i = hn if pos[t] == -2 else pos[t]
                if pos[t] == -2:
                    hn += 1
                while i > 0:
                    p = (i - 1) >> 1
                    if not f < hf[p]:
                        break
                    heap[i], hf[i] = heap[p], hf[p]
                    pos[heap[i]] = i
                    i = p
                heap[i], hf[i] = t, f
                pos[t] = i
    return exp, np.inf


def minimal_batch(world: World, queries: np.ndarray) -> float:
    """Expansions/s of :func:`_minimal_astar` on the queries (array resets not timed)."""
    lo = np.round(world.bounds[0]).astype(np.int64)
    dims = np.round(world.bounds[1] - world.bounds[0]).astype(np.int64) + 1
    free = np.ones(int(dims.prod()), np.uint8)
    b = world.blocked - lo
    free[(b[:, 0] * dims[1] + b[:, 1]) * dims[2] + b[:, 2]] = 0
    n = free.shape[0]
    g, pos, heap, hf = np.empty(n), np.empty(n, np.int64), np.empty(n, np.int64), np.empty(n)
    mv = np.array([(i, j, k) for i in (-1, 0, 1) for j in (-1, 0, 1) for k in (-1, 0, 1)
                   if (i, j, k) != (0, 0, 0)], np.int64)
    mc = np.linalg.norm(mv, axis=1)

    def flat(p):
        p = p.astype(np.int64) - lo
        return (p[0] * dims[1] + p[1]) * dims[2] + p[2]

    exp, secs = 0, 0.0
    for k, q in enumerate(queries):
        g[:] = np.inf
        pos[:] = -2
        t = time.perf_counter()
        e, c = _minimal_astar(free, dims[1], dims[2], flat(q[:3]), flat(q[3:6]), mv, mc, g, pos,
                              heap, hf)
        if k:  # the first call may compile
            secs += time.perf_counter() - t
            exp += e
        if len(q) > 6:
            assert abs(c - q[6]) <= 1e-6 * q[6], (q, c)
    return exp / secs if secs else math.nan


def compare(world: World, queries: np.ndarray, pad: int, with_nx: bool = True) -> dict:
    """numba vs networkx (build included) vs Python A* on cropped worlds. Queries whose
    cropped box holds more cells than the networkx backend takes are skipped for all three
    (counted in ``skipped``)."""
    from planner.search.reference import NX_NODE_CAP

    tn = tx = tp = 0.0
    exp = skipped = 0
    for q in queries:
        s, g = q[:3].astype(np.int64), q[3:6].astype(np.int64)
        w = crop(world, s, g, pad)
        box = (w.bounds[1] - w.bounds[0]) / (2 * w.lattice.packing_radius) + 1
        if with_nx and float(np.prod(box)) > NX_NODE_CAP:
            skipped += 1
            continue
        S.search(w, s, g)  # build the cropped world's grid outside the timing
        t = time.perf_counter()
        a = S.search(w, s, g)
        tn += time.perf_counter() - t
        exp += a.expansions
        t = time.perf_counter()
        c, _ = python_astar(w, s, g)
        tp += time.perf_counter() - t
        assert c == a.cost or abs(c - a.cost) <= 1e-9 * max(1.0, c), (c, a.cost)
        if with_nx:
            t = time.perf_counter()
            b = S.search(w, s, g, backend="networkx")
            tx += time.perf_counter() - t
            assert b.cost == a.cost or abs(b.cost - a.cost) <= 1e-9 * max(1.0, a.cost), (
                b.cost, a.cost)
    return dict(numba=tn, nx=tx, py=tp, exp=exp, skipped=skipped)


def geb079(n_queries: int = 20, seed: int = 0) -> tuple[World, np.ndarray] | None:
    """The real OctoMap scan geb079.bt on the cubic lattice at its native 0.08 m, with
    random free start/goal cells at least 8 m apart (None when the data is absent)."""
    from planner.api import build_world

    if not GEB079.is_file():
        return None
    world = build_world(GEB079, "cubic", cell_volume=0.08**3)
    rng = np.random.default_rng(seed)
    lo = np.ceil(world.bounds[0] / 0.08).astype(np.int64)
    hi = np.floor(world.bounds[1] / 0.08).astype(np.int64)
    q = []
    while len(q) < n_queries:
        c = rng.integers(lo, hi + 1, size=(2, 3))
        if world.is_free(c).all() and np.linalg.norm(c[0] - c[1]) * 0.08 > 8.0:
            q.append(np.r_[c[0], c[1]])
    return world, np.array(q, float)


def cold_warm() -> tuple[float, float]:
    """First-call time in a fresh process (cache on disk) and the warm time after it."""
    code = (
        "import time, numpy as np\n"
        "t = time.perf_counter()\n"
        "from planner import search as S\nfrom planner.lattice import Lattice\n"
        "from planner.world import World\n"
        "w = World(Lattice.named('cubic', 1.0), np.array([[5, 5, 5]]), [[0, 0, 0], [20, 20, 20]])\n"
        "S.search(w, [1, 1, 1], [18, 18, 18])\n"
        "t1 = time.perf_counter()\n"
        "S.search(w, [1, 1, 1], [18, 17, 18])\n"
        "print(t1 - t, time.perf_counter() - t1)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, cwd=ROOT)
    cold, warm = map(float, out.stdout.split())
    return cold, warm


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--all-warframe", action="store_true", help="check all 30,000 queries")
    ap.add_argument("--sample", type=int, default=200, help="queries per map for the table")
    ap.add_argument("--compare", type=int, default=10, help="queries per map vs nx/Python")
    ap.add_argument("--pad", type=int, default=6, help="crop padding (cells) for nx/Python")
    ap.add_argument("--da1", type=int, default=1000, help="DA1 queries to time (0: skip)")
    ap.add_argument("--no-geb079", dest="geb079", action="store_false",
                    help="skip the geb079.bt OctoMap world")
    a = ap.parse_args(argv)
    if not WARFRAME.exists():
        print(f"no Warframe data at {WARFRAME}; skipping")
        return 0

    cold, warm = cold_warm()
    print("minimal exp/s: a dense-array compiled A* (benchmarks/search_speed.py "
          "_minimal_astar) on 50 of the same queries; ratio = ours / minimal")
    print(f"first call in a fresh process (import + cached-kernel load + tiny search): "
          f"{cold:.2f} s; second call {warm * 1e3:.2f} ms")

    print("\nnumba A*, cubic-26, safe rule (kernel time; per-query Python overhead excluded)")
    print(f"{'map':10s} {'queries':>7s} {'expansions':>11s} {'exp/s':>11s} {'checks/s':>12s} "
          f"{'wall s':>7s} {'mismatch':>8s} {'minimal exp/s':>13s} {'ratio':>6s}")
    total_bad = []
    for name in MAPS:
        world, scen = load_warframe(name)
        S.search(world, scen[0, :3].astype(np.int64), scen[0, 3:6].astype(np.int64))
        qs = scen if a.all_warframe else scen[:: max(1, len(scen) // a.sample)][: a.sample]
        r = numba_batch(world, qs)
        total_bad += [(name, *b) for b in r["bad"]]
        mini = minimal_batch(world, qs[:: max(1, len(qs) // 50)])
        print(f"{name:10s} {r['n']:7d} {r['exp']:11d} {r['exp'] / r['ksec']:11.3g} "
              f"{r['checks'] / r['ksec']:12.3g} {r['wall']:7.2f} {len(r['bad']):8d} "
              f"{mini:13.3g} {r['exp'] / r['ksec'] / mini:6.2f}")
    if a.all_warframe:
        print(f"all Warframe queries: {len(total_bad)} mismatches")
        for b in total_bad[:20]:
            print("  ", b)

    if a.da1:
        world, scen = load_warframe("DA1")
        S.search(world, scen[0, :3].astype(np.int64), scen[0, 3:6].astype(np.int64))
        r = numba_batch(world, scen[: a.da1])
        print(f"\n{a.da1} DA1 queries: {r['wall']:.2f} s wall ({r['ksec']:.2f} s in the kernel), "
              f"{len(r['bad'])} mismatches")

    print(f"\nratios on cropped worlds (start/goal box + {a.pad} cells; same graph for all)")
    print(f"{'case':10s} {'queries':>7s} {'numba s':>9s} {'networkx s':>10s} {'python s':>9s} "
          f"{'nx/numba':>9s} {'py/numba':>9s}")
    cases = [(name, *load_warframe(name)) for name in MAPS]
    geb = geb079() if a.geb079 else None
    if geb is not None:
        cases.append(("geb079", *geb))
    for name, world, scen in cases if a.compare else []:
        qs = scen[:: max(1, len(scen) // a.compare)][: a.compare]
        r = compare(world, qs, a.pad)
        done = len(qs) - r["skipped"]
        if not done:
            print(f"{name:10s} {0:7d}  (every cropped world exceeds the networkx cap)")
            continue
        print(f"{name:10s} {done:7d} {r['numba']:9.4f} {r['nx']:10.3f} {r['py']:9.3f} "
              f"{r['nx'] / r['numba']:9.0f} {r['py'] / r['numba']:9.0f}"
              + (f"  ({r['skipped']} skipped: crop over the networkx cap)"
                 if r["skipped"] else ""))

    if geb is not None:
        gw, gq = geb
        print(f"\ngeb079.bt full world (cubic 0.08 m, {gw.n_blocked} blocked cells, "
              f"{gw.storage} storage), numba A*, random free queries > 8 m apart")
        S.search(gw, gq[0, :3].astype(np.int64), gq[0, 3:6].astype(np.int64))
        r = numba_batch(gw, gq)
        print(f"{len(gq)} queries: {r['exp']} expansions, {r['exp'] / r['ksec']:.3g} exp/s, "
              f"{r['checks'] / r['ksec']:.3g} checks/s, {r['wall']:.2f} s wall")
    return 1 if total_bad else 0


if __name__ == "__main__":
    sys.exit(main())
