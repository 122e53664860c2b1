"""Where a D* Lite replan's work goes while exploring: per replan, the scan's changed cells,
how many replans kept the stored path (:mod:`planner.search.dstar.rest`) and the cache
lines their check read, and over the
others the cached nodes whose stencil holds a changed cell (collected and repaired, the
kept scans' cells included), how many of those died
(their own cell blocked), and the first plan's expansions against A* forwards and
backwards on the same map state.

Usage::

    python benchmarks/explore_profile.py                    # office, FCC
    python benchmarks/explore_profile.py --lattices cubic fcc
    python benchmarks/explore_profile.py --smoke              # office, cubic, coarse sensor

Counts only (no timing): they explain the times of ``benchmarks/explore_speed.py``. The
counts are read after each :meth:`DStarLite.plan` (wrapped for the run) from the
planner's profiling counters (:attr:`DStarLite.last_repair`,
:meth:`DStarLite.pending_check_lines`). On the benchmark harness (``benchmarks/harness.py``):
its header (machine, load, versions, commit), and per lattice two ``ratio`` lines: the
first plan's expansions, D* Lite / A* forwards on the same map state, and the cache lines
a kept replan's check reads, with the block map / the cell map alone (medians).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import harness  # noqa: E402  (the sibling module)

from planner.explore import explore  # noqa: E402
from planner.maps import load_map_info, map_path  # noqa: E402
from planner.search import search  # noqa: E402
from planner.search.dstar.lite import DStarLite  # noqa: E402

NEIGHBORS = "full"  # the explorer's default move set


def profile(name: str, lattice: str, query: int, resolution: float = 3.0) -> dict:
    """Per-replan counts of one exploration run (the first plan apart); ``resolution``:
    degrees between the sensor's rays."""
    rows, first, planners = [], {}, []  # planners: kept alive, so no id is reused
    plan = DStarLite.plan

    def counted_plan(self):
        lines = self.pending_check_lines()  # before the plan takes the pending cells
        if not any(x is self for x in planners):  # its first plan: A* backwards
            planners.append(self)
            back = search(self.world, self.goal, self.start, method="astar",
                          neighbors=NEIGHBORS)
            first["backward"] = back.expansions  # the explorer's planner's last
        r = plan(self)
        kept = r.cell_checks == 0  # kept the stored path (a repair looks the start's cell up)
        rep = self.last_repair
        rows.append((id(self), rep.collected, rep.died, kept, lines.cell_map, lines.block_map))
        return r

    DStarLite.plan = counted_plan
    try:
        q = load_map_info(name)["queries"][query]
        r = explore(map_path(name), q["start"], q["goal"], lattice=lattice,
                    replanner="dstar", resolution=resolution, neighbors=NEIGHBORS)
    finally:
        DStarLite.plan = plan
    # this run's planner only (not a warm-up's), its first plan apart
    c = np.array([row[1:] for row in rows if row[0] == rows[-1][0]][1:])
    rep = c[c[:, 2] == 0]  # the replans that repaired
    kept = c[c[:, 2] == 1]
    return {"replans": r.replans, "changed": np.median(r.changed[1:]),
            "kept": int(c[:, 2].sum()), "lines": _median(kept[:, 3]),
            "block_lines": _median(kept[:, 4]),
            "collected": _median(rep[:, 0]), "died": _median(rep[:, 1]),
            "dstar_first": int(r.replan_expansions[0]),
            "forward": int(r.astar_expansions[0]), **first}


def _median(x: np.ndarray) -> float:
    return float(np.median(x)) if len(x) else float("nan")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--map", default="office", help="bundled map name (office)")
    ap.add_argument("--lattices", nargs="+", default=["fcc"])
    ap.add_argument("--query", type=int, default=0)
    ap.add_argument("--resolution", type=float, default=3.0,
                    help="degrees between the sensor's rays (3, the explorer's default)")
    harness.add_arguments(ap, repeat=None)
    a = ap.parse_args(argv)
    if a.smoke:  # one short run: cubic, a coarse sensor
        a.lattices, a.resolution = ["cubic"], 6.0
    with harness.session("D* Lite while exploring: what a replan touches (counts)",
                         smoke=a.smoke):
        print(f"{a.map} query {a.query}: medians over the replans after the first; first "
              "plan expansions of D* Lite and of A* forwards / backwards on the same map "
              "state")
        print("kept: cache lines a kept replan's check reads, cell map alone / with the "
              "block map")
        print(f"{'lattice':8s} {'replans':>7s} {'changed':>8s} {'kept':>5s} {'lines':>6s} "
              f"{'blocks':>6s} {'collected':>9s} {'died':>6s} "
              f"{'D* first':>9s} {'A* fwd':>7s} {'A* back':>8s}")
        ratios = []
        for lat in a.lattices:
            p = profile(a.map, lat, a.query, a.resolution)
            print(f"{lat:8s} {p['replans']:7d} {p['changed']:8.0f} {p['kept']:5d} "
                  f"{p['lines']:6.0f} {p['block_lines']:6.0f} {p['collected']:9.0f} "
                  f"{p['died']:6.0f} {p['dstar_first']:9d} {p['forward']:7d} "
                  f"{p['backward']:8d}", flush=True)
            ratios += [harness.single_ratio(f"D* first/A* forwards expansions {lat}",
                                            p["dstar_first"], p["forward"],
                                            note="the first plan, same map state"),
                       harness.single_ratio(f"kept-check lines block map/cell map {lat}",
                                            p["block_lines"], p["lines"],
                                            note="medians over the kept replans")]
        for line in ratios:
            print(line)
    return 0


if __name__ == "__main__":
    sys.exit(main())
