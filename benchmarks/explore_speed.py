"""Exploration speed: incremental D* Lite vs A* from scratch after every map update.

Usage::

    python benchmarks/explore_speed.py                       # bundled office, every lattice
    python benchmarks/explore_speed.py --maps office geb079  # and the geb079 OctoMap scan
    python benchmarks/explore_speed.py --plots results/      # one summary PNG per run
    python benchmarks/explore_speed.py --lattices bcc --near-median 8  # the replans at the median

For each map and lattice the robot explores from the query's start to its goal
(:func:`planner.explore.explore`); after every sensing step that changed the known map the
repaired D* Lite plan and an A* from scratch on the same map state (same process) are timed
and their cell checks counted. "med t" compares the engine's own times
(``SearchResult.seconds``: the compiled calls, for D* Lite the repair of the scan's
changes, the search and the path in one call; not the Python that checks arguments and
builds results); "med wall" the wall time of the calls a user makes (D* Lite's ``update``
and ``plan``, A*'s ``search``). The two alternate which runs first after the scan: the
first finds caches cold. Printed per run: status, moves, distance, replans, the median
over replans (after the first plan) of incremental / from-scratch time (both clocks) and
cell checks, the ratio of the totals, mismatches (costs that differ: the run fails if
any) and contacts (moves that touched an obstacle the sensor had not seen); D*chk, A*chk,
D*ms, A*ms are the medians over the same replans of each search's cell checks and
milliseconds. "kept" counts the replans (after the first) that kept the stored path
without repairing (:mod:`planner.search.dstar.rest`: the scan blocked no cell the path
rests on; such a replan makes no cell check, a repair at least the start's) and "rep t"
is the median time ratio over the others, the replans that repaired (the kept scans'
cells included) and searched; "1st t" the first plan's time ratio (in "tot t", not in
the medians). The first plan of a run also loads the compiled kernels; it is left out of
the medians. No timed assertions: figures only.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

from planner.explore import explore
from planner.lattice import NAMED_LATTICES
from planner.maps import load_map_info, map_path

ROOT = Path(__file__).resolve().parents[1]
GEB079 = ROOT / ".." / "shared" / "data" / "octomap" / "geb079.bt"
# geb079 (Freiburg building 079, OctoMap 0.08 m; radius 0.2 m as in the README): along the
# corridor, and from the corridor into a room.
GEB079_QUERIES = (((-2.96, -0.05, 1.0), (25.0, 0.0, 1.0)),
                  ((-2.96, -0.05, 1.0), (-5.0, -5.0, 1.0)))


def runs(names: list[str], query: int) -> list[tuple[str, object, tuple, dict]]:
    """(label, source, (start, goal), explore keywords) per map; geb079 only when present."""
    out = []
    for name in names:
        if name == "geb079":
            if not GEB079.is_file():
                print(f"skipping geb079: {GEB079} not found", file=sys.stderr)
                continue
            for i, q in enumerate(GEB079_QUERIES):
                out.append((f"geb079 q{i}", GEB079, q,
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
    p.add_argument("--query", type=int, default=0, help="bundled map query index (0)")
    p.add_argument("--sensor-range", type=float, default=4.0, help="m (4.0)")
    p.add_argument("--resolution", type=float, default=3.0, help="degrees between rays (3)")
    p.add_argument("--vertical", type=float, default=30.0, help="+- vertical fov, deg (30)")
    p.add_argument("--neighbors", default="full")
    p.add_argument("--plots", type=Path, help="folder for one summary PNG per run")
    p.add_argument("--near-median", type=int, default=0, metavar="N",
                   help="also list the N replans either side of each run's median time "
                        "ratio: which replan, whether it kept the path, both times")
    a = p.parse_args(argv)
    head = (f"{'map':<12} {'lattice':<7} {'status':<11} {'moves':>5} {'dist m':>7} "
            f"{'replans':>7} {'D*chk':>6} {'A*chk':>6} {'D*ms':>6} {'A*ms':>6} "
            f"{'med t':>6} {'med wall':>8} {'med chk':>7} {'kept':>5} {'rep t':>6} "
            f"{'1st t':>6} {'tot t':>6} {'tot chk':>7} "
            f"{'mism':>4} {'cont':>4} {'run s':>6}")
    print(f"sensor {a.sensor_range} m, fov 360 x +-{a.vertical} deg every {a.resolution} "
          f"deg, {a.neighbors} moves; ratios = D* Lite (repair + search) / A* from scratch")
    print(head)
    bad = 0
    for label, src, (start, goal), kw in runs(a.maps, a.query):
        for lat in a.lattices:
            t0 = time.perf_counter()
            r = explore(src, start, goal, lattice=lat, sensor_range=a.sensor_range,
                        fov=(360.0, a.vertical), resolution=a.resolution,
                        neighbors=a.neighbors, **kw)
            secs = time.perf_counter() - t0
            q = r.ratios()
            k = slice(1, None) if r.replans > 1 else slice(None)
            med = [float(np.median(a[k])) for a in (r.dstar_checks, r.astar_checks,
                                                     1e3 * r.dstar_seconds,
                                                     1e3 * r.astar_seconds)]
            kept = r.dstar_checks[k] == 0
            rep = (r.dstar_seconds[k] / r.astar_seconds[k])[~kept]
            rep_t = float(np.median(rep)) if len(rep) else float("nan")
            print(f"{label:<12} {lat:<7} {r.status:<11} {len(r.trajectory) - 1:>5} "
                  f"{r.distance:>7.2f} {r.replans:>7} {med[0]:>6.0f} {med[1]:>6.0f} "
                  f"{med[2]:>6.3f} {med[3]:>6.3f} {q['median_time_ratio']:>6.3f} "
                  f"{q['median_wall_ratio']:>8.3f} "
                  f"{q['median_checks_ratio']:>7.4f} {int(kept.sum()):>5} {rep_t:>6.3f} "
                  f"{r.dstar_seconds[0] / r.astar_seconds[0]:>6.2f} "
                  f"{q['total_time_ratio']:>6.3f} "
                  f"{q['total_checks_ratio']:>7.4f} {r.mismatches:>4} {r.contacts:>4} "
                  f"{secs:>6.1f}", flush=True)
            if a.near_median and r.replans > 1:
                _near_median(r, kept, a.near_median)
            bad += r.mismatches
            if a.plots:
                r.plot(a.plots / f"explore_{label.replace(' ', '_')}_{lat}.png")
    if bad:
        print(f"FAIL: {bad} replans whose D* Lite cost differs from A*", file=sys.stderr)
    return 1 if bad else 0


def _near_median(r, kept: np.ndarray, n: int) -> None:
    """The ``n`` replans (after the first) either side of the median time ratio of the
    exploration ``r``: replan number, kept (no repair), cells the scan changed, which search
    ran first after the map update (it finds the caches cold), D* Lite and A* engine times
    (us)."""
    d, t = r.dstar_seconds[1:], r.astar_seconds[1:]
    order = np.argsort(d / t, kind="stable")
    mid = len(order) // 2
    for i in order[max(0, mid - n):mid + n]:
        first = "A*" if (i + 1) % 2 else "D*"  # explore(): D* Lite first on even replans
        print(f"    replan {i + 1:>4}  {'kept' if kept[i] else 'repair':<6} "
              f"changed {r.changed[i + 1]:>5}  {first} first  D* {d[i] * 1e6:8.1f} us"
              f"  A* {t[i] * 1e6:8.1f} us  ratio {d[i] / t[i]:6.3f}")


if __name__ == "__main__":
    np.set_printoptions(precision=4)
    sys.exit(main())
