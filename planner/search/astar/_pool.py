"""The dense slot arrays of the A* driver (:mod:`planner.search.astar.driver`), pooled per
dense occupancy grid.

One dense slot array per dense occupancy grid, reused across searches (cleared after each
search at the cells it touched, so a search never pays for the whole box). A context holds
the array of the grid it last searched (the driver's ``_Context.held``) and returns it here when it
searches another grid: concurrent searches on one world get their own.
"""

from __future__ import annotations

import mmap
import threading
import weakref

import numpy as np

__all__ = ["give", "lazy_zeros", "take"]

_POOL: dict[int, np.ndarray] = {}
_LOCK = threading.Lock()
_WATCHED: set[int] = set()


def take(grid) -> np.ndarray | None:
    """The pooled dense slot array of ``grid`` (taken out of the pool), or None."""
    return _POOL.pop(id(grid), None)  # one dict operation: atomic under the GIL


def lazy_zeros(n: int) -> np.ndarray:
    """``np.zeros(n, np.int32)`` whose pages the OS zeroes on first touch, 4 KiB at a time.

    numpy asks for transparent huge pages on large arrays; a search touches a few scattered
    cells of the box, and each touch then makes the kernel zero a whole 2 MiB page (the first
    FCC query on a 256^3 box: 1.5 s instead of 0.01 s, and the whole array resident). An
    anonymous mapping without that advice is zeroed per small page, where it is touched."""
    nbytes = 4 * n
    if nbytes < 1 << 22:
        return np.zeros(n, np.int32)
    mm = mmap.mmap(-1, nbytes)
    if hasattr(mmap, "MADV_NOHUGEPAGE"):  # also when the system default is "always"
        mm.madvise(mmap.MADV_NOHUGEPAGE)
    return np.frombuffer(mm, dtype=np.int32)  # keeps the mapping alive; writable, aligned


def _forget(key: int) -> None:
    with _LOCK:
        _POOL.pop(key, None)
        _WATCHED.discard(key)


def give(grid, a: np.ndarray) -> None:
    """Return a cleared dense slot array of ``grid`` to the pool (dropped when the grid is
    freed)."""
    key = id(grid)
    _POOL[key] = a
    if key not in _WATCHED:
        with _LOCK:  # one finalizer per grid, whichever thread returns its array first
            new = key not in _WATCHED
            _WATCHED.add(key)
        if new:
            weakref.finalize(grid, _forget, key)
