"""Exploration speed: the explorer's replanning over a whole run against A* from scratch at
every replan on the same map states.

Usage::

    python benchmarks/explore_speed.py                       # bundled office, every lattice
    python benchmarks/explore_speed.py --maps office geb079  # and the geb079 OctoMap scan
    python benchmarks/explore_speed.py --replanner dstar     # D* Lite instead of the default
    python benchmarks/explore_speed.py --plots results/      # one summary PNG per run
    python benchmarks/explore_speed.py --lattices bcc --near-median 8  # the replans at the median
    python benchmarks/explore_speed.py --smoke               # office, cubic, coarse sensor

For each map and lattice the robot explores from the query's start to its goal
(:func:`planner.explore.explore` with ``--replanner``, default the explorer's: ``astar``,
A* only when a newly blocked cell touches the rest of the path; ``dstar``: D* Lite);
after every sensing step that changed the known map the replanner's plan and an A* from
scratch on the same map state (same process) are timed and their cell checks counted.
Times are the engine's own (``SearchResult.seconds``: the compiled calls; for D* Lite the
repair of the scan's changes, the search and the path in one call; for ``astar`` the
path check and the search when it ran; not the Python that checks arguments and builds
results); "med wall" the wall time of the calls a user makes (the
replanner's ``update`` and ``plan``, A*'s ``search``). The two alternate which runs first
after the scan: the first finds caches cold.

"WHOLE" is what a user pays: the run's total replanning time (first plan included) over
the total of A* from scratch at every replan, on the same map states (goal: <= 0.5), by
the thread's CPU time of the calls a user makes (the replanner's ``update`` and ``plan``,
A*'s ``search``; "R cpu" and "A* cpu", ms): on a shared machine a wall clock charges a
call for the time the thread waited, and one such wait outweighs a run's kept replans.
"tot t" is the same ratio by the engines' own (wall) times, "R ms" and "A* ms" their
totals. Beside it, per replan after the first: "med
t", "med wall", "med chk" the medians of replanner / from-scratch time (both clocks) and
cell checks; "srch" the replans (first plan included) that searched, the others kept their
path (no cell check: the scan blocked no cell the rest of the path rests on); "rep t" the
median time ratio over the replans after the first that searched; "1st t" the first
plan's ratio; "mism" the replans whose cost differs from A*'s (the run fails if any) and
"cont" the moves that touched an obstacle the sensor had not seen. The first plan of a
run also loads the compiled kernels (not timed: warmed up first). No timed assertions:
figures only.

On the benchmark harness (``benchmarks/harness.py``): its header (machine, load,
versions, commit), and per run a ``ratio`` line: the per-replan CPU ratios replanner / A*
from scratch (the replans after the first that searched; Hodges-Lehmann median with its
paired 95% interval), whose "overall" is the run's WHOLE (sum over sum, first plan and
kept replans included); "run s" is the run's thread CPU time and "peak MB" the process's
resident high-water mark after it (the sensor's rays and the known map included).
"""

from __future__ import annotations

import argparse
import sys
from functools import partial
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import harness  # noqa: E402  (the sibling module)

from planner.explore import explore  # noqa: E402
from planner.explore.run import REPLANNERS  # noqa: E402
from planner.lattice import NAMED_LATTICES  # noqa: E402
from planner.maps import load_map_info, map_path  # noqa: E402

GEB079 = harness.DATA / "octomap" / "geb079.bt"
# geb079 (Freiburg building 079, OctoMap 0.08 m; radius 0.2 m as in the README): along the
# corridor, and from the corridor into a room.
GEB079_QUERIES = (((-2.96, -0.05, 1.0), (25.0, 0.0, 1.0)),
                  ((-2.96, -0.05, 1.0), (-5.0, -5.0, 1.0)))


