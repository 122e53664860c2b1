"""Where lattice A*'s expansions lie: below the optimal cost C*, or on the plateau f = C*.

Usage::

    python benchmarks/plateau.py [--maps DA1 Complex geb079 office] [--queries 8]
    python benchmarks/plateau.py --maps DA1 Complex --queries 32 --tie nearer

The planning maps and queries of ``lattice_sight.py`` (the same worlds, the same query
points quantized on each lattice). A plain-Python A* (``search_speed.python_astar``) with
the engine's move set, safe rule, move-set gauge heuristic, f grid and larger-g tie-break
runs each query again and files each expansion by its f: below C* (nodes any A* with this
heuristic expands: a detour makes the path longer than the gauge) or at C* (the plateau of
paths as short as the gauge, where the tie-break decides how many). Its expansion counts
are printed beside the engine's; they differ only where nodes tie in both f and g (each
heap then picks its own). ``backtrack``: the most the g of an expansion fell below the
largest g expanded before it (m), summed over the queries: a dive into a dead end of the
plateau that the search had to back out of.

``--tie nearer`` replays the queries with another tie-break among equal f, the node nearest
the goal in a straight line first, in the plain-Python A* only: its columns then count
that rule's expansions, while ``engine`` and the ratio lines stay the engine's (larger g
first). Every cost must come out the same under either rule (any order among equal f keeps
A* optimal with a consistent heuristic); the expansions show what the rule would save.

The ratio lines pair each lattice's engine expansions with cubic-26's per query.
Pure Python: about a minute per 100,000 expansions.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import harness  # noqa: E402  (the sibling modules)
import lattice_sight  # noqa: E402
import search_speed  # noqa: E402

from planner import search as S  # noqa: E402


def plateau_table(map_name: str, n: int, data: Path, tie: str = "larger-g") -> None:
    worlds = lattice_sight.map_worlds(map_name, data)
    pts = lattice_sight.query_points(worlds, n)
    print(f"\n{map_name}: {len(pts)} queries (lattice_sight.py's), A* full move set; "
          f"expansions summed over the queries; python: tie-break {tie}")
    print(f"{'lattice':8s} {'engine':>8s} {'python':>8s} {'below C*':>9s} {'at C*':>8s} "
          f"{'at C* %':>7s} {'backtrack m':>11s}")
    engine = {}
    for name, w in worlds.items():
        q = w.lattice.quantize(pts.reshape(-1, 3)).reshape(-1, 2, 3)
        ours = np.zeros(len(q), np.int64)
        below = at = python = 0
        back = 0.0
        for i in range(len(q)):
            r = S.search(w, q[i, 0], q[i, 1])
            ours[i] = r.expansions
            trace = []
            c, _ = search_speed.python_astar(w, q[i, 0], q[i, 1], trace=trace, tie=tie)
            assert math.isclose(c, r.cost, rel_tol=1e-9), (name, i, c, r.cost)
            fs, gs = np.asarray(trace).T
            tol = 1e-9 * max(c, 1.0)
            below += int((fs < c - tol).sum())
            at += int((np.abs(fs - c) <= tol).sum())
            python += len(fs)
            back += float((np.maximum.accumulate(gs) - gs).max())
        engine[name] = ours
        print(f"{name:8s} {ours.sum():8d} {python:8d} {below:9d} {at:8d} "
              f"{100 * at / max(python, 1):7.1f} {back:11.1f}")
        harness.record(f"plateau/{map_name}/{name}/{tie}", dict(
            engine_expansions=int(ours.sum()), python_expansions=python, below_cost=below,
            at_cost=at, backtrack_m=back))
    for name in worlds:
        if name != "cubic":
            print(harness.ratio_line(f"A* expansions {name}/cubic, {map_name}", engine[name],
                                     engine["cubic"], note="per query, the engine's counts"))


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    harness.add_arguments(ap, repeat=None, data=True, json=True)
    ap.add_argument("--maps", nargs="*", default=["DA1", "Complex"],
                    help="maps (bundled names, geb079, or Warframe names under DATA/warframe)")
    ap.add_argument("--queries", type=int, default=8, help="queries per map")
    ap.add_argument("--tie", choices=search_speed.TIES, default="larger-g",
                    help="the plain-Python A*'s tie-break among equal f (default: the "
                    "engine's)")
    a = ap.parse_args(argv)
    if a.smoke:
        a.maps, a.queries = ["narrow_passage"], 2
    with harness.session("where lattice A*'s expansions lie: below C* or on its plateau",
                         smoke=a.smoke, json=a.json,
                         command=harness.command_line("plateau.py", argv)):
        lattice_sight.each_map(a.maps, a.data, lambda m: plateau_table(m, a.queries, a.data, a.tie))
    return 0


if __name__ == "__main__":
    sys.exit(main())
