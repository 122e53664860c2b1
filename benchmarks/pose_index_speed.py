"""PoseIndex query and add times from 1e3 to 1e6 stored poses, against scipy's cKDTree.

Run: ``python benchmarks/pose_index_speed.py [--sizes 1000,10000,100000,1000000]
[--queries 20000] [--lattice fcc] [--smoke]``.

Radius r = 0.5 m. Two densities: **uniform**, poses uniform in a cube whose volume grows
with their number (one pose per 8 m^3: constant density), and **piled**, poses uniform in
a fixed 10 m cube (density grows 1000-fold from 1e3 to 1e6). Queries are uniform in the
same cube. Per size: the CPU time per query of ``PoseIndex.near`` (one batch call) and of
``cKDTree.query(k=1, distance_upper_bound=r)`` on the same poses (tree built untimed), the
ratio to the 1e3 row; the CPU time per pose of building the index in 1,000 ``add`` calls
(every doubling of its arrays included: the amortised cost); and the mean and the largest
of 1,000 single-pose ``add`` calls (500 at 1e3) into the index holding that many poses
(Python's call overhead included; the largest is the call that doubled the arrays, if one
did). cKDTree
has no add: its build time over the poses is shown instead. Answers are checked equal to
the tree's on every query. CPU times are this thread's (``benchmarks/harness.py``); the
``ratio`` line per density pairs ``near`` with the tree's query, size by size.

``--smoke``: 1,000 and 4,000 poses, 2,000 queries.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
from scipy.spatial import cKDTree

sys.path.insert(0, str(Path(__file__).resolve().parent))
import harness  # noqa: E402  (the sibling module)

from planner.match import PoseIndex  # noqa: E402

R = 0.5
_cpu = harness.cpu_result  # (result, thread CPU seconds)


def run(kind: str, sizes: list[int], n_queries: int, lattice: str) -> None:
    print(f"\n{kind}: r = {R} m, {n_queries} queries, {lattice} cells")
    print(f"{'poses':>9s} {'near us':>8s} {'x 1e3':>6s} {'kd us':>7s} {'x 1e3':>6s} "
          f"{'near/kd':>7s} {'build us/pose':>13s} {'add us':>7s} {'max ms':>7s} "
          f"{'kd build s':>10s} {'true %':>6s}")
    rng = np.random.default_rng(0)
    first = None
    near_all, kd_all = [], []
    for n in sizes:
        side = (8.0 * n) ** (1 / 3) if kind == "uniform" else 10.0
        poses = rng.uniform(0, side, (n, 3))
        queries = rng.uniform(0, side, (n_queries, 3))
        idx = PoseIndex(R, lattice=lattice)
        for p in np.array_split(poses[:2000], 200):  # compiled kernels loaded (growth
            idx.add(p)  # included) before any timing
        idx.near(queries[:10])
        idx = PoseIndex(R, lattice=lattice)
        k = min(1000, n // 2)  # single adds at the end (half the poses at 1e3)
        body, extra = poses[:-k], poses[-k:]
        _, bulk_s = _cpu(lambda: [idx.add(p) for p in np.array_split(body, 1000)])  # noqa: B023
        single = [_cpu(lambda: idx.add(p))[1] for p in extra]  # noqa: B023 - called at once
        add_s, add_max = sum(single), max(single)
        got, near_s = _cpu(lambda: idx.near(queries))  # noqa: B023
        tree, build_s = _cpu(lambda: cKDTree(poses))  # noqa: B023
        (dist, _), kd_s = _cpu(lambda: tree.query(queries, k=1,  # noqa: B023
                                                  distance_upper_bound=R))
        want = dist <= R
        assert np.array_equal(got, want), f"{kind} {n}: answers differ from the tree's"
        q_us, kd_us = 1e6 * near_s / n_queries, 1e6 * kd_s / n_queries
        first = first or (q_us, kd_us)
        near_all.append(near_s)
        kd_all.append(kd_s)
        print(f"{n:9d} {q_us:8.2f} {q_us / first[0]:6.2f} {kd_us:7.2f} {kd_us / first[1]:6.2f} "
              f"{q_us / kd_us:7.2f} {1e6 * bulk_s / len(body):13.3f} "
              f"{1e6 * add_s / len(extra):7.2f} {1e3 * add_max:7.2f} {build_s:10.3f} "
              f"{100 * want.mean():6.1f}")
    print(harness.ratio_line(f"PoseIndex.near/cKDTree.query CPU per query ({kind})",
                             near_all, kd_all, note=f"paired by size, {len(sizes)} sizes"))


def main(argv=None) -> int:
    ap = harness.add_arguments(argparse.ArgumentParser(description=__doc__.split("\n")[0]),
                               repeat=None)
    ap.add_argument("--sizes", default="1000,10000,100000,1000000")
    ap.add_argument("--queries", type=int, default=20000)
    ap.add_argument("--lattice", default="fcc")
    a = ap.parse_args(argv)
    sizes = [1000, 4000] if a.smoke else [int(s) for s in a.sizes.split(",")]
    queries = 2000 if a.smoke else a.queries
    with harness.session("pose_index_speed: PoseIndex against cKDTree", smoke=a.smoke):
        for kind in ("uniform", "piled"):
            run(kind, sizes, queries, a.lattice)
    return 0


if __name__ == "__main__":
    sys.exit(main())
