"""Scan-matching speed: the scoring kernel's cost per point lookup on every lattice against a
dedicated cubic rounding, and whole matches against the GICP anchors.

Run: ``python benchmarks/match_speed.py [--data ../shared/data] [--inits 6] [--repeat 3]``.

1. **Per lookup** (Velodyne reference, 0.001 m^3 finest cells): the source's points (all
   64,685) scored at 64 poses near the truth on level 0 of each lattice by the matcher's
   kernel (coset rounding, :mod:`planner.lattice.cosets`), by the generic exact quantizer's
   kernel (``score_poses``), and, as the baseline, by a kernel written for the cubic
   lattice only (``x * (1/side)`` rounded, packed, looked up in the same hash set). Every
   kernel is compiled by one untimed call; the best of ``--repeat`` CPU times
   (``time.process_time``) divided by points x poses, in one process, with the ratio to
   the dedicated cubic kernel. The three agree on every score (checked).
2. **Whole matches** (the Velodyne pair against ``relative.txt`` and the simulated geb079
   pairs, exact truth): the same ``--inits`` initial errors (up to 0.5 m, 10 degrees) for
   every method; lattices (4 levels, reference build included) and the anchors of
   :mod:`planner.match.anchor` (preprocessing included); median CPU s per match, its ratio
   to GICP's, success (< 5 cm and < 1 degree) and median errors.
"""

import argparse
import time
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from planner._numba import njit_cached
from planner.lattice import NAMED_LATTICES, Lattice
from planner.match import MultiResVoxelList, _kernels, anchor, match, pose_error
from planner.match.experiment_pairs import draw_trial, geb079_pairs, velodyne_pair
from planner.occupancy.keys import in_key_set, pack3

DATA = Path(__file__).resolve().parents[1] / ".." / "shared" / "data"


@njit_cached(nogil=True)
def score_cubic(pts, wts, rots, trans, inv_side, table, bits, out):  # pragma: no cover
    """The baseline: the score on the cubic lattice of side 1/inv_side, rounding written
    for it (no quantizer tables)."""
    mask = (1 << bits) - 1
    for p in range(rots.shape[0]):
        r = rots[p]
        tx, ty, tz = trans[p, 0], trans[p, 1], trans[p, 2]
        s = 0.0
        for i in range(pts.shape[0]):
            a0, a1, a2 = pts[i, 0], pts[i, 1], pts[i, 2]
            w0 = np.int64(np.rint((r[0, 0] * a0 + r[0, 1] * a1 + r[0, 2] * a2 + tx) * inv_side))
            w1 = np.int64(np.rint((r[1, 0] * a0 + r[1, 1] * a1 + r[1, 2] * a2 + ty) * inv_side))
            w2 = np.int64(np.rint((r[2, 0] * a0 + r[2, 1] * a1 + r[2, 2] * a2 + tz) * inv_side))
            if in_key_set(table, mask, pack3(w0, w1, w2)):
                s += wts[i]
        out[p] = s


def _best(kernel, args: tuple, repeat: int) -> float:
    kernel(*args)  # compile / warm
    best = np.inf
    for _ in range(repeat):
        t0 = time.process_time()
        kernel(*args)
        best = min(best, time.process_time() - t0)
    return best


