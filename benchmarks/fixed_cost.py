"""Fixed cost per call: ``search()`` and ``plan()`` on a prebuilt world, outside the expansions.

Usage::

    python benchmarks/fixed_cost.py [--calls 2000]

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


def fixed_cost(calls: int = 2000) -> dict:
    """Median wall time per call (s) of ``search()`` and ``plan()`` on a one-move query, of
    the kernel time ``search()`` reports (``SearchResult.seconds``) and of ``search()`` from
    a cell to itself (``same``)."""
    rng = np.random.default_rng(0)
    blocked = rng.integers(0, 64, (2000, 3))
    blocked = blocked[blocked[:, 0] >= 20]  # the query's corner stays free
    world = World(Lattice.named("cubic", 1.0), blocked, [[0, 0, 0], [63, 63, 63]])
    s, g = np.array([10, 10, 10]), np.array([11, 10, 10])
    ps, pg = world.lattice.to_world(np.array([s, g]))
    S.warm_up()
    for _ in range(50):
        S.search(world, s, g)
        plan(world, ps, pg)
    out = {}
    for name, call in (("search", lambda: S.search(world, s, g)),
                       ("plan", lambda: plan(world, ps, pg)),
                       ("same", lambda: S.search(world, s, s))):
        t = np.empty(calls)
        k = np.empty(calls)
        for i in range(calls):
            t0 = time.perf_counter()
            r = call()
            t[i] = time.perf_counter() - t0
            k[i] = getattr(r, "seconds", 0.0)
        out[name] = float(np.median(t))
        if name == "search":
            out["kernel"] = float(np.median(k))
    return out


def line(calls: int = 2000) -> str:
    """One printed line of :func:`fixed_cost` (microseconds)."""
    r = fixed_cost(calls)
    return (f"fixed cost per call on a prebuilt world (one-move query, median of {calls}): "
            f"search() {r['search'] * 1e6:.1f} us (its kernel call {r['kernel'] * 1e6:.1f} us; "
            f"goal <= 10 us outside the expansions; {r['same'] * 1e6:.1f} us from a cell to "
            f"itself), plan() {r['plan'] * 1e6:.1f} us (goal <= 50 us)")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--calls", type=int, default=2000, help="calls per figure")
    a = ap.parse_args(argv)
    print(line(a.calls))
    return 0


if __name__ == "__main__":
    sys.exit(main())
