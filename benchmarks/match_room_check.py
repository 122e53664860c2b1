"""Why a room-pair trial of ``planner match-experiment`` fails: search or objective?

Run: ``python benchmarks/match_room_check.py [--trial K] [--lattice hex] [--seed 0]
[--data ../shared/data]``.
Replays trial K of the room pair (pair index 4 in the default source order velodyne,
3 x geb079, room) exactly as the experiment draws it, matches B->A (room_scan1 onto
room_scan2) on ``--lattice`` and on cubic, and scores both end poses on every lattice: the
fraction of room_scan1's points in occupied room_scan2 cells, per level. If the failed
pose scores higher than the converged one on every lattice, the failure is the point-count
objective's (a wrong global maximum), not the lattice's or the search's.
"""

import argparse
from pathlib import Path

import numpy as np

from planner.lattice import NAMED_LATTICES, Lattice
from planner.match import MultiResVoxelList, match, pose_error
from planner.match.experiment_pairs import draw_trial, room_pair

DATA = Path(__file__).resolve().parents[1] / ".." / "shared" / "data"


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--trial", type=int, default=2)
    ap.add_argument("--lattice", default="hex", choices=NAMED_LATTICES)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--pair-index", type=int, default=4)
    ap.add_argument("--data", type=Path, default=DATA)
    a = ap.parse_args()
    pair = room_pair(a.data)
    t = draw_trial(a.seed, a.pair_index, a.trial, 0.5, 10.0)
    r = t.rotation[:3, :3]
    src, ref = pair.source @ r.T, pair.reference @ r.T
    centre = t.rotation @ pair.transform @ t.rotation.T
    start = np.linalg.inv(t.error @ centre)  # B->A starts from the inverse of A->B's start
    ends = {}
    for name in dict.fromkeys([a.lattice, "cubic"]):
        res = match(ref, src, lattice=name, init=start)
        ends[name] = res.transform
        pos, rot = pose_error(res.transform, np.linalg.inv(centre))
        print(f"B->A on {name:5s}: {pos:.3f} m, {rot:.2f} deg from the centre's inverse")
    for name in NAMED_LATTICES:
        mr = MultiResVoxelList(src, Lattice.named(name, 0.001), 4)
        row = []
        for end, m in ends.items():
            moved = ref @ m[:3, :3].T + m[:3, 3]
            frac = [float(mr.contains(moved, k).mean()) for k in range(mr.levels)]
            row.append(f"{end} end " + " ".join(f"{f:.3f}" for f in frac))
        print(f"scored on {name:5s} (levels fine..coarse): " + " | ".join(row))


if __name__ == "__main__":
    main()