def per_lookup(data: Path, repeat: int) -> None:
    pair = velodyne_pair(data)
    rng = np.random.default_rng(0)
    rots = Rotation.from_rotvec(rng.normal(scale=0.01, size=(64, 3))).as_matrix() \
        @ pair.transform[:3, :3]
    trans = pair.transform[:3, 3] + rng.normal(scale=0.02, size=(64, 3))
    pts, wts = pair.source, np.ones(len(pair.source))
    n = len(rots) * len(pts)

    cubic = MultiResVoxelList(pair.reference, Lattice.named("cubic", 0.001), 1).level(0)
    inv = 1.0 / cubic.side
    base_out = np.empty(len(rots))
    base = _best(score_cubic, (pts, wts, rots, trans, inv, cubic.table, cubic.bits,
                               base_out), repeat) / n
    print(f"Per lookup: {len(pts)} points x {len(rots)} poses, best of {repeat} CPU times")
    print(f"  dedicated cubic rounding (baseline)  {1e9 * base:5.1f} ns")
    print(f"  {'lattice':7s} {'cosets':>6s} {'matcher ns':>10s} {'x cubic':>8s} "
          f"{'generic ns':>10s} {'x cubic':>8s}")
    for name in NAMED_LATTICES:
        lv = MultiResVoxelList(pair.reference, Lattice.named(name, 0.001), 1).level(0)
        cq = lv.cosets
        fr, ft = np.ascontiguousarray(cq.frame @ rots), np.ascontiguousarray(trans @ cq.frame.T)
        fast_out, gen_out = np.empty(len(rots)), np.empty(len(rots))
        fast = _best(_kernels.score_poses_cosets, (
            pts, wts, fr, ft, cq.inv_sides, cq.sides, cq.shifts, cq.index_basis,
            cq.index_offsets, lv.table, lv.bits, fast_out), repeat) / n
        gen = _best(_kernels.score_poses, (pts, wts, rots, trans, *lv.tables, lv.table,
                                           lv.bits, gen_out), repeat) / n
        assert np.array_equal(fast_out, gen_out), name
        if name == "cubic":
            assert np.array_equal(fast_out, base_out)
        print(f"  {name:7s} {cq.cosets:6d} {1e9 * fast:10.1f} {fast / base:8.2f} "
              f"{1e9 * gen:10.1f} {gen / base:8.2f}")


def _lattice_run(src, ref, name, init):
    t0 = time.process_time()
    res = match(src, MultiResVoxelList(ref, Lattice.named(name, 0.001), 4), init=init)
    return res.transform, time.process_time() - t0


def whole_matches(data: Path, inits: int) -> None:
    pairs = [velodyne_pair(data), *geb079_pairs(data)]
    methods = [*NAMED_LATTICES, *(anchor.ANCHORS if anchor.available() else ())]
    rows = {m: [] for m in methods}
    for i, p in enumerate(pairs):
        starts = [draw_trial(0, i, k, 0.5, 10.0).error @ p.transform for k in range(inits)]
        for m in methods:
            def run(init, m=m, p=p):
                if m in NAMED_LATTICES:
                    return _lattice_run(p.source, p.reference, m, init)
                return anchor.register(m, p.source, p.reference, init)
            run(starts[0])  # untimed: compiles the kernels, fills the caches
            for s in starts:
                t, sec = run(s)
                rows[m].append((*pose_error(t, p.transform), sec, p.group))
    print(f"\nWhole matches: {len(pairs)} pairs x {inits} initial errors (<= 0.5 m, 10 deg); "
          f"median CPU s per match")
    ref = "gicp" if "gicp" in rows else methods[0]
    ref_s = {g: np.median([r[2] for r in rows[ref] if r[3] == g]) for g in
             ("velodyne", "geb079")}
    print(f"  {'method':9s} {'success':>7s} {'pos mm':>7s} {'rot deg':>7s} | "
          f"{'velodyne s':>10s} {'x ' + ref:>10s} | {'geb079 s':>8s} {'x ' + ref:>10s}")
    for m, rr in rows.items():
        a = np.array([r[:3] for r in rr])
        ok = ((a[:, 0] < 0.05) & (a[:, 1] < 1.0)).mean()
        sv = np.median([r[2] for r in rr if r[3] == "velodyne"])
        sg = np.median([r[2] for r in rr if r[3] == "geb079"])
        print(f"  {m:9s} {100 * ok:6.0f}% {1e3 * np.median(a[:, 0]):7.1f} "
              f"{np.median(a[:, 1]):7.3f} | {sv:10.3f} {sv / ref_s['velodyne']:10.1f} | "
              f"{sg:8.3f} {sg / ref_s['geb079']:10.1f}")


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--data", type=Path, default=DATA)
    ap.add_argument("--inits", type=int, default=6)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--no-matches", action="store_true", help="per-lookup costs only")
    a = ap.parse_args()
    per_lookup(a.data, a.repeat)
    if not a.no_matches:
        whole_matches(a.data, a.inits)


if __name__ == "__main__":
    main()
