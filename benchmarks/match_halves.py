"""One Velodyne sweep split into two disjoint halves, matched onto each other (truth: the
identity): does the point-count objective peak at the truth when the two scans never share
a point?

Run: ``python benchmarks/match_halves.py [--data ../shared/data] [--trials 6]``.

Three splits of ``251370668.pcd``: a random half of the points against the other half;
even against odd point indices (alternate firings); and alternate elevation rings (the
elevation angle rounded to 1.33 degree bands, even bands against odd: the two halves then
sample different circles on the ground, so no surface is seen by both at the same places).
Each from the same ``--trials`` initial errors (up to 0.5 m, 10 degrees), on cubic and FCC
with and without the final refinement, and with the GICP anchor (the ``match`` extra).
Prints success (< 5 cm and < 1 degree) and the median errors.
"""

import argparse
from pathlib import Path

import numpy as np

from planner.io import load_points
from planner.match import anchor, match, pose_error
from planner.match.experiment_pairs import draw_trial

DATA = Path(__file__).resolve().parents[1] / ".." / "shared" / "data"


def splits(pts: np.ndarray) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    perm = np.random.default_rng(0).permutation(len(pts))
    el = np.degrees(np.arctan2(pts[:, 2], np.hypot(pts[:, 0], pts[:, 1])))
    band = np.round(el / 1.33).astype(int) % 2
    return {"random halves": (pts[perm[::2]], pts[perm[1::2]]),
            "even/odd index": (pts[::2], pts[1::2]),
            "alternate rings": (pts[band == 0], pts[band == 1])}


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--data", type=Path, default=DATA)
    ap.add_argument("--trials", type=int, default=6)
    a = ap.parse_args()
    pts = load_points(a.data / "velodyne" / "251370668.pcd")
    inits = [draw_trial(0, 9, k, 0.5, 10.0).error for k in range(a.trials)]
    methods = [("cubic", False), ("cubic", True), ("fcc", False), ("fcc", True)]
    if anchor.available():
        methods.append(("gicp", None))
    print(f"{'split':16s} {'method':18s} {'success':>7s} {'median mm':>9s} {'median deg':>10s}")
    for split, (src, ref) in splits(pts).items():
        for name, refine in methods:
            errs = []
            for init in inits:
                if refine is None:
                    t, _ = anchor.register(name, src, ref, init)
                else:
                    t = match(src, ref, lattice=name, init=init, refine=refine).transform
                errs.append(pose_error(t, np.eye(4)))
            e = np.array(errs)
            ok = ((e[:, 0] < 0.05) & (e[:, 1] < 1.0)).mean()
            label = name if refine is None else f"{name} {'refined' if refine else 'discrete'}"
            print(f"{split:16s} {label:18s} {100 * ok:6.0f}% {1e3 * np.median(e[:, 0]):9.1f} "
                  f"{np.median(e[:, 1]):10.3f}", flush=True)


if __name__ == "__main__":
    main()