def runs(names: list[str], query: int, geb079: Path = GEB079
         ) -> list[tuple[str, object, tuple, dict]]:
    """(label, source, (start, goal), explore keywords) per map; geb079 only when present."""
    out = []
    for name in names:
        if name == "geb079":
            if not geb079.is_file():
                print(f"skipping geb079: {geb079} not found", file=sys.stderr)
                continue
            for i, q in enumerate(GEB079_QUERIES):
                out.append((f"geb079 q{i}", geb079, q,
                            {"radius": 0.2, "cell_volume": 0.08**3}))
        else:
            info = load_map_info(name)
            q = info["queries"][query]
            out.append((f"{name} q{query}", map_path(name), (q["start"], q["goal"]), {}))
    return out


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--maps", nargs="+", default=["office"],
                   help="bundled map names and/or geb079 (default: office)")
    p.add_argument("--lattices", nargs="+", default=list(NAMED_LATTICES))
    p.add_argument("--geb079", type=Path, default=GEB079,
                   help="the geb079 OctoMap (default: ../shared/data/octomap/geb079.bt from "
                        "the repository root)")
    p.add_argument("--query", type=int, default=0, help="bundled map query index (0)")
    p.add_argument("--sensor-range", type=float, default=4.0, help="m (4.0)")
    p.add_argument("--resolution", type=float, default=3.0, help="degrees between rays (3)")
    p.add_argument("--vertical", type=float, default=30.0, help="+- vertical fov, deg (30)")
    p.add_argument("--neighbors", default="full")
    p.add_argument("--replanner", default=REPLANNERS[0], choices=REPLANNERS,
                   help=f"the explorer's replanner (default {REPLANNERS[0]})")
    p.add_argument("--plots", type=Path, help="folder for one summary PNG per run")
    p.add_argument("--near-median", type=int, default=0, metavar="N",
                   help="also list the N replans either side of each run's median time "
                        "ratio: which replan, whether it kept the path, both times")
    harness.add_arguments(p, repeat=None)
    a = p.parse_args(argv)
    if a.smoke:  # one short run: office, cubic, a coarse sensor
        a.maps, a.lattices, a.resolution, a.near_median = ["office"], ["cubic"], 6.0, 0
    with harness.session("exploration: the replanner over a whole run against A* from "
                         "scratch at every replan", smoke=a.smoke):
        return _run(a)


