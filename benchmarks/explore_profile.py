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

Counts only (no timing): they explain the times of ``benchmarks/explore_speed.py``.
"""

from __future__ import annotations

import argparse

import numpy as np

import planner.explore.run as ex  # the module whose globals explore() reads
from planner.maps import load_map_info, map_path
from planner.search import search
from planner.search.dstar.lite import DStarLite


def profile(name: str, lattice: str, query: int) -> dict:
    """Per-replan counts of one exploration run (the first plan apart)."""
    rows, first = [], {}
    plan, scratch = DStarLite.plan, ex._scratch_astar

    def counted_plan(self):
        lines = _rest_lines(self)  # before the plan takes the pending cells
        r = plan(self)
        kept = r.cell_checks == 0  # kept the stored path: nothing collected (a repair
        n = 0 if kept else int(self._st["collected"])  # looks the start's cell up)
        dead = int((self._nd.mask[self._sc.ss[:n]] == 0).sum()) if n else 0
        rows.append((id(self), n, dead, kept, *lines))
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
        r = ex.explore(map_path(name), q["start"], q["goal"], lattice=lattice,
                       replanner="dstar")
    finally:
        DStarLite.plan, ex._scratch_astar = plan, scratch
    # this run's planner only (not a warm-up's), its first plan apart
    c = np.array([row[1:] for row in rows if row[0] == rows[-1][0]][1:])
    rep = c[c[:, 2] == 0]  # the replans that repaired
    kept = c[c[:, 2] == 1]
    return {"replans": r.replans, "changed": np.median(r.changed[1:]),
            "kept": int(c[:, 2].sum()), "lines": _median(kept[:, 3]),
            "block_lines": _median(kept[:, 4]),
            "collected": _median(rep[:, 0]), "died": _median(rep[:, 1]),
            "dstar_first": int(r.replan_expansions[0]), **first}


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


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--map", default="office", help="bundled map name (office)")
    ap.add_argument("--lattices", nargs="+", default=["fcc"])
    ap.add_argument("--query", type=int, default=0)
    a = ap.parse_args(argv)
    print(f"{a.map} query {a.query}: medians over the replans after the first; first plan "
          "expansions of D* Lite and of A* forwards / backwards on the same map state")
    print("kept: cache lines a kept replan's check reads, cell map alone / with the block map")
    print(f"{'lattice':8s} {'replans':>7s} {'changed':>8s} {'kept':>5s} {'lines':>6s} "
          f"{'blocks':>6s} {'collected':>9s} {'died':>6s} "
          f"{'D* first':>9s} {'A* fwd':>7s} {'A* back':>8s}")
    for lat in a.lattices:
        p = profile(a.map, lat, a.query)
        print(f"{lat:8s} {p['replans']:7d} {p['changed']:8.0f} {p['kept']:5d} "
              f"{p['lines']:6.0f} {p['block_lines']:6.0f} {p['collected']:9.0f} "
              f"{p['died']:6.0f} {p['dstar_first']:9d} {p['forward']:7d} {p['backward']:8d}")


if __name__ == "__main__":
    main()
