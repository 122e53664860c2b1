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
counts are read from the planner's state after each :meth:`DStarLite.plan` (wrapped for
the run): what a replan collected and which rest-map lines its check reads are internal
to D* Lite, with no public counter. On the benchmark harness (``benchmarks/harness.py``):
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
        lines = _rest_lines(self)  # before the plan takes the pending cells
        if not any(x is self for x in planners):  # its first plan: A* backwards
            planners.append(self)
            back = search(self.world, self.goal, self.start, method="astar",
                          neighbors=NEIGHBORS)
            first["backward"] = back.expansions  # the explorer's planner's last
        r = plan(self)
        kept = r.cell_checks == 0  # kept the stored path: nothing collected (a repair
        n = 0 if kept else int(self._st["collected"])  # looks the start's cell up)
        dead = int((self._nd.mask[self._sc.ss[:n]] == 0).sum()) if n else 0
        rows.append((id(self), n, dead, kept, *lines))
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


def _rest_lines(planner: DStarLite) -> tuple[int, int]:
    """Cache lines (64 bytes) a kept replan's check of the pending cells reads: of the
    per-cell rest map alone, and of the 4x4x4-block map plus the cell map's lines of the
    cells whose block is marked (:mod:`planner.search.dstar.rest`)."""
    pend = [c for c, _ in planner._pending if len(c)]
    if not pend:
        return 0, 0
    bx = planner._bx
    d = bx.dims
    a = np.concatenate(pend) - bx.lo
    a = a[((a >= 0) & (a < d)).all(axis=1)]
    k = (a[:, 0] * d[1] + a[:, 1]) * d[2] + a[:, 2]
    q = ((a[:, 0] >> 2) * ((d[1] + 3) >> 2) + (a[:, 1] >> 2)) * ((d[2] + 3) >> 2) + (a[:, 2] >> 2)
    marked = ((bx.rest_blocks[q >> 3] >> (q & 7)) & 1).astype(bool)
    return (len(np.unique(k >> 9)),  # 512 bits a line
            len(np.unique(q >> 9)) + len(np.unique(k[marked] >> 9)))


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
