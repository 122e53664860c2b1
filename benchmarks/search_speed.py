"""Search engine speed: our A* vs a minimal C++ A* (the anchor), per lattice, Lazy Theta*
vs A*, weighted-theta vs both, DA1 throughput, and numba vs networkx vs plain Python A* on
cropped worlds.

Usage::

    python benchmarks/search_speed.py                 # every table, sampled queries
    python benchmarks/search_speed.py --all-warframe  # all 30,000 Warframe queries, mismatches
    python benchmarks/search_speed.py --da1 1000      # time 1,000 DA1 queries
    python benchmarks/search_speed.py --smoke         # tiny sizes, well under a minute

The per-lattice tables (sight walk per cell against the cubic integer walk, A* + smoothing
and Lazy Theta* per lattice against cubic on the office map, geb079 and the Warframe maps
DA1 and Complex at 2-voxel cells) are ``benchmarks/lattice_sight.py``'s, printed here too
(``--no-lattice-sight`` skips them).

Ours against the C++ floor is ``benchmarks/cpp_anchor.py``'s table (compiled at run time
with the system compiler, called in this process; skipped with a line when there is none).
Timing (``benchmarks/harness.py``): this thread's CPU time around each call, the sides of a
comparison taking turns query by query, each query its fastest of ``--repeat`` rounds; each
comparison prints a ``ratio`` line (median of the per-query ratios with its 95% interval).
Every ratio is measured in one run on the same queries (the machine may be shared: trust
ratios, not absolute times). Tables whose data is absent under ``--data`` are skipped with
a line.

Cubic lattice, 26 neighbours, safe rule (= MovingAI no corner cutting). networkx and the
Python baseline run on a cropped world (the start/goal box padded by ``--pad`` cells) so
that their graphs stay small; the numba search runs on the same cropped world for the
ratio columns. No assertions on time anywhere: this prints figures.
"""

from __future__ import annotations

import argparse
import heapq
import json
import math
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import harness  # noqa: E402  (the sibling module)

from planner import search as S  # noqa: E402
from planner.lattice import Lattice  # noqa: E402
from planner.search.run import H_WEIGHT as WEIGHT  # noqa: E402
from planner.world import World  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
MAPS = ("Simple", "Complex", "DA1")


def load_warframe(name: str, data: Path = harness.DATA) -> tuple[World, np.ndarray]:
    path = data / "warframe" / f"{name}.3dmap"
    dims = np.loadtxt(path, max_rows=1, usecols=(1, 2, 3), dtype=np.int64)
    blocked = np.loadtxt(path, skiprows=1, dtype=np.int64, ndmin=2)
    scen = np.loadtxt(f"{path}.3dscen", skiprows=2, ndmin=2)
    return World(Lattice.named("cubic", 1.0), blocked, np.array([[0, 0, 0], dims - 1.0])), scen


#: tie-breaks among equal f of :func:`python_astar`: the engine's, and the node nearest the
#: goal in a straight line first (the squared Euclidean distance)
TIES = ("larger-g", "nearer")


