"""Fixed cost per call: ``search()`` and ``plan()`` on a prebuilt world, outside the expansions.

Usage::

    python benchmarks/fixed_cost.py [--calls 2000] [--parts]

The query is one move long (start and goal are neighbouring free cells of a 64^3 cubic
world with a few obstacles), so the two expansions it makes (26 nodes generated) cost a small
share: the figure is what every call pays whatever its length (argument checks, endpoint
checks, the kernel call, building the result). The same search with the goal at the start
(one expansion, no node generated) is the fixed cost with no expansion work at all. Each
figure is the median per call of ``--calls`` calls, after warm-up (compilation is never
counted). ``search_speed.py`` prints the same line.
"""

from __future__ import annotations

import argparse
import sys
import time

import numpy as np

from planner import search as S
from planner.lattice import Lattice
from planner.planning import plan
from planner.world import World


def _query():
    """The one-move query: a 64^3 cubic world with a few obstacles, and two neighbouring
    free cells, searched once to warm everything up."""
    rng = np.random.default_rng(0)
    blocked = rng.integers(0, 64, (2000, 3))
    blocked = blocked[blocked[:, 0] >= 20]  # the query's corner stays free
    world = World(Lattice.named("cubic", 1.0), blocked, [[0, 0, 0], [63, 63, 63]])
    s, g = np.array([10, 10, 10]), np.array([11, 10, 10])
    S.warm_up()
    return world, s, g


def _medians(calls: int, named: tuple) -> dict:
    """Median wall time per call (s) of each ``(name, call)`` of ``named``, and as
    ``"engine"`` that of the ``seconds`` the ``"search"`` call's results report."""
    out = {}
    for name, call in named:
        t = np.empty(calls)
        k = np.empty(calls)
        for i in range(calls):
            t0 = time.perf_counter()
            r = call()
            t[i] = time.perf_counter() - t0
            k[i] = getattr(r, "seconds", 0.0)
        out[name] = float(np.median(t))
        if name == "search":
            out["engine"] = float(np.median(k))
    return out


def fixed_cost(calls: int = 2000) -> dict:
    """Median wall time per call (s) of ``search()`` and ``plan()`` on a one-move query, of
    the kernel time ``search()`` reports (``SearchResult.seconds``, ``engine``) and of
    ``search()`` from a cell to itself (``same``)."""
    world, s, g = _query()
    ps, pg = world.lattice.to_world(np.array([s, g]))
    for _ in range(50):
        S.search(world, s, g)
        plan(world, ps, pg)
    return _medians(calls, (("search", lambda: S.search(world, s, g)),
                            ("plan", lambda: plan(world, ps, pg)),
                            ("same", lambda: S.search(world, s, s))))


def line(calls: int = 2000) -> str:
    """One printed line of :func:`fixed_cost` (microseconds)."""
    r = fixed_cost(calls)
    return (f"fixed cost per call on a prebuilt world (one-move query, median of {calls}): "
            f"search() {r['search'] * 1e6:.1f} us (its kernel call {r['engine'] * 1e6:.1f} us; "
            f"goal <= 10 us outside the expansions; {r['same'] * 1e6:.1f} us from a cell to "
            f"itself), plan() {r['plan'] * 1e6:.1f} us (goal <= 50 us)")


def parts(calls: int = 2000) -> dict:
    """Where ``search()``'s time goes on the one-move query: the median (s) of ``search()``,
    of its engine call (``SearchResult.seconds``: the driver's repeat of the thread's last
    search and its compiled call), of the compiled call alone (read from the thread's
    search context, as the driver makes it: engine internals), and of building a
    ``SearchResult`` like the one it returns."""
    from planner.search.astar._context import _LOCAL
    from planner.search.result import SearchResult

    world, s, g = _query()
    for _ in range(50):
        r = S.search(world, s, g)
    f = _LOCAL.free[-1].fast  # the short path's tuple (planner.search.astar.driver._run)
    compiled, b, params, pausing = f[13], f[7], f[9], f[10]
    cells = r.cells
    return _medians(calls, (
        ("search", lambda: S.search(world, s, g)),
        ("compiled", lambda: compiled(b, params, pausing, *s.tolist(), *g.tolist())),
        ("result", lambda: SearchResult(True, cells, 1.0, 54, 2, 27, 1e-6, 4096, "", {},
                                        "found", True, 0.0))))


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--calls", type=int, default=2000, help="calls per figure")
    ap.add_argument("--parts", action="store_true",
                    help="also where search()'s time goes (engine internals)")
    a = ap.parse_args(argv)
    print(line(a.calls))
    if a.parts:
        r = parts(a.calls)
        print(f"search() {r['search'] * 1e6:.1f} us: its engine call {r['engine'] * 1e6:.1f} us "
              f"(the compiled call alone {r['compiled'] * 1e6:.1f} us), the rest its own Python "
              f"(building its SearchResult alone {r['result'] * 1e6:.1f} us)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
