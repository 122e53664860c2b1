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
from typing import NamedTuple

import numpy as np

from planner.occupancy.walk import as_cells
from planner.search._los import SightScratch, is_cubic, new_scratch, reach, shortcut_kernel
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
    chk = world.checker
    walk = chk.walk
    kept = _scratch(walk, c)
    keep, n, gen = shortcut_kernel(chk.occupancy, walk, c, kept.sc, kept.gen[0])
    kept.gen[0] = gen
    world.cell_checks += int(n)
    return c[keep]


class _Kept(NamedTuple):
    """A sight scratch kept for the next call on this thread: built for ``walk`` and sight
    lines up to ``span`` m, and the last generation stamped in it (a reused scratch needs
    fresh stamps: :func:`planner.occupancy.walk.walk_on`)."""

    walk: object
    span: float
    sc: SightScratch
    gen: list[int]  # one element, updated in place


_LOCAL = threading.local()  # per thread: its _Kept for non-cubic lattices
_CUBIC: list[_Kept] = []  # one for all threads: the cubic integer walk never touches it


def _scratch(walk, cells: np.ndarray) -> _Kept:
    """Scratch for shortcutting ``cells`` on ``walk``: building one costs several
    microseconds, a fair part of a short path's smoothing, so a thread keeps its last."""
    if is_cubic(walk.g):
        if not _CUBIC:
            _CUBIC.append(_Kept(walk, 0.0, new_scratch(0.0, walk), [0]))
        return _CUBIC[0]
    span = reach(walk.g, cells)
    kept = getattr(_LOCAL, "kept", None)
    if kept is None or kept.walk is not walk or kept.span < span:
        kept = _LOCAL.kept = _Kept(walk, span, new_scratch(span, walk), [0])
    return kept