def python_astar(world: World, s: np.ndarray, gl: np.ndarray, neighbors: str = "full",
                 trace: list | None = None, tie: str = "larger-g"):
    """Plain Python heapq A* over the implicit graph, same moves / rule / heuristic, f grid
    (1e-9 of the shortest move) and tie-break (``tie``, one of :data:`TIES`; by default the
    engine's, the larger g first) as the engine.

    Returns (cost, expansions); ``trace`` gets ``(f, g)`` (m) of each expansion in order."""
    if tie not in TIES:
        raise ValueError(f"tie must be one of {TIES}, not {tie!r}")
    moves, mcost, _, _, _, per_move = S.move_stencils(world.lattice, neighbors, False)
    step = 1e-9 * float(mcost.min())  # the engine's f grid for lattice A*
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

    def second(gv, v):  # the heap's key after f (smaller first)
        if tie == "larger-g":
            return -gv
        d = [goal[0] - v[0], goal[1] - v[1], goal[2] - v[2]]
        return sum((g_[r][0] * d[0] + g_[r][1] * d[1] + g_[r][2] * d[2]) ** 2
                   for r in range(3))

    def h(c):
        d = (goal[0] - c[0], goal[1] - c[1], goal[2] - c[2])
        return max(0.0, max(f[0] * d[0] + f[1] * d[1] + f[2] * d[2] for f in hm))

    def key(f):
        return math.floor(f / step + 0.5) * step

    start = tuple(s.tolist())
    gs = {start: 0.0}
    closed = set()
    heap = [(key(h(start)), 0.0, start)]
    while heap:
        f, _, u = heapq.heappop(heap)
        if u in closed:
            continue
        if trace is not None:
            trace.append((f, gs[u]))
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
                heapq.heappush(heap, (key(gv + h(v)), second(gv, v), v))
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
    costs = np.empty(len(queries))
    secs = np.empty(len(queries))
    exps = np.empty(len(queries), np.int64)
    t0 = time.perf_counter()
    for i, q in enumerate(queries):
        r = S.search(world, q[:3].astype(np.int64), q[3:6].astype(np.int64))
        costs[i] = r.cost
        secs[i] = r.seconds
        exps[i] = r.expansions
        exp += r.expansions
        checks += r.cell_checks
        ksec += r.seconds
        if len(q) > 6 and (not r.found or abs(r.cost - q[6]) > 1e-6 * q[6]):
            bad.append((q[:6].astype(int).tolist(), q[6], r.cost))
    wall = time.perf_counter() - t0
    return dict(n=len(queries), exp=exp, checks=checks, ksec=ksec, wall=wall, bad=bad,
                costs=costs, secs=secs, exps=exps)


