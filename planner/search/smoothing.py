"""Line-of-sight shortcutting of a lattice path (:func:`shortcut`, what
``plan(..., shortcut=True)`` and ``planner plan --shortcut`` apply to A* and Dijkstra paths),
over the compiled rule :func:`planner.search._los.shortcut_kernel`.

Examples
--------
>>> import numpy as np
>>> from planner.lattice import Lattice
>>> from planner.world import World
>>> w = World(Lattice.named("cubic", 1.0), np.zeros((0, 3), np.int64), [[0, 0, 0], [9, 9, 9]])
>>> shortcut(w, [[0, 0, 0], [1, 0, 0], [2, 1, 0], [3, 2, 0], [4, 2, 0]]).tolist()
[[0, 0, 0], [4, 2, 0]]
"""

from __future__ import annotations

import threading

import numpy as np

from planner.occupancy.walk import as_cells
from planner.search._kept import Kept, kept_scratch
from planner.search._los import is_cubic, new_scratch, reach, shortcut_kernel
from planner.world.world import World

__all__ = ["shortcut"]


def shortcut(world: World, cells: np.ndarray) -> np.ndarray:
    """Line-of-sight shortcutting of a cell path: from each kept cell, gallop (sight tests
    2, 4, 8, ... cells ahead) then bisect to a later cell in sight whose successor is not,
    then drop each kept cell whose neighbours see each other
    (:func:`~planner.search._los.shortcut_kernel`). In sight: every cell the
    centre-to-centre segment touches is free, the searches' safe rule, walked exactly, so
    the path keeps the world's clearance. Lookups are added to ``world.cell_checks``.

    Parameters
    ----------
    world : World
    cells : array_like of int, shape (K, 3)
        Lattice indices of a path (consecutive cells need not see each other: such a pair
        is kept as it is).

    Returns
    -------
    ndarray, shape (K', 3), int64
        A subsequence of ``cells`` with the first and the last; each consecutive pair in
        sight (or consecutive in the input), so no longer than the input (triangle
        inequality).
    """
    c = as_cells(cells)
    if len(c) <= 2:
        return c.copy()
    if not (c.flags.writeable and c.flags.aligned):
        c = c.copy()  # one compiled type for every call: numba types these flags
    chk = world.checker
    walk = chk.walk
    kept = _scratch(walk, c)
    args = (chk.occupancy, walk, c, kept.sc, kept.gen[0])
    keep, n, gen = chk.compiled(shortcut_kernel, args)(*args)
    kept.gen[0] = gen
    world.cell_checks += int(n)
    return c[keep]


_LOCAL = threading.local()  # per thread: its store of non-cubic scratches (_kept)
_CUBIC: list[Kept] = []  # one for all threads: the cubic integer walk never touches it


def _scratch(walk, cells: np.ndarray) -> Kept:
    """Scratch for shortcutting ``cells`` on ``walk``: building one costs several
    microseconds, a fair part of a short path's smoothing, so a thread keeps one per walk
    (:mod:`planner.search._kept`)."""
    if is_cubic(walk.g):
        if not _CUBIC:
            _CUBIC.append(Kept(walk, 0.0, new_scratch(0.0, walk), [0]))
        return _CUBIC[0]
    store = getattr(_LOCAL, "store", None)
    if store is None:
        store = _LOCAL.store = {}
    return kept_scratch(store, walk, reach(walk.g, cells))
