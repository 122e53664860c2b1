"""What the dense node array and the search loop's variants fixed for it buy: each search
on a dense grid against the same search on the paged node map, on the same queries.

Every search runs the one search loop, ``planner/search/astar/loop.py:search_loop``,
compiled per variant. A search on a dense grid whose cell -> node array fits
:data:`planner.search.astar.driver.DENSE_SLOT_BUDGET` finds its nodes in that array and runs
the variant fixed for that case at compile time (the dense array, the stencil's bit mask and
the method fixed, so their tests fold away): A* ``DENSE_ASTAR`` (which also marks closed
nodes in the dense array), Lazy Theta* ``DENSE_LAZY``. With the budget at 0 (the switch
``tests/test_search.py`` uses to check the two agree) the same search runs the ``GENERAL``
variant on the paged node map: that is the other side here. Each side searches its own copy
of the world (the dense node array is held per grid, so the budget only decides for a grid
that holds none), with the same queries, and the answers must agree (cost and expansions; a
disagreement is printed and makes the exit code 1). The ratio is what the dense node array
buys together with the variant that folds its tests: the paged map's lookups and the
general variant's per-expansion tests.

Usage::

    python benchmarks/loop_speed.py                       # DA1 and Complex, 20 queries each
    python benchmarks/loop_speed.py --maps DA1 --queries 50
    python benchmarks/loop_speed.py --smoke               # a few seconds

Timing (``benchmarks/harness.py``): thread CPU time per ``search()`` call, the two sides
taking turns query by query, each query its fastest of ``--repeat`` rounds; ``ratio`` lines
give the median per-query ratio paged / dense with its 95% interval.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import harness  # noqa: E402  (the sibling module)
from search_speed import MAPS, load_warframe  # noqa: E402

from planner import search as S  # noqa: E402
from planner.search.astar import driver  # noqa: E402
from planner.world import World  # noqa: E402

METHODS = {"astar": "DENSE_ASTAR", "lazy-theta": "DENSE_LAZY"}


def _search_general(world: World, s, g, method: str):
    """``search()`` with the dense node array refused: the general loop on the paged map."""
    budget = driver.DENSE_SLOT_BUDGET
    driver.DENSE_SLOT_BUDGET = 0
    try:
        return S.search(world, s, g, method=method)
    finally:
        driver.DENSE_SLOT_BUDGET = budget


def compare(name: str, world: World, qs: np.ndarray, method: str, repeat: int) -> tuple:
    """Both sides on the queries ``qs`` (Q, >= 6); returns (row text, ratio line, agree)."""
    general = World(world.lattice, world.blocked, world.bounds)  # its own grid (docstring)
    res: dict[str, list] = {"special": [None] * len(qs), "general": [None] * len(qs)}
    calls = {"special": lambda s, g: S.search(world, s, g, method=method),
             "general": lambda s, g: _search_general(general, s, g, method)}

    def side(k):
        def run(i):
            s, g = qs[i, :3].astype(np.int64), qs[i, 3:6].astype(np.int64)
            r, t = harness.cpu_result(lambda: calls[k](s, g))
            res[k][i] = r
            return t
        return run

    side("special")(0), side("general")(0)  # compile / load outside the clock
    best = harness.interleaved({k: side(k) for k in calls}, range(len(qs)), repeat)
    sp, ge = res["special"], res["general"]
    pairs = list(zip(sp, ge, strict=True))
    agree = all(a.cost == b.cost and a.expansions == b.expansions for a, b in pairs)
    dense_bytes = np.median([a.peak_bytes - b.peak_bytes for a, b in pairs])
    ts, tg = best["special"], best["general"]
    row = (f"{name:8s} {method:10s} {len(qs):7d} {1e3 * np.median(ts):8.2f} "
           f"{1e3 * np.median(tg):8.2f} {np.median(tg / ts):7.2f} "
           f"{tg.sum() / ts.sum():7.2f} {dense_bytes / 2**20:9.1f} {'yes' if agree else 'NO':>6s}")
    line = harness.ratio_line(f"paged general / dense {METHODS[method]}, {name}", tg, ts,
                              note="per query; > 1: the dense side is faster")
    return row, line, agree


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    harness.add_arguments(ap, repeat=3, data=True)
    ap.add_argument("--maps", nargs="+", choices=MAPS, default=["Complex", "DA1"],
                    help="Warframe maps (default: Complex DA1)")
    ap.add_argument("--queries", type=int, default=20, help="queries per map (evenly spaced)")
    ap.add_argument("--methods", nargs="+", choices=list(METHODS), default=list(METHODS))
    a = ap.parse_args(argv)
    n, maps = (3, ["Simple"]) if a.smoke else (a.queries, a.maps)
    with harness.session("dense node array and its loops vs the paged map", smoke=a.smoke):
        present = [m for m in maps if (a.data / "warframe" / f"{m}.3dmap").is_file()]
        if not present:
            return harness.skip(f"no Warframe maps under {a.data / 'warframe'}")
        print("cubic-26, safe rule; thread CPU time per search() call, the sides taking turns "
              f"per query, fastest of {a.repeat}; paged = DENSE_SLOT_BUDGET 0; median, sum: "
              "paged / dense time")
        print(f"{'map':8s} {'method':10s} {'queries':>7s} {'dense ms':>8s} {'paged ms':>8s} "
              f"{'median':>7s} {'sum':>7s} {'dense MiB':>9s} {'agree':>6s}")
        lines, ok = [], True
        for name in present:
            world, scen = load_warframe(name, a.data)
            qs = scen[:: max(1, len(scen) // n)][:n]
            for method in a.methods:
                row, line, agree = compare(name, world, qs, method, a.repeat)
                print(row, flush=True)
                lines.append(line)
                ok &= agree
        for line in lines:
            print(line)
        print("dense MiB: median extra peak bytes of the dense side (its dense node "
              "array), which also shows each side ran the loop it names")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
