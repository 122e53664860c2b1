"""Fill numba's on-disk cache with the kernels the README's commands use.

Run at build time by ``setup.py`` (``pip install`` / ``pip install -e`` / ``pip wheel`` run it
on their own: no step for the user): it compiles every kernel that ``planner compare``,
``planner plan`` (lattice searches, shortcutting, OMPL's state and motion checks) and
``planner explore`` run, on small problems, so that numba writes them to the ``__pycache__``
folders beside the sources, which the install (or wheel) then carries. The first command
after installing then loads compiled kernels instead of compiling them (tens of seconds).

The cache is numba's own: keyed by the source file's content, numba's version, Python's
version and the CPU. Whatever does not match (another CPU, another numba) is compiled on
first use as before; nothing here changes a result.

Usage::

    python -m planner._warm                         # what the build runs; prints its seconds
    python -m planner._warm --check compare office  # run a command, then report numba's
                                                    # cache hits and misses; exit 1 on a miss
"""

from __future__ import annotations

import sys
import time

import numpy as np

from planner import planning as api
from planner.cli import main
from planner.lattice import NAMED_LATTICES

__all__ = ["warm"]


def warm() -> float:
    """Compile (or load) the kernels of ``compare``, ``plan`` and ``explore``; returns seconds.

    Kernels compile per argument *type*, not per size, so coarse cells and short queries
    reach the same compiled code as the real commands (when they run the same Python
    paths: ``tests/test_cold_start.py`` checks that ``compare office`` compiles nothing
    more).
    """
    t0 = time.perf_counter()
    from planner.analysis.compare import compare  # lazy: numba, scipy
    from planner.maps import MAPS_DIR  # lazy: scipy
    from planner.search import warm_up  # lazy: numba, scipy

    warm_up()  # every search method's kernel
    # The README's first command itself (a few seconds): map reading, inflation, world
    # build, A* and shortcutting on every lattice. On coarser cells its paths may not be
    # found, and then the shortcut kernel would not be reached.
    office = str(MAPS_DIR / "office.ply")  # the bundled file, whatever the current folder
    compare(office, lattices=list(NAMED_LATTICES), progress=False)
    world = api.build_world(office, "fcc", cell_volume=0.05, radius=0.25)
    chk = world.checker  # OMPL's state and motion checks
    chk.is_valid(np.array([2.5, 2.5, 1.2]))
    chk.check_motion(np.array([2.5, 2.5, 1.2]), np.array([3.5, 2.5, 1.2]))
    _warm_explore(office)
    return time.perf_counter() - t0


def _warm_explore(office: str) -> None:
    """Each replanner of ``planner explore`` (:data:`planner.explore.run.REPLANNERS`), on a
    short run."""
    from planner.explore import explore  # lazy: numba, scipy
    from planner.explore.run import REPLANNERS  # lazy: with explore

    for name in REPLANNERS:
        explore(office, (2.5, 2.5, 1.2), (4.0, 2.5, 1.2), lattice="fcc", radius=0.25,
                cell_volume=0.05, max_steps=200, replanner=name)


def cache_stats() -> tuple[int, int, list[str]]:
    """Cache hits, cache misses and the kernels that missed, over every planner kernel used.

    Read from numba's own dispatcher statistics: a hit is a signature loaded from the on-disk
    cache, a miss one compiled because the cache did not hold it.
    """
    from numba.core.dispatcher import Dispatcher

    hits = misses = 0
    missed: list[str] = []
    for name, mod in list(sys.modules.items()):
        if not name.startswith("planner"):
            continue
        for obj in vars(mod).values():
            if isinstance(obj, Dispatcher) and obj.py_func.__module__ == name:
                h, m = sum(obj.stats.cache_hits.values()), sum(obj.stats.cache_misses.values())
                hits, misses = hits + h, misses + m
                if m:
                    missed.append(f"{name}.{obj.py_func.__qualname__}")
    return hits, misses, missed


def check(argv: list[str]) -> int:
    """Run ``planner ARGV`` in this process; 0 if every kernel it used came from the cache."""
    t = time.perf_counter()
    rc = main(argv)
    secs = time.perf_counter() - t
    hits, misses, missed = cache_stats()
    print(f"planner {' '.join(argv)}: exit {rc}, {secs:.1f} s; numba cache: {hits} kernel "
          f"signatures loaded, {misses} compiled" + (f" ({', '.join(missed)})" if missed else ""),
          file=sys.stderr)
    return 1 if rc or misses or not hits else 0


if __name__ == "__main__":
    if sys.argv[1:2] == ["--check"]:
        sys.exit(check(sys.argv[2:]))
    print(f"numba kernels compiled or loaded in {warm():.1f} s", file=sys.stderr)
