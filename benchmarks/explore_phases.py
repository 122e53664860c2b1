"""Where a D* Lite repair's time goes while exploring: the changed cells' collection, the
repair of the collected nodes' edges, the search, and the path's extraction, each timed on
its own, against A* from scratch on the same map state.

Usage::

    python benchmarks/explore_phases.py                       # office, every lattice
    python benchmarks/explore_phases.py --lattices bcc cubic
    python benchmarks/explore_phases.py --smoke               # office, cubic

The exploration runs with ``planner.explore.explore(..., replanner="dstar",
phases=True)``: every replan is
:meth:`planner.search.dstar.lite.DStarLite.plan_phases`, the same phase code as a plan's
one compiled call, one call per phase, each timed (the calls' entry points are looked up
once: no argument typing is timed). The planner's answers are unchanged: the run's cost
mismatches against A* are printed. The phases' times include the cold start of each call,
as a replan's own call has once. An exploration runs once untimed first (caches and the
phase calls' compilation; not in ``--smoke``).
The repairs counted are the replans after the first that repaired (a kept replan checks
nothing) and did not grow the planner's arrays (their phases are not separated).

Times are the engines' own wall clocks (``time.perf_counter`` around the compiled calls:
the phases' and A*'s ``SearchResult.seconds``), in microseconds: a thread CPU clock read
costs about a microsecond itself, as much as a short phase. On the benchmark harness
(``benchmarks/harness.py``): its header (machine, load, versions, commit), and per
lattice a ``ratio`` line: the repair (its four phases) / A* from scratch on the same map
state, paired per replan.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import harness  # noqa: E402  (the sibling module)

from planner.explore import explore  # noqa: E402
from planner.lattice import NAMED_LATTICES  # noqa: E402
from planner.maps import load_map_info, map_path  # noqa: E402
from planner.search.dstar.replan import PHASES  # noqa: E402


def phases(name: str, lattice: str, query: int, resolution: float = 3.0, warm: bool = True
           ) -> tuple[np.ndarray, np.ndarray, int]:
    """Per repair: the phases' times (s, columns :data:`PHASES`) and A*'s time from
    scratch on the same map state (s); and the run's cost mismatches. ``resolution``:
    degrees between the sensor's rays; ``warm``: one untimed run first."""
    q = load_map_info(name)["queries"][query]
    run = {"lattice": lattice, "replanner": "dstar", "phases": True,
           "resolution": resolution}
    if warm:
        explore(map_path(name), q["start"], q["goal"], **run)
    r = explore(map_path(name), q["start"], q["goal"], **run)
    t = r.replan_phase_seconds[1:]
    rep = (r.replan_checks[1:] > 0) & np.isfinite(t).all(axis=1)  # repaired, not grown
    return t[rep], r.astar_seconds[1:][rep], r.mismatches


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--map", default="office", help="bundled map name (office)")
    ap.add_argument("--lattices", nargs="+", default=list(NAMED_LATTICES))
    ap.add_argument("--query", type=int, default=0)
    ap.add_argument("--resolution", type=float, default=3.0,
                    help="degrees between the sensor's rays (3, the explorer's default)")
    harness.add_arguments(ap, repeat=None)
    a = ap.parse_args(argv)
    if a.smoke:  # one short run: cubic, a coarse sensor, no warm-up run
        a.lattices, a.resolution = ["cubic"], 6.0
    with harness.session("D* Lite while exploring: a repair's time per phase against A* "
                         "from scratch", smoke=a.smoke):
        print(f"{a.map} query {a.query}: medians over the replans that repaired (us)")
        print(f"{'lattice':8s} {'repairs':>7s} " + " ".join(f"{p:>8s}" for p in PHASES)
              + f" {'A*':>8s} {'mism':>5s}")
        ratios, bad = [], 0
        for lat in a.lattices:
            t, astar, mism = phases(a.map, lat, a.query, a.resolution, warm=not a.smoke)
            bad += mism
            med = np.median(t, axis=0) * 1e6 if len(t) else np.full(len(PHASES), np.nan)
            print(f"{lat:8s} {len(t):7d} " + " ".join(f"{m:8.0f}" for m in med)
                  + f" {np.median(astar) * 1e6 if len(astar) else np.nan:8.0f} {mism:5d}",
                  flush=True)
            ratios.append(harness.ratio_line(f"repair/A* {lat}", t.sum(axis=1), astar,
                                             note="the four phases against A* from scratch "
                                                  "on the same map state, per repair"))
        for line in ratios:
            print(line)
        peak = harness.peak_rss()
        print(f"peak resident memory {peak / 2**20:.0f} MB" if peak else
              "peak resident memory n/a")
    if bad:
        print(f"FAIL: {bad} replans whose cost differs from A*", file=sys.stderr)
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
