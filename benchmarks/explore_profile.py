"""Where a D* Lite replan's work goes while exploring: per replan, the scan's changed cells,
the cached nodes whose stencil holds one (collected and repaired), how many of those died
(their own cell blocked), and the first plan's expansions against A* forwards and
backwards on the same map state.

Usage::

    python benchmarks/explore_profile.py                    # office, FCC
    python benchmarks/explore_profile.py --lattices cubic fcc

Counts only (no timing): they explain the times of ``benchmarks/explore_speed.py``.
"""

from __future__ import annotations

import argparse

import numpy as np

import planner.explore as ex
from planner.maps import load_map_info, map_path
from planner.search import search
from planner.search.dstar.lite import DStarLite


def profile(name: str, lattice: str, query: int) -> dict:
    """Per-replan counts of one exploration run (the first plan apart)."""
    rows, first = [], {}
    plan, scratch = DStarLite.plan, ex._scratch_astar

    def counted_plan(self):
        r = plan(self)
        n = int(self._st["collected"])
        dead = int((self._nd.mask[self._sc.ss[:n]] == 0).sum()) if n else 0
        rows.append((n, dead))
        return r

    def with_backward(search_fn, world, cur, goal, neighbors):
        out = scratch(search_fn, world, cur, goal, neighbors)
        if not first:
            back = search(world, goal, cur, method="astar", neighbors=neighbors)
            first.update(forward=out[3], backward=back.expansions)
        return out

    DStarLite.plan, ex._scratch_astar = counted_plan, with_backward
    try:
        q = load_map_info(name)["queries"][query]
        r = ex.explore(map_path(name), q["start"], q["goal"], lattice=lattice)
    finally:
        DStarLite.plan, ex._scratch_astar = plan, scratch
    c = np.array(rows[1:])
    return {"replans": r.replans, "changed": np.median(r.changed[1:]),
            "collected": np.median(c[:, 0]), "died": np.median(c[:, 1]),
            "dstar_first": int(r.dstar_expansions[0]), **first}


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--map", default="office", help="bundled map name (office)")
    ap.add_argument("--lattices", nargs="+", default=["fcc"])
    ap.add_argument("--query", type=int, default=0)
    a = ap.parse_args(argv)
    print(f"{a.map} query {a.query}: medians over the replans after the first; first plan "
          "expansions of D* Lite and of A* forwards / backwards on the same map state")
    print(f"{'lattice':8s} {'replans':>7s} {'changed':>8s} {'collected':>9s} {'died':>6s} "
          f"{'D* first':>9s} {'A* fwd':>7s} {'A* back':>8s}")
    for lat in a.lattices:
        p = profile(a.map, lat, a.query)
        print(f"{lat:8s} {p['replans']:7d} {p['changed']:8.0f} {p['collected']:9.0f} "
              f"{p['died']:6.0f} {p['dstar_first']:9d} {p['forward']:7d} {p['backward']:8d}")


if __name__ == "__main__":
    main()
