"""Where a D* Lite replan's work goes while exploring: per replan, the scan's changed cells,
how many replans kept the stored path (:mod:`planner.search.dstar.rest`), and over the
others the cached nodes whose stencil holds a changed cell (collected and repaired, the
kept scans' cells included, over every collecting call of the replan), how many of those
died (their own cell blocked), the blocked cells left waiting at the end of the run (far
from the corridor of shortest paths: :mod:`planner.search.dstar.defer`), and the first
plan's expansions against A* forwards and backwards on the same map state.

Usage::

    python benchmarks/explore_profile.py                    # office, FCC
    python benchmarks/explore_profile.py --lattices cubic fcc

Counts only (no timing): they explain the times of ``benchmarks/explore_speed.py``.
"""

from __future__ import annotations

import argparse

import numpy as np

import planner.explore.run as ex  # the module whose globals explore() reads
from planner.maps import load_map_info, map_path
from planner.search import search
from planner.search.dstar.lite import DStarLite
from planner.search.dstar.replan import PH_COLLECT


def profile(name: str, lattice: str, query: int) -> dict:
    """Per-replan counts of one exploration run (the first plan apart)."""
    rows, first, acc = [], {}, [0, 0]
    plan, scratch, call = DStarLite.plan, ex._scratch_astar, DStarLite._call

    def counted_call(self):  # sums each collecting call's nodes (a repair may make several)
        f, arg = call(self)

        def counted(a, cells, state):
            collecting = int(self._st["phase"]) == PH_COLLECT
            out = f(a, cells, state)
            if collecting:
                n = int(self._st["collected"])
                acc[0] += n
                acc[1] += int((self._nd.mask[self._sc.ss[:n]] == 0).sum())
            return out
        return counted, arg

    def counted_plan(self):
        acc[:] = [0, 0]
        r = plan(self)
        kept = r.cell_checks == 0  # kept the stored path: nothing collected (a repair
        rows.append((id(self), acc[0], acc[1], kept, len(self._wait)))  # looks the start up)
        return r

    def with_backward(search_fn, world, cur, goal, neighbors):
        out = scratch(search_fn, world, cur, goal, neighbors)
        if not first:
            back = search(world, goal, cur, method="astar", neighbors=neighbors)
            first.update(forward=out[3], backward=back.expansions)
        return out

    DStarLite.plan, ex._scratch_astar, DStarLite._call = counted_plan, with_backward, counted_call
    try:
        q = load_map_info(name)["queries"][query]
        r = ex.explore(map_path(name), q["start"], q["goal"], lattice=lattice)
    finally:
        DStarLite.plan, ex._scratch_astar, DStarLite._call = plan, scratch, call
    # this run's planner only (not a warm-up's), its first plan apart
    c = np.array([row[1:] for row in rows if row[0] == rows[-1][0]][1:])
    rep = c[c[:, 2] == 0]  # the replans that repaired
    return {"replans": r.replans, "changed": np.median(r.changed[1:]),
            "kept": int(c[:, 2].sum()),
            "collected": _median(rep[:, 0]), "died": _median(rep[:, 1]),
            "waiting": int(c[-1, 3]) if len(c) else 0,
            "dstar_first": int(r.dstar_expansions[0]), **first}


def _median(x: np.ndarray) -> float:
    return float(np.median(x)) if len(x) else float("nan")


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--map", default="office", help="bundled map name (office)")
    ap.add_argument("--lattices", nargs="+", default=["fcc"])
    ap.add_argument("--query", type=int, default=0)
    a = ap.parse_args(argv)
    print(f"{a.map} query {a.query}: medians over the replans after the first; first plan "
          "expansions of D* Lite and of A* forwards / backwards on the same map state")
    print(f"{'lattice':8s} {'replans':>7s} {'changed':>8s} {'kept':>5s} {'collected':>9s} "
          f"{'died':>6s} {'waiting':>8s} "
          f"{'D* first':>9s} {'A* fwd':>7s} {'A* back':>8s}")
    for lat in a.lattices:
        p = profile(a.map, lat, a.query)
        print(f"{lat:8s} {p['replans']:7d} {p['changed']:8.0f} {p['kept']:5d} "
              f"{p['collected']:9.0f} "
              f"{p['died']:6.0f} {p['waiting']:8d} {p['dstar_first']:9d} {p['forward']:7d} "
              f"{p['backward']:8d}")


if __name__ == "__main__":
    main()
