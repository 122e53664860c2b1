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

    python -m planner._warm        # what the build runs; prints the seconds it took
"""

from __future__ import annotations

import sys
import time

import numpy as np

__all__ = ["warm"]


def warm() -> float:
    """Compile (or load) the kernels of ``compare``, ``plan`` and ``explore``; returns seconds.

    Kernels compile per argument *type*, not per size, so coarse cells and short queries
    reach the same compiled code as the real commands (when they run the same Python
    paths: ``tests/test_cold_start.py`` checks that ``compare office`` compiles nothing
    more).
    """
    t0 = time.perf_counter()
    from planner import planning as api
    from planner.analysis.compare import compare
    from planner.lattice import NAMED_LATTICES
    from planner.maps import MAPS_DIR
    from planner.search import warm_up

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
    """D* Lite replanning (``planner explore``), on a short run."""
    from planner.explore import explore

    explore(office, (2.5, 2.5, 1.2), (4.0, 2.5, 1.2), lattice="fcc", radius=0.25,
            cell_volume=0.05, max_steps=200)


if __name__ == "__main__":
    print(f"numba kernels compiled or loaded in {warm():.1f} s", file=sys.stderr)
