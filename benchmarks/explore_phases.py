"""Where a D* Lite repair's time goes while exploring: the changed cells' collection, the
repair of the collected nodes' edges, the search, and the path's extraction, each timed on
its own, against A* from scratch on the same map state.

Usage::

    python benchmarks/explore_phases.py                       # office, every lattice
    python benchmarks/explore_phases.py --lattices bcc cubic

A replan is one compiled call (:func:`planner.search.dstar.replan.replan`) that runs its
phases in turn and can resume at any of them (``st.phase``). Here each replan that repairs
runs its first three phases as separate compiled calls (their entry points looked up once:
no argument typing is timed), then the planner's own call finishes it from the phase left
(the path). The planner's answers are unchanged: the run's cost mismatches against A* are
printed. The phases' times include the cold start of each call, as a replan's own call
has once. An exploration runs once untimed first (compilation).
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from numba import njit, typeof

import planner.explore.run as ex
from planner._entry import entry_point
from planner.maps import load_map_info, map_path
from planner.search.astar.dense import grid_offsets
from planner.search.dstar import kernel as dk
from planner.search.dstar import replan as dr
from planner.search.dstar.lite import DStarLite
from planner.search.result import RUN_GROW

PHASES = ("collect", "apply", "search", "extract")


@njit(cache=False)
def _collect(occ, ms, affect, bx, nd, sa, cells, blocked, ss, old, redo):
    st = sa[0]
    off = grid_offsets(ms.union, ms.moves, bx.dims[1], bx.dims[2])[0]
    st.collected = dr.collect(occ, ms, affect, bx, nd, st, cells, blocked, ss, old, redo, off)
    st.phase = dr.PH_APPLY


@njit(cache=False)
def _apply(occ, ms, ufree, bx, nd, heap, sa, fs, start, ss, old, redo, touched):
    st = sa[0]
    n, nm = st.collected, ms.moves.shape[0]
    if st.nodes + n * nm + 1 > nd.key.shape[0] or touched.shape[0] < 2 * n * nm + 1:
        return False  # room first: the planner's call asks for it
    dr.apply_changes(occ, ms, ufree, bx, nd, heap, st, fs[0], start, ss, old, redo, n, touched)
    st.phase = dr.PH_SEARCH
    return True


@njit(cache=False)
def _search(occ, ms, ufree, bx, nd, heap, sa, fs, start):
    st = sa[0]
    if dk.compute_path(occ, ms, ufree, bx, nd, heap, st, fs[0], start,
                       st.check_start == 1) == RUN_GROW:
        return False
    st.check_start = 0
    st.phase = dr.PH_PATH
    return True


def phases(name: str, lattice: str, query: int) -> tuple[np.ndarray, np.ndarray, int]:
    """Per repair: the phases' times (s, columns :data:`PHASES`) and A*'s time from
    scratch on the same map state (s); and the run's cost mismatches."""
    rows: list[list[float]] = []
    own_call = DStarLite._call
    calls: dict = {}

    def phased_call(self):
        call, arg = own_call(self)

        def run(arg_, cells, blocked):
            if int(self._st["phase"]) != dr.PH_COLLECT:  # resumed, or nothing changed
                return call(arg_, cells, blocked)
            sc, occ, sa = self._sc, self.world.occupancy, self._state_array
            args = ((occ, self._ms, sc.affect, self._bx, self._nd, sa, cells, blocked, sc.ss,
                     sc.old, sc.redo),
                    (occ, self._ms, sc.ufree, self._bx, self._nd, self._heap, sa, self._fs,
                     self.start, sc.ss, sc.old, sc.redo, sc.touched),
                    (occ, self._ms, sc.ufree, self._bx, self._nd, self._heap, sa, self._fs,
                     self.start))
            fns = []
            for fn, a in zip((_collect, _apply, _search), args, strict=True):
                key = (fn, tuple(typeof(x) for x in a))
                if key not in calls:  # compiled or looked up once, untimed
                    calls[key] = entry_point(fn, a)
                fns.append(calls[key])
            first = self._mark == (0, 0)  # the first plan: nothing to repair yet
            t = [time.perf_counter()]
            whole = True
            for fn, a in zip(fns, args, strict=True):
                whole = fn(*a) is not False
                t.append(time.perf_counter())
                if not whole:
                    break
            done = call(arg_, cells, blocked)
            t.append(time.perf_counter())
            if whole and done != RUN_GROW and not first:
                rows.append(list(np.diff(t)))
            return done

        return run, arg

    q = load_map_info(name)["queries"][query]
    ex.explore(map_path(name), q["start"], q["goal"], lattice=lattice,
               replanner="dstar")  # compile
    DStarLite._call = phased_call
    try:
        r = ex.explore(map_path(name), q["start"], q["goal"], lattice=lattice,
                       replanner="dstar")
    finally:
        DStarLite._call = own_call
    rep = r.replan_checks[1:] > 0  # the replans that repaired (a kept one checks nothing)
    return np.array(rows), r.astar_seconds[1:][rep], r.mismatches


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--map", default="office", help="bundled map name (office)")
    ap.add_argument("--lattices", nargs="+", default=["cubic", "bcc", "fcc", "mcc", "hex"])
    ap.add_argument("--query", type=int, default=0)
    a = ap.parse_args(argv)
    print(f"{a.map} query {a.query}: medians over the replans that repaired (us)")
    print(f"{'lattice':8s} {'repairs':>7s} " + " ".join(f"{p:>8s}" for p in PHASES)
          + f" {'A*':>8s} {'mism':>5s}")
    for lat in a.lattices:
        t, astar, bad = phases(a.map, lat, a.query)
        med = np.median(t, axis=0) * 1e6 if len(t) else np.full(4, np.nan)
        print(f"{lat:8s} {len(t):7d} " + " ".join(f"{m:8.0f}" for m in med)
              + f" {np.median(astar) * 1e6 if len(astar) else np.nan:8.0f} {bad:5d}")


if __name__ == "__main__":
    main()
