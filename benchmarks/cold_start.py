"""Cold start: the README's first command on a fresh install, and the same command warm.

Usage::

    python benchmarks/cold_start.py            # planner compare office, fresh then warm
    python benchmarks/cold_start.py --runs 3   # warm runs to take the median of

Each run is a new Python process (``python -m planner compare office``) with its own
``NUMBA_CACHE_DIR``: the first run starts from an empty directory (what a fresh install
sees: every kernel compiles), the warm runs reuse what it wrote. Also prints the time of
``import planner`` alone, and the "compile s" / "search s" columns the command reports (JIT
time is reported apart from search time). No assertions: this prints figures.
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
COMMAND = ["-m", "planner", "compare", "office"]


def timed(args: list[str], cache: str) -> tuple[float, str]:
    """Wall seconds and stdout of ``python args`` with ``NUMBA_CACHE_DIR=cache``."""
    env = dict(os.environ, NUMBA_CACHE_DIR=cache, PYTHONPATH=str(ROOT))
    t = time.perf_counter()
    out = subprocess.run([sys.executable, *args], capture_output=True, text=True, env=env,
                         cwd=ROOT)
    secs = time.perf_counter() - t
    if out.returncode != 0:
        raise SystemExit(f"{' '.join(args)} failed ({out.returncode}): {out.stderr.strip()}")
    return secs, out.stdout


def import_time(cache: str, runs: int = 5) -> float:
    """Median seconds of ``import planner`` in a fresh process (interpreter start excluded)."""
    code = "import time; t = time.perf_counter(); import planner; print(time.perf_counter() - t)"
    return statistics.median(float(timed(["-c", code], cache)[1]) for _ in range(runs))


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--runs", type=int, default=2, help="warm runs (median reported)")
    a = ap.parse_args(argv)
    with tempfile.TemporaryDirectory(prefix="planner_numba_") as cache:
        imp = import_time(cache)
        cold, table = timed(COMMAND, cache)
        warm = statistics.median(timed(COMMAND, cache)[0] for _ in range(max(1, a.runs)))
        imp_warm = import_time(cache)
    print(f"command: python {' '.join(COMMAND)}  (fresh NUMBA_CACHE_DIR, new process each)")
    print(f"import planner: {imp:.2f} s (empty cache), {imp_warm:.2f} s (warm cache)")
    print(f"first run (fresh install, every kernel compiles): {cold:.1f} s")
    print(f"warm run (kernels from the cache, median of {max(1, a.runs)}): {warm:.1f} s")
    print("\nthe first run's table (compile s = the search kernels' compilation, kept out of "
          "search s):")
    print(table.rstrip())
    return 0


if __name__ == "__main__":
    sys.exit(main())
