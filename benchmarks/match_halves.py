"""One Velodyne sweep split into two disjoint halves, matched onto each other (truth: the
identity): does the point-count objective peak at the truth when the two scans never share
a point?

Run: ``python benchmarks/match_halves.py [--data ../shared/data] [--trials 6] [--smoke]``.

Three splits of ``251370668.pcd``: a random half of the points against the other half;
even against odd point indices (alternate firings); and alternate elevation rings (the
elevation angle rounded to 1.33 degree bands, even bands against odd: the two halves then
sample different circles on the ground, so no surface is seen by both at the same places).
Each from the same ``--trials`` initial errors (up to 0.5 m, 10 degrees), on cubic and FCC
with and without the final refinement, and with the GICP anchor (the ``match`` extra).
Prints success (< 5 cm and < 1 degree) and the median errors, then ``ratio`` lines per
lattice method against GICP (against cubic discrete without the ``match`` extra), paired
by split and start: the position error (where both succeed), and the CPU time per match
(this thread's for the lattices, ``benchmarks/harness.py``; the anchor's own process CPU
report for GICP, which runs on one thread).

``--smoke``: one start per split.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import harness  # noqa: E402  (the sibling module)

from planner.io import load_points  # noqa: E402
from planner.match import anchor, match, pose_error  # noqa: E402
from planner.match.experiment_pairs import draw_trial  # noqa: E402


def splits(pts: np.ndarray) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    perm = np.random.default_rng(0).permutation(len(pts))
    el = np.degrees(np.arctan2(pts[:, 2], np.hypot(pts[:, 0], pts[:, 1])))
    band = np.round(el / 1.33).astype(int) % 2
    return {"random halves": (pts[perm[::2]], pts[perm[1::2]]),
            "even/odd index": (pts[::2], pts[1::2]),
            "alternate rings": (pts[band == 0], pts[band == 1])}


def _label(name: str, refine: bool | None) -> str:
    return name if refine is None else f"{name} {'refined' if refine else 'discrete'}"


def _run(name: str, refine: bool | None, src, ref, init) -> tuple[np.ndarray, float]:
    """The end pose and the CPU seconds of one match."""
    if refine is None:
        return anchor.register(name, src, ref, init)  # its own process CPU report
    return harness.cpu_result(
        lambda: match(src, ref, lattice=name, init=init, refine=refine).transform)


def main(argv=None) -> int:
    ap = harness.add_arguments(argparse.ArgumentParser(description=__doc__.split("\n")[0]),
                               repeat=None, data=True)
    ap.add_argument("--trials", type=int, default=6)
    a = ap.parse_args(argv)
    with harness.session("match_halves: one sweep's disjoint halves matched onto each other",
                         smoke=a.smoke):
        sweep = a.data / "velodyne" / "251370668.pcd"
        if not sweep.is_file():
            return harness.skip(f"no {sweep}")
        compare(load_points(sweep), 1 if a.smoke else a.trials)
    return 0


def compare(pts: np.ndarray, trials: int) -> None:
    """The table and the ratio lines (module docstring)."""
    inits = [draw_trial(0, 9, k, 0.5, 10.0).error for k in range(trials)]
    methods = [("cubic", False), ("cubic", True), ("fcc", False), ("fcc", True)]
    if anchor.available():
        methods.append(("gicp", None))
    halves = splits(pts)
    for name, refine in methods:  # untimed: compiles the kernels, fills the caches
        _run(name, refine, *halves["random halves"], inits[0])
    rows: dict[str, list] = {_label(*m): [] for m in methods}  # (pos m, deg, CPU s)
    print(f"{'split':16s} {'method':18s} {'success':>7s} {'median mm':>9s} {'median deg':>10s}")
    for split, (src, ref) in halves.items():
        for name, refine in methods:
            errs = []
            for init in inits:
                t, sec = _run(name, refine, src, ref, init)
                errs.append(pose_error(t, np.eye(4)))
                rows[_label(name, refine)].append((*errs[-1], sec))
            e = np.array(errs)
            ok = _success(e).mean()
            print(f"{split:16s} {_label(name, refine):18s} {100 * ok:6.0f}% "
                  f"{1e3 * np.median(e[:, 0]):9.1f} {np.median(e[:, 1]):10.3f}", flush=True)
    base = "gicp" if "gicp" in rows else "cubic discrete"
    b = np.array(rows[base])
    print()
    for label, rr in rows.items():
        if label == base:
            continue
        r = np.array(rr)
        both = _success(r) & _success(b)  # an error ratio of two failures means nothing
        print(harness.ratio_line(f"{label}/{base} position error", r[both, 0], b[both, 0],
                                 note="paired by split and start, where both succeed"))
        print(harness.ratio_line(f"{label}/{base} CPU per match", r[:, 2], b[:, 2],
                                 note="paired by split and start"))


def _success(rows: np.ndarray) -> np.ndarray:
    """(N,) bool: position error < 5 cm and rotation error < 1 degree."""
    return (rows[:, 0] < 0.05) & (rows[:, 1] < 1.0)


if __name__ == "__main__":
    sys.exit(main())
