"""Scan-matching speed and accuracy on the Velodyne pair, every lattice, and the ICP anchor.

Run: ``python benchmarks/match_speed.py [--inits N]``. The same random initial errors (up to
0.5 m and 10 degrees) for every lattice; each lattice is warmed up by one match first (JIT
compilation is not timed). Prints, per lattice, the reference build time and memory, the
median time per match, its ratio to the cubic lattice's, and the position / rotation errors
against ``relative.txt``; the ICP anchor (``match`` extra) when installed.
"""

import argparse
import time
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from planner.io import load_points
from planner.lattice import NAMED_LATTICES, Lattice
from planner.match import MultiResVoxelList, anchor, match, pose_error

DATA = Path(__file__).resolve().parents[1] / ".." / "shared" / "data" / "velodyne"


def initial_errors(n: int, rng: np.random.Generator) -> list[np.ndarray]:
    out = []
    for _ in range(n):
        e = np.eye(4)
        e[:3, :3] = Rotation.from_rotvec(Rotation.random(random_state=rng).as_rotvec()
                                         / np.pi * np.radians(rng.uniform(0, 10))).as_matrix()
        d = rng.normal(size=3)
        e[:3, 3] = d / np.linalg.norm(d) * rng.uniform(0, 0.5)
        out.append(e)
    return out


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--inits", type=int, default=10)
    a = ap.parse_args()
    ref = load_points(DATA / "251370668.pcd")
    src = load_points(DATA / "251371071.pcd")
    truth = np.loadtxt(DATA / "relative.txt")
    inits = [e @ truth for e in initial_errors(a.inits, np.random.default_rng(0))]
    base = None
    print(f"{len(src)} source, {len(ref)} reference points; {a.inits} initial errors")
    for name in NAMED_LATTICES:
        lat = Lattice.named(name, 0.001)
        MultiResVoxelList(ref, lat, 4)
        t0 = time.perf_counter()
        mr = MultiResVoxelList(ref, lat, 4)
        build = time.perf_counter() - t0
        match(src, mr)  # compile
        res = [match(src, mr, init=m) for m in inits]
        errs = np.array([pose_error(r.transform, truth) for r in res])
        sec = float(np.median([r.seconds for r in res]))
        base = base or sec
        ok = ((errs[:, 0] < 0.05) & (errs[:, 1] < 1.0)).mean()
        print(f"{name:6s} build {build:.3f} s {mr.nbytes / 1e6:.2f} MB | match median {sec:.3f} s"
              f" ({sec / base:.2f} x cubic) | pos err median {np.median(errs[:, 0]):.4f} m, "
              f"rot {np.median(errs[:, 1]):.3f} deg, success {ok:.2f}")
    if anchor.available():
        anchor.icp(src, ref, inits[0])
        out = [anchor.icp(src, ref, m) for m in inits]
        errs = np.array([pose_error(m, truth) for m, _ in out])
        sec = float(np.median([s for _, s in out]))
        ok = ((errs[:, 0] < 0.05) & (errs[:, 1] < 1.0)).mean()
        print(f"icp    match median {sec:.3f} s ({sec / base:.2f} x cubic) | pos err median "
              f"{np.median(errs[:, 0]):.4f} m, rot {np.median(errs[:, 1]):.3f} deg, "
              f"success {ok:.2f}")


if __name__ == "__main__":
    main()
