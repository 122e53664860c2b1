"""Why a room-pair trial of ``planner match-experiment`` fails: search or objective?

Run: ``python benchmarks/match_room_check.py [--trial K] [--lattice hex] [--seed 0]
[--data ../shared/data] [--smoke]``.
Replays trial K of the room pair (pair index 4 in the default source order velodyne,
3 x geb079, room) exactly as the experiment draws it, matches B->A (room_scan1 onto
room_scan2) on ``--lattice`` and on cubic, and scores both end poses on every lattice: the
fraction of room_scan1's points in occupied room_scan2 cells, per level. If the failed
pose scores higher than the converged one on every lattice, the failure is the point-count
objective's (a wrong global maximum), not the lattice's or the search's.

The ``ratio`` lines: the ``--lattice`` end pose's score over the cubic end pose's, paired
by lattice and level (below 1: the end pose ``--lattice`` stopped at scores lower, so
its failure is the search's), and per level over the lattices; and the two matches' CPU
times (this thread's, ``benchmarks/harness.py``; one match each, after an untimed one).

``--smoke``: the same trial; one level scored on cubic only.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import harness  # noqa: E402  (the sibling module)

from planner.lattice import NAMED_LATTICES, Lattice  # noqa: E402
from planner.match import MultiResVoxelList, match, pose_error  # noqa: E402
from planner.match.experiment_pairs import draw_trial, room_pair  # noqa: E402


def main(argv=None) -> int:
    ap = harness.add_arguments(argparse.ArgumentParser(description=__doc__.split("\n")[0]),
                               repeat=None, data=True)
    ap.add_argument("--trial", type=int, default=2)
    ap.add_argument("--lattice", default="hex", choices=NAMED_LATTICES)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--pair-index", type=int, default=4)
    a = ap.parse_args(argv)
    with harness.session("match_room_check: search or objective on a failed room trial",
                         smoke=a.smoke):
        if not (a.data / "pcl_room").is_dir():
            return harness.skip(f"no room scans in {a.data / 'pcl_room'}")
        check(a, ["cubic"] if a.smoke else list(NAMED_LATTICES), 1 if a.smoke else 4)
    return 0


def check(a: argparse.Namespace, scored_on: list[str], levels: int) -> None:
    """The end poses, their scores and the ratio lines (module docstring)."""
    pair = room_pair(a.data)
    t = draw_trial(a.seed, a.pair_index, a.trial, 0.5, 10.0)
    r = t.rotation[:3, :3]
    src, ref = pair.source @ r.T, pair.reference @ r.T
    centre = t.rotation @ pair.transform @ t.rotation.T
    start = np.linalg.inv(t.error @ centre)  # B->A starts from the inverse of A->B's start
    ends, secs = {}, {}
    for name in dict.fromkeys([a.lattice, "cubic"]):
        match(ref, src, lattice=name, init=start)  # untimed: compiles, fills the caches
        ends[name], secs[name] = harness.cpu_result(
            lambda name=name: match(ref, src, lattice=name, init=start).transform)
        pos, rot = pose_error(ends[name], np.linalg.inv(centre))
        print(f"B->A on {name:5s}: {pos:.3f} m, {rot:.2f} deg from the centre's inverse")
    frac = {}  # (scored on, end) -> fraction per level
    for name in scored_on:
        mr = MultiResVoxelList(src, Lattice.named(name, 0.001), levels)
        row = []
        for end, m in ends.items():
            moved = ref @ m[:3, :3].T + m[:3, 3]
            frac[name, end] = [float(mr.contains(moved, k).mean()) for k in range(mr.levels)]
            row.append(f"{end} end " + " ".join(f"{f:.3f}" for f in frac[name, end]))
        print(f"scored on {name:5s} (levels fine..coarse): " + " | ".join(row))
    if a.lattice == "cubic":
        print(harness.skip("--lattice cubic: no second end pose to compare"))
        return
    mine = np.array([frac[n, a.lattice] for n in scored_on])  # (lattices, levels)
    cubic = np.array([frac[n, "cubic"] for n in scored_on])
    print()
    print(harness.ratio_line(f"{a.lattice} end/cubic end score", mine.ravel(), cubic.ravel(),
                             note="fraction in occupied cells, paired by lattice and level"))
    for k in range(levels):
        print(harness.ratio_line(f"{a.lattice} end/cubic end score at level {k}",
                                 mine[:, k], cubic[:, k], note="paired by lattice"))
    print(harness.single_ratio(f"{a.lattice} match/cubic match CPU", secs[a.lattice],
                               secs["cubic"], note="one match each"))


if __name__ == "__main__":
    sys.exit(main())
