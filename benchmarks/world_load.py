"""How much the verification of a saved world costs: ``load_world`` (checked reads, schema,
digest) against a plain ``numpy.load`` of the same arrays, in the same process.

Usage: ``python benchmarks/world_load.py WORLD.npz`` (a world from ``planner world``, e.g.
``planner world ../shared/data/octomap/geb079.bt --radius 0.2 --out geb079.npz``). The first
call of each (imports, the check kernel's compilation or cache load) is not timed.
"""

from __future__ import annotations

import statistics
import sys
import time

import numpy as np

from planner.world.file import load_world


def _plain(path: str) -> None:
    with np.load(path, allow_pickle=False) as z:
        for k in z.files:
            z[k]


def _median(fn, path: str, repeats: int = 7) -> float:
    fn(path)  # not timed: first use
    times = []
    for _ in range(repeats):
        t = time.perf_counter()
        fn(path)
        times.append(time.perf_counter() - t)
    return statistics.median(times)


def main(path: str) -> None:
    plain = _median(_plain, path)
    checked = _median(load_world, path)
    w = load_world(path)
    print(f"{path}: {w.n_blocked} blocked, {w.n_unknown} unknown cells")
    print(f"numpy.load {plain * 1e3:.0f} ms, load_world {checked * 1e3:.0f} ms, "
          f"ratio {checked / plain:.2f}")


if __name__ == "__main__":
    main(sys.argv[1])