def compare(world: World, queries: np.ndarray, pad: int, with_nx: bool = True) -> dict:
    """numba vs networkx (build included) vs Python A* on cropped worlds (thread CPU
    seconds, one run each: the slow sides take seconds per query). Queries whose
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
        a, t = harness.cpu_result(lambda w=w, s=s, g=g: S.search(w, s, g))
        tn += t
        exp += a.expansions
        (c, _), t = harness.cpu_result(lambda w=w, s=s, g=g: python_astar(w, s, g))
        tp += t
        assert c == a.cost or abs(c - a.cost) <= 1e-9 * max(1.0, c), (c, a.cost)
        if with_nx:
            b, t = harness.cpu_result(lambda w=w, s=s, g=g: S.search(w, s, g,
                                                                     backend="networkx"))
            tx += t
            assert b.cost == a.cost or abs(b.cost - a.cost) <= 1e-9 * max(1.0, a.cost), (
                b.cost, a.cost)
    return dict(numba=tn, nx=tx, py=tp, exp=exp, skipped=skipped)


def geb079(n_queries: int = 20, seed: int = 0, lattice: str = "cubic",
           data: Path = harness.DATA) -> tuple[World, np.ndarray] | None:
    """The real OctoMap scan geb079.bt on the cubic lattice at its native 0.08 m, with
    random free start/goal cells at least 10 m apart (None when the data is absent)."""
    from planner.world.build import build_world

    path = data / "octomap" / "geb079.bt"
    if not path.is_file():
        return None
    world = build_world(path, lattice, cell_volume=0.08**3, radius=0.0)
    rng = np.random.default_rng(seed)
    lo = np.ceil(world.bounds[0] / 0.08).astype(np.int64)
    hi = np.floor(world.bounds[1] / 0.08).astype(np.int64)
    q = []
    while len(q) < n_queries:
        c = rng.integers(lo, hi + 1, size=(2, 3))
        if world.is_free(c).all() and np.linalg.norm(c[0] - c[1]) * 0.08 >= 10.0:
            q.append(np.r_[c[0], c[1]])
    return world, np.array(q, float)


def warframe_cases(names, data: Path) -> list[tuple[str, World, np.ndarray]]:
    """The named Warframe maps present under ``data`` (a line for each one absent)."""
    out = []
    for name in names:
        if (data / "warframe" / f"{name}.3dmap").is_file():
            out.append((name, *load_warframe(name, data)))
        else:
            print(f"{name}: not under {data / 'warframe'}, skipped")
    return out


def lattice_table(geb: tuple[World, np.ndarray], repeat: int = 3,
                  data: Path = harness.DATA) -> None:
    """A* per-expansion cost on each lattice relative to cubic: geb079 at the same cell
    volume (0.08 m^3), the cubic queries' centres quantized on each lattice (a query whose
    ends are blocked on a lattice is left out there). Thread CPU time per ``search`` call,
    the lattices taking turns query by query, each query its fastest of ``repeat``
    rounds."""
    from planner.lattice import NAMED_LATTICES

    gw, gq = geb
    pts = gw.lattice.to_world(gq[:, :6].reshape(-1, 3).astype(np.int64)).reshape(-1, 2, 3)
    print("\nA* per expansion by lattice, geb079 (cell volume 0.08^3 m^3, full neighbours, "
          "safe rule); ratio = ns per expansion / cubic's (goal <= 1.3);\n"
          f"thread CPU time per query, the lattices taking turns query by query, each its "
          f"fastest of {max(1, repeat)} rounds")
    print(f"{'lattice':8s} {'queries':>7s} {'expansions':>11s} {'ns/exp':>8s} {'vs cubic':>8s}")
    cases = {}
    for name in NAMED_LATTICES:
        w = gw if name == "cubic" else geb079(0, lattice=name, data=data)[0]
        q = w.lattice.quantize(pts.reshape(-1, 3)).reshape(-1, 6)
        ok = w.is_free(q[:, :3]) & w.is_free(q[:, 3:])
        i0 = int(np.flatnonzero(ok)[0])
        S.search(w, q[i0, :3], q[i0, 3:])  # compile / load outside the clock
        cases[name] = (w, q, ok, np.zeros(len(q), np.int64))

    def side(name):
        w, q, ok, exps = cases[name]

        def run(i):
            if not ok[i]:
                return math.inf
            r, t = harness.cpu_result(lambda: S.search(w, q[i, :3], q[i, 3:]))
            exps[i] = r.expansions
            return t
        return run

    best = harness.interleaved({k: side(k) for k in cases}, range(len(pts)), repeat)
    per = {}
    ns = {}
    for name, (_, _, ok, exps) in cases.items():
        exp = int(exps[ok].sum())
        ns[name] = 1e9 * best[name][ok].sum() / exp
        per[name] = np.where(ok, best[name] / np.maximum(exps, 1), math.inf)
        print(f"{name:8s} {int(ok.sum()):7d} {exp:11d} {ns[name]:8.0f} "
              f"{ns[name] / ns['cubic']:8.2f}")
        harness.record(f"lattice_expansion/{name}", dict(
            queries=int(ok.sum()), expansions=exp, ns_per_expansion=ns[name],
            vs_cubic=ns[name] / ns["cubic"]))
    for name in cases:
        if name != "cubic":
            print(harness.ratio_line(f"A* ns per expansion {name}/cubic, geb079", per[name],
                                     per["cubic"], goal="<= 1.3", overall=ns[name] / ns["cubic"],
                                     note="per query"))


def _method_sides(world: World, qs: np.ndarray, methods) -> tuple[dict, dict, dict]:
    """One side per search method over the queries ``qs`` (Q, >= 6): each returns the
    thread CPU seconds of one ``search`` call and records the result's expansions and
    cost."""
    exps = {m: np.zeros(len(qs), np.int64) for m in methods}
    costs = {m: np.full(len(qs), math.inf) for m in methods}

    def side(m):
        def run(i):
            s, g = qs[i, :3].astype(np.int64), qs[i, 3:6].astype(np.int64)
            r, t = harness.cpu_result(lambda: S.search(world, s, g, method=m))
            exps[m][i], costs[m][i] = r.expansions, r.cost
            return t
        return run

    return {m: side(m) for m in methods}, exps, costs


def anyangle_table(cases: list, n: int, save: Path | None = None,
                   check: Path | None = None, repeat: int = 3) -> None:
    """Lazy Theta* vs A* on the same queries: median per-query time ratio (goal <= 2), and
    the median per-query expansion ratio beside it (most of the time ratio: where an obstacle
    makes the path longer than the straight line by a little, Lazy Theta* must expand every
    cell whose g + |x - goal| is below the path length, a thin tube along the whole line; A*'s
    move-set gauge is flat along the many equal-cost lattice paths, so it dives).

    ``cases``: (name, world, queries (Q, >= 6)) per world. ``save`` writes each query's Lazy
    Theta* path length (JSON, per world); ``check`` compares this run's lengths with such a
    file (a run of another version): the largest relative difference and the queries
    differing by more than 0.1% (goal: none). Thread CPU time per call, the two methods
    taking turns query by query, each query its fastest of ``repeat`` rounds."""
    print(f"\nLazy Theta* vs A* (cubic-26, same queries; thread CPU time, fastest of {repeat} "
          f"alternating runs per query); up to {n} per world")
    head = (f"{'world':10s} {'queries':>7s} {'A* med ms':>9s} {'LT* med ms':>10s} "
            f"{'med ratio':>9s} {'LT*/A* exp':>10s} {'med exp':>7s} {'LT* length m':>12s}")
    ref = json.loads(check.read_text()) if check is not None else None
    print(head + (f" {'max dlen':>9s} {'>0.1%':>5s}" if ref is not None else ""))
    lengths = {}
    ratios = []
    for name, world, scen in cases:
        qs = scen[:: max(1, len(scen) // n)][:n]
        S.search(world, qs[0, :3].astype(np.int64), qs[0, 3:6].astype(np.int64),
                 method="lazy-theta")
        sides, exps, costs = _method_sides(world, qs, ("astar", "lazy-theta"))
        best = harness.interleaved(sides, range(len(qs)), repeat)
        ta, tl = best["astar"], best["lazy-theta"]
        ea, el = exps["astar"], exps["lazy-theta"]
        ll = costs["lazy-theta"].tolist()
        lengths[name] = ll
        row = (f"{name:10s} {len(qs):7d} {1e3 * np.median(ta):9.2f} "
               f"{1e3 * np.median(tl):10.2f} {np.median(tl / ta):9.2f} "
               f"{el.sum() / ea.sum():10.2f} {np.median(el / ea):7.2f} {sum(ll):12.4f}")
        if ref is not None and name in ref and len(ref[name]) == len(ll):
            old, new = np.array(ref[name]), np.array(ll)
            rel = np.abs(new - old) / np.maximum(old, 1e-12)
            rel[~np.isfinite(old) & ~np.isfinite(new)] = 0.0
            row += f" {rel.max():9.2e} {int((rel > 1e-3).sum()):5d}"
        print(row)
        harness.record(f"anyangle/{name}", dict(
            queries=len(qs), astar_median_ms=1e3 * np.median(ta),
            lazy_median_ms=1e3 * np.median(tl), median_ratio=np.median(tl / ta),
            expansion_ratio=el.sum() / ea.sum(), median_expansion_ratio=np.median(el / ea),
            lazy_length_m=sum(ll)))
        ratios.append(harness.ratio_line(f"Lazy Theta*/A* time, {name}", tl, ta,
                                         goal="<= 2", note="per query"))
    for line in ratios:
        print(line)
    if save is not None:
        save.write_text(json.dumps(lengths))


def weighted_table(cases: list, n: int, repeat: int = 3) -> None:
    """Any-angle at A*'s cost (issue goal: <= 2x A*): per world (``cases``: DA1, geb079 at
    0.08 m), the median per-query time ratio of Lazy Theta* / A* and of weighted-theta /
    A*, and the per-query length ratio weighted-theta / Lazy Theta* (goal: within 0.5% on
    every query): its largest, median and the share within 0.5%. Thread CPU time per call,
    the three methods taking turns query by query, each query its fastest of ``repeat``
    rounds."""
    print(f"\nweighted-theta (Lazy Theta*, heuristic x{WEIGHT}) vs Lazy Theta* vs A* "
          f"(cubic-26, same queries, fastest of {repeat} alternating runs); up to {n} per "
          "world\ntime goal <= 2 (median of per-query ratios); length goal: "
          "weighted / LT* <= 1.005 on every query")
    print(f"{'world':8s} {'queries':>7s} {'LT*/A*':>7s} {'W/A*':>6s} {'W/A* exp':>8s} "
          f"{'len max':>8s} {'len med':>8s} {'<=0.5%':>6s}")
    methods = ("astar", "lazy-theta", "weighted-theta")
    ratios = []
    for name, world, scen in cases:
        qs = scen[:: max(1, len(scen) // n)][:n]
        for m in methods:  # compile / load every kernel outside the timed runs
            S.search(world, qs[0, :3].astype(np.int64), qs[0, 3:6].astype(np.int64), method=m)
        sides, exps, costs = _method_sides(world, qs, methods)
        best = harness.interleaved(sides, range(len(qs)), repeat)
        found = np.isfinite(costs["astar"])  # no path: nothing to compare
        ta, tl, tw = (best[m][found] for m in methods)
        ew = exps["weighted-theta"][found] / exps["astar"][found]
        ln = costs["weighted-theta"][found] / costs["lazy-theta"][found]
        print(f"{name:8s} {len(ln):7d} {np.median(tl / ta):7.2f} {np.median(tw / ta):6.2f} "
              f"{np.median(ew):8.2f} {ln.max():8.4f} {np.median(ln):8.4f} "
              f"{np.mean(ln <= 1.005):6.0%}")
        harness.record(f"weighted/{name}", dict(
            queries=len(ln), lazy_over_astar=np.median(tl / ta),
            weighted_over_astar=np.median(tw / ta), weighted_expansions_over_astar=np.median(ew),
            length_max=ln.max(), length_median=np.median(ln),
            within_half_percent=int((ln <= 1.005).sum())))
        ratios += [harness.ratio_line(f"weighted-theta/A* time, {name}", tw, ta, goal="<= 2",
                                      note="per query"),
                   harness.ratio_line(f"weighted-theta/Lazy Theta* time, {name}", tw, tl,
                                      note="per query"),
                   harness.ratio_line(f"weighted-theta/Lazy Theta* length, {name}",
                                      costs["weighted-theta"][found],
                                      costs["lazy-theta"][found],
                                      goal="<= 1.005 on every query", note="per query")]
    for line in ratios:
        print(line)


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
    harness.add_arguments(ap, repeat=3, data=True, json=True)
    ap.add_argument("--all-warframe", action="store_true",
                    help="check all 10,000 queries of each Warframe map")
    ap.add_argument("--maps", nargs="+", choices=MAPS, default=list(MAPS),
                    help="Warframe maps of the floor table (default: all three)")
    ap.add_argument("--sample", type=int, default=200, help="queries per map for the table")
    ap.add_argument("--compare", type=int, default=10, help="queries per map vs nx/Python")
    ap.add_argument("--pad", type=int, default=6, help="crop padding (cells) for nx/Python")
    ap.add_argument("--da1", type=int, default=1000, help="DA1 queries to time (0: skip)")
    ap.add_argument("--workers", type=int, default=2,
                    help="threads for the DA1 search_many line (besides 1)")
    ap.add_argument("--no-geb079", dest="geb079", action="store_false",
                    help="skip the geb079.bt OctoMap world")
    ap.add_argument("--geb-queries", type=int, default=20, help="geb079 queries (>= 10 m)")
    ap.add_argument("--no-lattices", dest="lattices", action="store_false",
                    help="skip the per-lattice cost table on geb079")
    ap.add_argument("--no-anchor", dest="anchor", action="store_false",
                    help="skip the A* vs C++ floor table")
    ap.add_argument("--anyangle", type=int, default=20,
                    help="queries per world for Lazy Theta* and weighted-theta vs A* (0: skip)")
    ap.add_argument("--no-lattice-sight", dest="lattice_sight", action="store_false",
                    help="skip the per-lattice sight walk and planning tables "
                         "(benchmarks/lattice_sight.py)")
    ap.add_argument("--plan-queries", type=int, default=32,
                    help="queries per map of the per-lattice planning table (one long query "
                         "can decide a sum over 8)")
    ap.add_argument("--save-lengths", type=Path, metavar="JSON",
                    help="write each query's Lazy Theta* path length here")
    ap.add_argument("--check-lengths", type=Path, metavar="JSON",
                    help="compare Lazy Theta* path lengths with a --save-lengths file")
    a = ap.parse_args(argv)
    segments, plan_queries = 20_000, a.plan_queries
    plan_maps = ["office", "geb079", "DA1", "Complex"]
    if a.smoke:  # tiny sizes; geb079 (five lattice builds) left out
        a.sample, a.compare, a.da1, a.anyangle, a.repeat = 4, 1, 20, 3, 1
        a.maps, a.geb079, a.all_warframe = ["Simple"], False, False
        segments, plan_maps, plan_queries = 5000, ["office"], 2
    if not a.geb079:
        plan_maps = [m for m in plan_maps if m != "geb079"]
    files = {"geb079": a.data / "octomap" / "geb079.bt"}
    plan_maps = [m for m in plan_maps  # the maps present (office is bundled)
                 if m == "office" or files.get(m, a.data / "warframe" / f"{m}.3dmap").is_file()]
    with harness.session("search engine speed: ours vs the C++ floor, per lattice, "
                         "any-angle vs A*", smoke=a.smoke, json=a.json,
                         command=harness.command_line("search_speed.py", argv)):
        return _run(a, segments, plan_maps, plan_queries)


def _run(a: argparse.Namespace, segments: int, plan_maps: list[str], plan_queries: int
         ) -> int:
    import cpp_anchor  # the sibling scripts
    import fixed_cost
    import lattice_sight

    cold, warm = cold_warm()
    print(f"first call in a fresh process (import + cached-kernel load + tiny search): "
          f"{cold:.2f} s; second call {warm * 1e3:.2f} ms")
    harness.record("first_call", dict(cold_s=cold, warm_ms=warm * 1e3))
    print(fixed_cost.line(300 if a.smoke else 3000))

    print("\nA*, cubic-26, safe rule (= MovingAI no corner cutting), ours vs the strongest "
          "C++ floor (benchmarks/cpp_anchor.py, in process) on the same queries;\nthread CPU "
          f"time per query, the two sides taking turns, each query its fastest of {a.repeat} "
          "rounds")
    total_bad = 0
    if not a.anchor:
        print("skipped table: --no-anchor")
    elif not cpp_anchor.available():
        print("skipped table: no C++ compiler (g++ / c++) on PATH: the C++ floor")
    else:
        names = list(a.maps) + (["geb079"] if a.geb079 else [])
        rows = cpp_anchor.floor_rows(a.data, names, None if a.all_warframe else a.sample,
                                     a.geb_queries, a.repeat)
        if rows:
            cpp_anchor.print_rows(rows)
            total_bad = sum(r.mismatches for r in rows)
            harness.record("floor_checked", dict(
                mismatches=total_bad, all_warframe=a.all_warframe,
                queries_per_warframe_map=10_000 if a.all_warframe else a.sample,
                geb079_queries=a.geb_queries if a.geb079 else 0, repeat=a.repeat))
            print(f"optimal costs: {total_bad} mismatches (ours vs the floor vs the listed "
                  "Warframe optimum)"
                  + (f" (all {10_000 * len(a.maps):,} Warframe queries)" if a.all_warframe
                     else f" ({a.sample} per Warframe map)"))
        else:
            print(f"skipped table: none of the maps under {a.data}")

    geb = geb079(a.geb_queries, data=a.data) if a.geb079 else None
    if a.geb079 and geb is None:
        print(f"\nno geb079 under {a.data / 'octomap'}: its tables are skipped")
    if geb is not None and a.lattices:
        lattice_table(geb, a.repeat, a.data)
    wf = warframe_cases(MAPS, a.data) if (a.anyangle or a.compare) else []
    if a.anyangle:
        cases = wf + ([("geb079", *geb)] if geb is not None else [])
        if cases:
            anyangle_table(cases, a.anyangle, a.save_lengths, a.check_lengths, a.repeat)
            weighted_table([c for c in cases if c[0] in ("DA1", "geb079")] or cases[:1],
                           a.anyangle, a.repeat)
        else:
            print("\nskipped table: any-angle vs A* (no Warframe map, no geb079)")

    if a.lattice_sight:  # the sibling script's tables: sight walk per cell, planning
        lattice_sight.sight_table(segments, a.repeat)
        for m in plan_maps:
            lattice_sight.plan_table(m, plan_queries, a.repeat, a.data)

    da1 = [c for c in wf if c[0] == "DA1"]
    if a.da1 and not da1:
        print("\nskipped: DA1 throughput (no DA1 map)")
    elif a.da1:
        _, world, scen = da1[0]
        S.search(world, scen[0, :3].astype(np.int64), scen[0, 3:6].astype(np.int64))
        qs = scen[: a.da1]
        r = numba_batch(world, qs)
        print(f"\n{a.da1} DA1 queries, one by one (search): {r['wall']:.2f} s wall "
              f"({r['ksec']:.2f} s in the kernel), {len(r['bad'])} mismatches")
        harness.record("da1/one_by_one", dict(queries=a.da1, wall_s=r["wall"],
                                              kernel_s=r["ksec"], mismatches=len(r["bad"])))
        for workers in sorted({1, a.workers}):
            t0 = time.perf_counter()
            res = S.search_many(world, qs[:, :3].astype(np.int64), qs[:, 3:6].astype(np.int64),
                                workers=workers)
            wall = time.perf_counter() - t0
            bad = sum(not x.found or abs(x.cost - q[6]) > 1e-6 * q[6]
                      for x, q in zip(res, qs, strict=True))
            print(f"{a.da1} DA1 queries, search_many with {workers} thread(s): {wall:.2f} s "
                  f"wall, {bad} mismatches")
            harness.record(f"da1/search_many_{workers}", dict(queries=a.da1, wall_s=wall,
                                                              mismatches=bad))
        total_bad += len(r["bad"])
    if not a.compare:
        return 1 if total_bad else 0

    print(f"\nratios on cropped worlds (start/goal box + {a.pad} cells; same graph for all; "
          "thread CPU s)")
    print(f"{'case':10s} {'queries':>7s} {'numba s':>9s} {'networkx s':>10s} {'python s':>9s} "
          f"{'nx/numba':>9s} {'py/numba':>9s}")
    cases = wf + ([("geb079", *geb)] if geb is not None else [])
    if a.smoke:  # networkx takes seconds per query on the larger maps
        cases = [c for c in cases if c[0] == "Simple"]
    ratios = []
    for name, world, scen in cases:
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
        harness.record(f"cropped/{name}", dict(queries=done, numba_s=r["numba"], nx_s=r["nx"],
                                               python_s=r["py"], skipped=r["skipped"]))
        ratios += [harness.single_ratio(f"networkx/numba time, {name} cropped", r["nx"],
                                        r["numba"], note=f"sums over {done} queries"),
                   harness.single_ratio(f"Python/numba time, {name} cropped", r["py"],
                                        r["numba"], note=f"sums over {done} queries")]
    for line in ratios:
        print(line)
    return 1 if total_bad else 0


if __name__ == "__main__":
    sys.exit(main())
