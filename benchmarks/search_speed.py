"""Search engine speed: our A* vs a minimal C++ A* (the anchor), per lattice, Lazy Theta*
vs A*, weighted-theta vs both, DA1 throughput, and numba vs networkx vs plain Python A* on
cropped worlds.

Usage::

    python benchmarks/search_speed.py                 # every table, sampled queries
    python benchmarks/search_speed.py --all-warframe  # all 30,000 Warframe queries, mismatches
    python benchmarks/search_speed.py --da1 1000      # time 1,000 DA1 queries

The per-lattice tables (sight walk per cell against the cubic integer walk, A* + smoothing
and Lazy Theta* per lattice against cubic on the office map and geb079) are
``benchmarks/lattice_sight.py``'s, printed here too (``--no-lattice-sight`` skips them).

The C++ anchor (``benchmarks/cpp_anchor.py``) is compiled at run time with the system
compiler and skipped with a note when there is none. Every ratio is measured in one run on
the same queries (the machine may be shared: trust ratios, not absolute times).

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

from planner import search as S
from planner.lattice import Lattice
from planner.search.run import H_WEIGHT as WEIGHT
from planner.world import World

ROOT = Path(__file__).resolve().parents[1]
WARFRAME = ROOT / ".." / "shared" / "data" / "warframe"
MAPS = ("Simple", "Complex", "DA1")
LONG = 10_000  # expansions: the queries the floor goal is about
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


def anchor_batch(world: World, queries: np.ndarray, repeat: int = 1) -> dict | None:
    """The C++ anchor (:mod:`cpp_anchor`, cubic-26, MovingAI rule) on the same world and
    queries, ``repeat`` passes over them in one process: its expansions (one pass) and
    per-query search seconds, the fastest pass of each (grid loading outside its clock).
    None when no compiler is present. Costs are checked against ours by the caller."""
    import cpp_anchor

    if not cpp_anchor.available():
        return None
    occ = world.occupancy
    if occ.mode != 0:
        return None
    n = int(np.prod(occ.dims))  # the occupancy grid holds one bit per cell
    free = np.unpackbits(occ.grid, count=n, bitorder="little").astype(bool).reshape(
        tuple(occ.dims))
    cells = queries[:, :6].astype(np.int64) - np.tile(occ.lo, 2)
    res = cpp_anchor.run(free, np.tile(cells, (max(1, repeat), 1)))
    res, secs = res[: len(cells)], res[:, 2].reshape(-1, len(cells)).min(axis=0)
    step = 2.0 * world.lattice.packing_radius  # the anchor counts cells; ours are metres
    cost = np.where(res[:, 0] < 0, res[:, 0], res[:, 0] * step)
    return dict(exp=int(res[:, 1].sum()), sec=float(secs.sum()), cost=cost, secs=secs,
                exps=res[:, 1].astype(np.int64))


def anchor_row(name: str, world: World, qs: np.ndarray, repeat: int = 3) -> tuple[str, dict]:
    """Ours vs the anchor on the same queries: expansions/s of each and their ratio.

    Each side makes ``repeat`` passes over the queries in one process (ours: this one; the
    anchor: its own), and each query counts its fastest pass on each side: a busy machine
    slows whichever side it happens to meet, and the minimum filters that out. Both sides
    keep their arrays between passes, so both see a query's memory warm after the first.
    Returns the row and our first pass (costs, mismatches)."""
    repeat = max(1, repeat)
    runs = [numba_batch(world, qs)]
    an = anchor_batch(world, qs, repeat)
    runs += [numba_batch(world, qs) for _ in range(repeat - 1)]
    r = runs[0]
    secs = np.min([x["secs"] for x in runs], axis=0)
    ours = r["exp"] / secs.sum()
    if an is None:
        return (f"{name:10s} {r['n']:7d} {ours:11.3g}  (C++ anchor skipped: no g++ / c++ on "
                "PATH)", r)
    ok = np.isclose(an["cost"], r["costs"], rtol=1e-9, atol=1e-9) | (
        (an["cost"] < 0) & ~np.isfinite(r["costs"]))
    aps = an["exp"] / an["sec"]
    # the goal's queries: >= LONG expansions, where the per-call cost no longer counts
    long = r["exps"] >= LONG
    if long.any():
        lr = (r["exps"][long].sum() / secs[long].sum()) / (
            an["exps"][long].sum() / an["secs"][long].sum())
        tail = f" {int(long.sum()):6d} {lr:7.2f}"
    else:
        tail = f" {0:6d} {'-':>7s}"
    return (f"{name:10s} {r['n']:7d} {ours:11.3g} {aps:11.3g} {ours / aps:7.2f} "
            f"{r['exp'] / max(an['exp'], 1):9.3f} {int((~ok).sum()):8d}" + tail, r)


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


def geb079(n_queries: int = 20, seed: int = 0, lattice: str = "cubic"
           ) -> tuple[World, np.ndarray] | None:
    """The real OctoMap scan geb079.bt on the cubic lattice at its native 0.08 m, with
    random free start/goal cells at least 10 m apart (None when the data is absent)."""
    from planner.world.build import build_world

    if not GEB079.is_file():
        return None
    world = build_world(GEB079, lattice, cell_volume=0.08**3, radius=0.0)
    rng = np.random.default_rng(seed)
    lo = np.ceil(world.bounds[0] / 0.08).astype(np.int64)
    hi = np.floor(world.bounds[1] / 0.08).astype(np.int64)
    q = []
    while len(q) < n_queries:
        c = rng.integers(lo, hi + 1, size=(2, 3))
        if world.is_free(c).all() and np.linalg.norm(c[0] - c[1]) * 0.08 >= 10.0:
            q.append(np.r_[c[0], c[1]])
    return world, np.array(q, float)


def lattice_table(geb: tuple[World, np.ndarray], repeat: int = 3) -> None:
    """A* per-expansion cost on each lattice relative to cubic: geb079 at the same cell
    volume (0.08 m^3), the cubic queries' centres quantized on each lattice. ``repeat``
    passes over the lattices in turn; each query counts its fastest pass (a busy machine
    slows whichever lattice it happens to meet)."""
    from planner.lattice import NAMED_LATTICES

    gw, gq = geb
    pts = gw.lattice.to_world(gq[:, :6].reshape(-1, 3).astype(np.int64)).reshape(-1, 2, 3)
    print("\nA* per expansion by lattice, geb079 (cell volume 0.08^3 m^3, full neighbours, "
          "safe rule); ratio = ns per expansion / cubic's (goal <= 1.3);\n"
          f"each query's time is its fastest of {max(1, repeat)} passes, the lattices in turn")
    print(f"{'lattice':8s} {'queries':>7s} {'expansions':>11s} {'ns/exp':>8s} {'vs cubic':>8s}")
    cases = []
    for name in NAMED_LATTICES:
        w = gw if name == "cubic" else geb079(0, lattice=name)[0]
        q = w.lattice.quantize(pts.reshape(-1, 3)).reshape(-1, 6)
        q = q[w.is_free(q[:, :3]) & w.is_free(q[:, 3:])]
        S.search(w, q[0, :3], q[0, 3:])
        cases.append((name, w, q.astype(float), []))
    for _ in range(max(1, repeat)):
        for _, w, q, runs in cases:
            runs.append(numba_batch(w, q))
    base = None
    for name, _, _, runs in cases:
        exp = runs[0]["exp"]
        ns = 1e9 * np.min([x["secs"] for x in runs], axis=0).sum() / exp
        base = ns if base is None else base
        print(f"{name:8s} {len(runs[0]['secs']):7d} {exp:11d} {ns:8.0f} {ns / base:8.2f}")


def anyangle_table(geb: tuple[World, np.ndarray] | None, n: int,
                   save: Path | None = None, check: Path | None = None,
                   repeat: int = 3) -> None:
    """Lazy Theta* vs A* on the same queries: median per-query time ratio (goal <= 2), and
    the median per-query expansion ratio beside it (most of the time ratio: where an obstacle
    makes the path longer than the straight line by a little, Lazy Theta* must expand every
    cell whose g + |x - goal| is below the path length, a thin tube along the whole line; A*'s
    move-set gauge is flat along the many equal-cost lattice paths, so it dives).

    ``save`` writes each query's Lazy Theta* path length (JSON, per world); ``check``
    compares this run's lengths with such a file (a run of another version): the largest
    relative difference and the queries differing by more than 0.1% (goal: none).
    Each query's time on each side is its fastest of ``repeat`` alternating runs."""
    print(f"\nLazy Theta* vs A* (cubic-26, same queries; kernel time, fastest of {repeat} "
          f"alternating runs per query); up to {n} per world")
    head = (f"{'world':10s} {'queries':>7s} {'A* med ms':>9s} {'LT* med ms':>10s} "
            f"{'med ratio':>9s} {'LT*/A* exp':>10s} {'med exp':>7s} {'LT* length m':>12s}")
    ref = json.loads(check.read_text()) if check is not None else None
    print(head + (f" {'max dlen':>9s} {'>0.1%':>5s}" if ref is not None else ""))
    cases = [(m, *load_warframe(m)) for m in MAPS]
    if geb is not None:
        cases.append(("geb079", *geb))
    lengths = {}
    for name, world, scen in cases:
        qs = scen[:: max(1, len(scen) // n)][:n]
        ta, tl, ea, el, ll = [], [], [], [], []
        S.search(world, qs[0, :3].astype(np.int64), qs[0, 3:6].astype(np.int64),
                 method="lazy-theta")
        for q in qs:
            s, g = q[:3].astype(np.int64), q[3:6].astype(np.int64)
            ka, kl = [], []
            for _ in range(max(1, repeat)):
                ra = S.search(world, s, g)
                rl = S.search(world, s, g, method="lazy-theta")
                ka.append(ra.seconds)
                kl.append(rl.seconds)
            ta.append(min(ka))
            tl.append(min(kl))
            ea.append(ra.expansions)
            el.append(rl.expansions)
            ll.append(rl.cost)
        ta, tl, ea, el = np.array(ta), np.array(tl), np.array(ea), np.array(el)
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
    if save is not None:
        save.write_text(json.dumps(lengths))


def weighted_table(geb: tuple[World, np.ndarray] | None, n: int, repeat: int = 3) -> None:
    """Any-angle at A*'s cost (issue goal: <= 2x A*): per world (DA1, geb079 at 0.08 m),
    the median per-query time ratio of Lazy Theta* / A* and of weighted-theta / A*, and the
    per-query length ratio weighted-theta / Lazy Theta* (goal: within 0.5% on every
    query): its largest, median and the share within 0.5%. Kernel time, each query's
    fastest of ``repeat`` alternating runs of the three methods."""
    print(f"\nweighted-theta (Lazy Theta*, heuristic x{WEIGHT}) vs Lazy Theta* vs A* "
          f"(cubic-26, same queries, fastest of {repeat} alternating runs); up to {n} per "
          "world\ntime goal <= 2 (median of per-query ratios); length goal: "
          "weighted / LT* <= 1.005 on every query")
    print(f"{'world':8s} {'queries':>7s} {'LT*/A*':>7s} {'W/A*':>6s} {'W/A* exp':>8s} "
          f"{'len max':>8s} {'len med':>8s} {'<=0.5%':>6s}")
    cases = [("DA1", *load_warframe("DA1"))]
    if geb is not None:
        cases.append(("geb079", *geb))
    methods = ("astar", "lazy-theta", "weighted-theta")
    for name, world, scen in cases:
        qs = scen[:: max(1, len(scen) // n)][:n]
        for m in methods:  # compile / load every kernel outside the timed runs
            S.search(world, qs[0, :3].astype(np.int64), qs[0, 3:6].astype(np.int64), method=m)
        tl, tw, ew, ln = [], [], [], []
        for q in qs:
            s, g = q[:3].astype(np.int64), q[3:6].astype(np.int64)
            best = dict.fromkeys(methods, math.inf)
            for _ in range(max(1, repeat)):
                res = {m: S.search(world, s, g, method=m) for m in methods}
                for m in methods:
                    best[m] = min(best[m], res[m].seconds)
            if not res["astar"].found:  # no path: nothing to compare
                continue
            tl.append(best["lazy-theta"] / best["astar"])
            tw.append(best["weighted-theta"] / best["astar"])
            ew.append(res["weighted-theta"].expansions / res["astar"].expansions)
            ln.append(res["weighted-theta"].cost / res["lazy-theta"].cost)
        ln = np.array(ln)
        print(f"{name:8s} {len(ln):7d} {np.median(tl):7.2f} {np.median(tw):6.2f} "
              f"{np.median(ew):8.2f} {ln.max():8.4f} {np.median(ln):8.4f} "
              f"{np.mean(ln <= 1.005):6.0%}")


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
    ap.add_argument("--all-warframe", action="store_true",
                    help="check all 10,000 queries of each Warframe map")
    ap.add_argument("--maps", nargs="+", choices=MAPS, default=list(MAPS),
                    help="Warframe maps of the anchor table (default: all three)")
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
                    help="skip the A* vs C++ anchor table")
    ap.add_argument("--repeat", type=int, default=3,
                    help="runs of each side (ours / the anchor, A* / Lazy Theta*, each "
                         "lattice), alternating; each query counts its fastest run on each "
                         "side (load on a shared machine)")
    ap.add_argument("--anyangle", type=int, default=20,
                    help="queries per world for Lazy Theta* and weighted-theta vs A* (0: skip)")
    ap.add_argument("--no-lattice-sight", dest="lattice_sight", action="store_false",
                    help="skip the per-lattice sight walk and planning tables "
                         "(benchmarks/lattice_sight.py)")
    ap.add_argument("--save-lengths", type=Path, metavar="JSON",
                    help="write each query's Lazy Theta* path length here")
    ap.add_argument("--check-lengths", type=Path, metavar="JSON",
                    help="compare Lazy Theta* path lengths with a --save-lengths file")
    a = ap.parse_args(argv)
    if not WARFRAME.exists():
        print(f"no Warframe data at {WARFRAME}; skipping")
        return 0

    cold, warm = cold_warm()
    print(f"first call in a fresh process (import + cached-kernel load + tiny search): "
          f"{cold:.2f} s; second call {warm * 1e3:.2f} ms")
    import fixed_cost  # the sibling script

    print(fixed_cost.line())

    print("\nA*, cubic-26, safe rule (= MovingAI no corner cutting), ours vs the C++ anchor "
          "(benchmarks/cpp_anchor.py, g++ -O3) on the same queries; kernel time only.\n"
          "ratio = our exp/s / anchor exp/s; exp ratio = our expansions / its; long: the\n"
          f"queries of >= {LONG:,} expansions and the ratio over them alone (goal >= 0.7);\n"
          f"each side's time per query is its fastest of {a.repeat} passes (each side in "
          "one process)")
    head = (f"{'map':10s} {'queries':>7s} {'ours exp/s':>11s} {'anchor':>11s} {'ratio':>7s} "
            f"{'exp ratio':>9s} {'cost!=':>8s} {'long':>6s} {'ratio':>7s}")
    print(head)
    total_bad = []
    for name in a.maps if a.anchor else ():
        world, scen = load_warframe(name)
        S.search(world, scen[0, :3].astype(np.int64), scen[0, 3:6].astype(np.int64))
        qs = scen if a.all_warframe else scen[:: max(1, len(scen) // a.sample)][: a.sample]
        row, r = anchor_row(name, world, qs, a.repeat)
        total_bad += [(name, *b) for b in r["bad"]]
        print(row)
    geb = geb079(a.geb_queries) if a.geb079 else None
    if geb is not None and a.anchor:
        gw, gq = geb
        S.search(gw, gq[0, :3].astype(np.int64), gq[0, 3:6].astype(np.int64))
        print(anchor_row("geb079", gw, gq, a.repeat)[0])
    print(f"Warframe optimal costs: {len(total_bad)} mismatches"
          + (f" (all {10_000 * len(a.maps):,} queries)" if a.all_warframe
             else f" ({a.sample} per map)"))
    for b in total_bad[:20]:
        print("  ", b)

    if geb is not None and a.lattices:
        lattice_table(geb, a.repeat)
    if a.anyangle:
        anyangle_table(geb, a.anyangle, a.save_lengths, a.check_lengths, a.repeat)
        weighted_table(geb, a.anyangle, a.repeat)

    if a.lattice_sight:  # the sibling script: sight walk per cell, planning per lattice
        import lattice_sight

        lattice_sight.main(["--repeat", str(a.repeat)]
                           + ([] if a.geb079 else ["--maps", "office"]))

    if a.da1:
        world, scen = load_warframe("DA1")
        S.search(world, scen[0, :3].astype(np.int64), scen[0, 3:6].astype(np.int64))
        qs = scen[: a.da1]
        r = numba_batch(world, qs)
        print(f"\n{a.da1} DA1 queries, one by one (search): {r['wall']:.2f} s wall "
              f"({r['ksec']:.2f} s in the kernel), {len(r['bad'])} mismatches")
        for workers in sorted({1, a.workers}):
            t0 = time.perf_counter()
            res = S.search_many(world, qs[:, :3].astype(np.int64), qs[:, 3:6].astype(np.int64),
                                workers=workers)
            wall = time.perf_counter() - t0
            bad = sum(not x.found or abs(x.cost - q[6]) > 1e-6 * q[6]
                      for x, q in zip(res, qs, strict=True))
            print(f"{a.da1} DA1 queries, search_many with {workers} thread(s): {wall:.2f} s "
                  f"wall, {bad} mismatches")
    if not a.compare:
        return 1 if total_bad else 0

    print(f"\nratios on cropped worlds (start/goal box + {a.pad} cells; same graph for all)")
    print(f"{'case':10s} {'queries':>7s} {'numba s':>9s} {'networkx s':>10s} {'python s':>9s} "
          f"{'nx/numba':>9s} {'py/numba':>9s}")
    cases = [(name, *load_warframe(name)) for name in MAPS]
    if geb is not None:
        cases.append(("geb079", *geb))
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

    return 1 if total_bad else 0


if __name__ == "__main__":
    sys.exit(main())
