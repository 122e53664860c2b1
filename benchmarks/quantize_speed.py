"""Quantization throughput per lattice, against a straightforward numpy eq. (2).

    python benchmarks/quantize_speed.py [--n 10000000] [--stream] [--stream-n 100000000]
    python benchmarks/quantize_speed.py --smoke     # 10^5 points, seconds

For every named lattice (cell volume 1 m^3, points uniform in a 16-cell cube):

* ``Lattice.quantize`` rate (points/s, best of 3) and the rate of the paper's eq. (2)
  written plainly in numpy (``round(G^-1 x)``, then the nearest of the 27 candidates
  ``w + Delta``, ``Delta = {-1, 0, 1}^3``, 16,384 points per chunk), both in this process,
  and whether the two agree (this thread's CPU time, ``benchmarks/harness.py``);
* how often eq. (2) with the paper's own Delta sets (eqs. 3-7, plus the zero offset)
  returns a lattice point that is not the nearest, and the largest extra distance.

Goals: >= 10 M points/s per lattice and >= 5x the numpy eq. (2).
``--stream`` quantizes ``--stream-n`` points generated and consumed in chunks and reports
the peak resident set size (``VmHWM``, :func:`harness.peak_rss`), showing memory stays
bounded.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import harness  # noqa: E402  (the sibling module)

from planner.analysis.measure import (  # noqa: E402
    NAMED,
    format_table,
    paper_delta_errors,
    quantize_eq2_numpy,
)
from planner.lattice import Lattice  # noqa: E402

CUBE27 = np.array(np.meshgrid(*[(-1, 0, 1)] * 3, indexing="ij")).reshape(3, -1).T


def peak_rss_mb() -> float:
    """Peak resident set size of this process so far, MiB (NaN without /proc)."""
    b = harness.peak_rss()
    return b / 2**20 if b is not None else float("nan")


def _best_rate(fn, n: int, repeat: int) -> float:
    return n / harness.best_of(fn, repeat)


def speed_rows(n: int, n_numpy: int, n_check: int, seed: int = 0) -> list[dict]:
    rng = np.random.default_rng(seed)
    pts = 16 * rng.random((n, 3)) - 8
    rows = []
    for name in NAMED:
        lat = Lattice.named(name, 1.0)
        lat.quantize(pts[:16])  # load compiled kernels
        fast = _best_rate(lambda lat=lat: lat.quantize(pts), n, 3)
        sub = pts[:n_numpy]
        ref = quantize_eq2_numpy(sub, lat.generator, CUBE27)
        slow = _best_rate(lambda lat=lat, sub=sub: quantize_eq2_numpy(sub, lat.generator, CUBE27),
                          len(sub), 1)
        agree = float(np.mean(np.all(ref == lat.quantize(sub), axis=1)))
        err = paper_delta_errors(lat, n_check, seed=seed)
        rows.append({
            "lattice": name, "quantize_pts_s": fast, "numpy_eq2_pts_s": slow,
            "speedup": fast / slow, "agree_27": agree,
            "paper_deltas": err["n_deltas"], "paper_wrong_rate": err["rate"],
            "paper_max_extra": err["max_extra_rel"],
            "goal_10M": "yes" if fast >= 1e7 else "NO",
            "goal_5x": "yes" if fast / slow >= 5 else "NO",
        })
    return rows


def stream(n_total: int, chunk: int, seed: int = 0) -> list[dict]:
    rows = []
    for name in NAMED:
        lat = Lattice.named(name, 1.0)
        rng = np.random.default_rng(seed)
        buf = np.empty((chunk, 3))
        checksum = 0
        t = harness.cpu_clock()
        done = 0
        while done < n_total:
            m = min(chunk, n_total - done)
            x = buf[:m]
            rng.random(out=x)
            x *= 1000.0
            x -= 500.0
            w = lat.quantize(x)
            checksum ^= int(np.bitwise_xor.reduce(w[:, 0]))  # consume the result
            done += m
        dt = harness.cpu_clock() - t
        rows.append({"lattice": name, "points": done, "seconds": dt,
                     "pts_s_incl_rng": done / dt, "peak_rss_mib": peak_rss_mb()})
    return rows


def main(argv: Sequence[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--n", type=int, default=10**7, help="points for the rate (default 1e7)")
    ap.add_argument("--n-numpy", type=int, default=2 * 10**6,
                    help="points for the numpy eq. (2) rate (default 2e6)")
    ap.add_argument("--n-check", type=int, default=10**6,
                    help="points for the paper-Delta error rate (default 1e6)")
    ap.add_argument("--stream", action="store_true", help="also run the chunked stream test")
    ap.add_argument("--stream-n", type=int, default=10**8, help="stream points (default 1e8)")
    ap.add_argument("--chunk", type=int, default=10**6, help="stream chunk size (default 1e6)")
    ap.add_argument("--seed", type=int, default=0)
    harness.add_arguments(ap, repeat=None)
    args = ap.parse_args(argv)
    if args.smoke:
        args.n, args.n_numpy, args.n_check = 10**5, 2 * 10**4, 10**4
        args.stream_n, args.chunk = 10**6, 10**5
    with harness.session("quantization throughput per lattice", smoke=args.smoke):
        return _run(ap, args)


def _run(ap: argparse.ArgumentParser, args: argparse.Namespace) -> int:
    if min(args.n, args.n_numpy, args.n_check, args.stream_n, args.chunk) < 1:
        ap.error("sizes must be positive")
    n_numpy = min(args.n_numpy, args.n)

    if args.stream:
        base = peak_rss_mb()
        print(f"stream {args.stream_n} points in chunks of {args.chunk} "
              f"(peak RSS before: {base:.0f} MiB; a full (N,3) float64 array would need "
              f"{args.stream_n * 24 / 2**20:.0f} MiB)")
        print(format_table(stream(args.stream_n, args.chunk, args.seed)))
        print("(run first, so the peak RSS is not inflated by the rate test's arrays)\n")
    print(f"quantize {args.n} uniform points per lattice (cell volume 1 m^3); numpy eq. (2) "
          f"with 27 offsets on {n_numpy}; paper Delta check on {args.n_check}")
    rows = speed_rows(args.n, n_numpy, args.n_check, args.seed)
    print(format_table(rows))
    print("agree_27: fraction identical to the numpy eq. (2) with all 27 offsets; "
          "paper_max_extra: worst extra distance / cell size with the paper's Delta")
    print(f"peak RSS {peak_rss_mb():.0f} MiB (VmHWM)")
    for r in rows:
        print(harness.single_ratio(f"quantize / numpy eq. (2) points per s, {r['lattice']}",
                                   r["quantize_pts_s"], r["numpy_eq2_pts_s"], goal=">= 5",
                                   note="best of 3 and of 1, thread CPU"))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
