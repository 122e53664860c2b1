"""Shortcutting's rule against the forward scan it replaced: the delivered path's length and
the cells looked up to smooth it, per lattice, on the queries of ``lattice_sight.py``.

Usage::

    python benchmarks/smoothing_rule.py                 # office
    python benchmarks/smoothing_rule.py --maps office two_storey warehouse forest geb079
    python benchmarks/smoothing_rule.py --smoke         # tiny sizes, seconds

Per map, the queries of ``lattice_sight.py``'s planning table (``--queries`` of them, the
same seed: start/goal points solved on every lattice); per lattice and query the A* path,
then smoothed two ways:

* ``rule``: :func:`planner.search.shortcut`, what ``plan(..., shortcut=True)`` applies
  (gallop, bisect, one drop pass); its lookups as counted in ``world.cell_checks``;
* ``scan``: the forward scan shortcutting used before, written here in Python over
  :func:`planner.search.sight_many` (the same sight walk): from each kept cell i, test sight
  to i + 2, i + 3, ... one line each and keep the cell before the first out of sight; its
  lookups summed.

Each is joined to the query's start and goal points as ``plan()`` joins them
(:func:`planner.planning.joined`) and measured by :func:`planner.path.path_length`: the
delivered path. Printed per lattice: the queries where the rule's delivered path is
shorter / equal / longer than the scan's (relative tolerance 1e-9), the extreme relative
differences, the lengths summed, the lookups summed, and how many delivered paths are
longer than the A* path joined the same way (unsmoothed); a ``ratio`` line per lattice for
the lookups (rule / scan, per query). Cells looked up, not time: the scan runs in Python
(``lattice_sight.py`` times what a user pays).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import harness  # noqa: E402  (the sibling modules)
import lattice_sight  # noqa: E402

from planner import search as S  # noqa: E402
from planner.path import path_length  # noqa: E402
from planner.planning import joined  # noqa: E402
from planner.world import World  # noqa: E402

TOL = 1e-9  # relative: lengths closer than this count as equal


def scan(world: World, cells: np.ndarray) -> tuple[np.ndarray, int]:
    """The forward scan: the kept cells of ``cells`` (K, 3) and the cells looked up."""
    n, keep, looked, i = len(cells), [0], 0, 0
    while i < n - 1:
        j = i + 1
        while j + 1 < n:
            r = S.sight_many(world, cells[i:i + 1], cells[j + 1:j + 2])
            looked += int(r.lookups[0])
            if not r.free[0]:
                break
            j += 1
        keep.append(j)
        i = j
    return cells[keep], looked


def delivered(world: World, cells: np.ndarray, ends: np.ndarray) -> float:
    """Length (m) of the path ``plan()`` delivers through the centres of ``cells`` from
    ``ends[0]`` to ``ends[1]`` ((2, 3) m, the world's frame)."""
    return path_length(joined(world, np.concatenate(
        [ends[:1], world.lattice.to_world(cells), ends[1:]])), 0.0)


def compare(map_name: str, n: int, data: Path) -> None:
    worlds = lattice_sight.map_worlds(map_name, data)
    pts = lattice_sight.query_points(worlds, n)
    print(f"\n{map_name}: {len(pts)} queries; delivered length of the rule vs the scan "
          f"(rel. tolerance {TOL:g}), lookups to smooth")
    print(f"{'lattice':8s} {'shorter':>7s} {'equal':>5s} {'longer':>6s} {'min diff':>9s} "
          f"{'max diff':>9s} {'rule m':>8s} {'scan m':>8s} {'rule look':>9s} "
          f"{'scan look':>9s} {'> A*':>4s}")
    looks = {}
    for name, w in worlds.items():
        rule_len, scan_len, rule_look, scan_look, over = [], [], [], [], 0
        for ends in pts:
            q = w.lattice.quantize(ends)
            r = S.search(w, q[0], q[1])
            if not r.found:
                continue
            before = w.cell_checks
            cut = S.shortcut(w, r.cells)
            rule_look.append(w.cell_checks - before)
            ref, looked = scan(w, r.cells)
            scan_look.append(looked)
            rule_len.append(delivered(w, cut, ends))
            scan_len.append(delivered(w, ref, ends))
            over += rule_len[-1] > delivered(w, r.cells, ends) * (1 + TOL)
        a, b = np.array(rule_len), np.array(scan_len)
        d = a / b - 1
        print(f"{name:8s} {(d < -TOL).sum():7d} {(abs(d) <= TOL).sum():5d} {(d > TOL).sum():6d} "
              f"{d.min():+9.2e} {d.max():+9.2e} {a.sum():8.2f} {b.sum():8.2f} "
              f"{sum(rule_look):9d} {sum(scan_look):9d} {over:4d}")
        looks[name] = np.array(rule_look, float), np.array(scan_look, float)
    for name, (x, y) in looks.items():
        print(harness.ratio_line(f"smoothing lookups rule/scan {name}, {map_name}", x, y,
                                 note="per query"))


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    harness.add_arguments(ap, repeat=None, data=True)
    ap.add_argument("--maps", nargs="*", default=["office"],
                    help="maps (bundled names or geb079)")
    ap.add_argument("--queries", type=int, default=8, help="queries per map")
    a = ap.parse_args(argv)
    if a.smoke:
        a.queries = 2
        a.maps = [m for m in a.maps if m != "geb079"][:1] or ["office"]
    with harness.session("shortcutting's rule against the forward scan: delivered length "
                         "and lookups", smoke=a.smoke):
        lattice_sight.each_map(a.maps, a.data, lambda m: compare(m, a.queries, a.data))
    return 0


if __name__ == "__main__":
    sys.exit(main())