def _run(a: argparse.Namespace) -> int:
    head = (f"{'map':<12} {'lattice':<7} {'status':<8} {'moves':>5} {'replans':>7} "
            f"{'srch':>4} {'med t':>6} {'med wall':>8} {'med chk':>7} {'rep t':>6} "
            f"{'1st t':>6} {'R ms':>8} {'A* ms':>8} {'tot t':>6} {'R cpu':>7} {'A* cpu':>7} "
            f"{'WHOLE':>6} "
            f"{'mism':>4} {'cont':>4} {'run s':>6} {'peak MB':>7}")
    print(f"sensor {a.sensor_range} m, fov 360 x +-{a.vertical} deg every {a.resolution} "
          f"deg, {a.neighbors} moves; replanner {a.replanner}; ratios = replanner / A* from "
          f"scratch at every replan (same map states, same process)")
    print(head)
    bad, whole, per_map, ratios = 0, [], {}, []
    for label, src, (start, goal), kw in runs(a.maps, a.query, a.geb079):
        for lat in a.lattices:
            r, secs = harness.cpu_result(partial(
                explore, src, start, goal, lattice=lat, sensor_range=a.sensor_range,
                fov=(360.0, a.vertical), resolution=a.resolution,
                neighbors=a.neighbors, replanner=a.replanner, **kw))
            peak = harness.peak_rss()
            q = r.ratios()
            k = slice(1, None) if r.replans > 1 else slice(None)
            rep = (r.replan_seconds[k] / r.astar_seconds[k])[r.searched[k]]
            rep_t = float(np.median(rep)) if len(rep) else float("nan")
            whole.append(q["total_cpu_ratio"])
            per_map.setdefault(label, []).append((q["total_cpu_ratio"], q["total_time_ratio"],
                                                  int(r.searched.sum()), r.replans,
                                                  r.mismatches))
            print(f"{label:<12} {lat:<7} {r.status:<8} {len(r.trajectory) - 1:>5} "
                  f"{r.replans:>7} {int(r.searched.sum()):>4} "
                  f"{q['median_time_ratio']:>6.3f} {q['median_wall_ratio']:>8.3f} "
                  f"{q['median_checks_ratio']:>7.4f} {rep_t:>6.3f} "
                  f"{r.replan_seconds[0] / r.astar_seconds[0]:>6.2f} "
                  f"{1e3 * r.replan_seconds.sum():>8.2f} {1e3 * r.astar_seconds.sum():>8.2f} "
                  f"{q['total_time_ratio']:>6.3f} {1e3 * r.replan_cpu_seconds.sum():>7.1f} "
                  f"{1e3 * r.astar_cpu_seconds.sum():>7.1f} {q['total_cpu_ratio']:>6.3f} "
                  f"{r.mismatches:>4} {r.contacts:>4} {secs:>6.1f} "
                  f"{peak / 2**20 if peak else float('nan'):>7.0f}", flush=True)
            ratios.append((label, lat, r, q["total_cpu_ratio"]))
            if a.near_median and r.replans > 1:
                _near_median(r, a.near_median)
            bad += r.mismatches
            if a.plots:
                r.plot(a.plots / f"explore_{label.replace(' ', '_')}_{lat}.png")
    for label, got in per_map.items():  # one line per map and query, as the README says it
        cpu, eng, srch, reps, mism = zip(*got, strict=True)
        print(f"{label}, {a.replanner}, {len(got)} lattices: whole run {min(cpu):.2f}-"
              f"{max(cpu):.2f} of A* at every replan (CPU; engine time {min(eng):.2f}-"
              f"{max(eng):.2f}), {min(srch)}-{max(srch)} of {min(reps)}-{max(reps)} replans "
              f"searched, {sum(mism)} mismatches")
    for label, lat, r, total in ratios:
        srch = r.searched.copy()
        srch[0] = False  # the first plan apart: it is in "overall" (the WHOLE)
        print(harness.ratio_line(
            f"{a.replanner}/A* cpu per replan {label} {lat}", r.replan_cpu_seconds[srch],
            r.astar_cpu_seconds[srch], overall=total, goal="overall <= 0.5",
            note="median over the replans after the first that searched; overall = the "
                 "whole run (WHOLE)"))
    if whole:
        print(f"whole-run ratio over {len(whole)} runs: {min(whole):.3f} .. {max(whole):.3f} "
              f"(goal <= 0.5); mismatches: {bad}")
    if bad:
        print(f"FAIL: {bad} replans whose cost differs from A*", file=sys.stderr)
    return 1 if bad else 0


def _near_median(r, n: int) -> None:
    """The ``n`` replans (after the first) either side of the median time ratio of the
    exploration ``r``: replan number, whether it searched, cells the scan changed, which
    search ran first after the map update (it finds the caches cold), the replanner's and
    A*'s engine times (us)."""
    d, t = r.replan_seconds[1:], r.astar_seconds[1:]
    order = np.argsort(d / t, kind="stable")
    mid = len(order) // 2
    for i in order[max(0, mid - n):mid + n]:
        first = "A*" if (i + 1) % 2 else "R"  # explore(): the replanner first on even replans
        print(f"    replan {i + 1:>4}  {'search' if r.searched[i + 1] else 'kept':<6} "
              f"changed {r.changed[i + 1]:>5}  {first} first  R {d[i] * 1e6:8.1f} us"
              f"  A* {t[i] * 1e6:8.1f} us  ratio {d[i] / t[i]:6.3f}")


if __name__ == "__main__":
    np.set_printoptions(precision=4)
    sys.exit(main())
