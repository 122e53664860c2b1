"""D* Lite's stored path as the cells it rests on (numba), and the replan that keeps it.

A path's cost depends only on its moves, and a move exists while its own cell, its end
cell and the cells of its safe rule (:mod:`planner.search.moves`) are free. When a scan
only *blocks* cells (costs only rise) and none of them is one of those cells of the stored
path, the rest of that path from the robot's cell costs what it did, and every other path
costs at least what it did: the stored path is still a shortest one. Such a replan keeps
it and leaves the scan's cells pending (:class:`planner.search.dstar.lite.DStarLite` keeps
them); the first replan that cannot keep the path (a pending cell under it, a freed cell,
the robot off it) repairs every pending cell in one batch, then searches. A pending cell
never reaches a search: nothing is looked up or expanded while one is pending.

The cells are bits of ``DBox.rest`` (one bit per cell of the index box), set when a path
is extracted and cleared when the next one replaces it; ``DBox.rest_blocks`` has a bit per
4x4x4 block of the box, set while one of its cells is a rest cell. A kept replan reads a
changed cell's block bit first and its own bit only when that is set: right after a scan
both maps are out of cache, a scan's cells mostly lie away from the path, and the block
map is 64 times smaller (fewer cache lines to fetch).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from planner._numba import njit_cached
from planner.search.dstar.kernel import PATH_COST, _box


@njit_cached(_nrt=False)
def _block(bx, a, b, c):  # pragma: no cover - compiled
    """Index in ``bx.rest_blocks`` of box cell (a, b, c) (offsets from ``bx.lo``)."""
    return ((a >> 2) * ((bx.dims[1] + 3) >> 2) + (b >> 2)) * ((bx.dims[2] + 3) >> 2) + (c >> 2)


@njit_cached(_nrt=False)
def _bit(bx, v0, v1, v2, value):  # pragma: no cover - compiled
    """Set or clear the rest bit of cell (v0, v1, v2), and its block's. Clearing the block
    bit is right because a path's bits are cleared all at once, before the next path's
    are set (:func:`mark_path`): no other rest cell is left in the block."""
    b = _box(bx, v0, v1, v2)
    if b >= 0:
        q = _block(bx, v0 - bx.lo[0], v1 - bx.lo[1], v2 - bx.lo[2])
        if value:
            bx.rest[b >> 3] |= np.uint8(1 << (b & 7))
            bx.rest_blocks[q >> 3] |= np.uint8(1 << (q & 7))
        else:
            bx.rest[b >> 3] &= np.uint8(~(1 << (b & 7)) & 0xFF)
            bx.rest_blocks[q >> 3] &= np.uint8(~(1 << (q & 7)) & 0xFF)


@njit_cached(_nrt=False)
def mark_path(ms, bx, path, k, value):  # pragma: no cover - compiled
    """Set (``value``) or clear the rest bits of the path ``path[:k]`` ((>= k, 3) int64):
    each cell, and each move's safe-rule cells. A path is cleared whole, before the next
    one is set (:func:`_bit`)."""
    for i in range(k):
        p0, p1, p2 = path[i, 0], path[i, 1], path[i, 2]
        _bit(bx, p0, p1, p2, value)
        if i + 1 == k:
            break
        m = move_of(ms, path[i + 1, 0] - p0, path[i + 1, 1] - p1, path[i + 1, 2] - p2)
        if m >= 0:
            for e in ms.idx[ms.ptr[m]:ms.ptr[m + 1]]:
                _bit(bx, p0 + ms.union[e, 0], p1 + ms.union[e, 1], p2 + ms.union[e, 2], value)


@njit_cached(_nrt=False)
def move_of(ms, d0, d1, d2):  # pragma: no cover - compiled
    """The move of ``ms`` with offset (d0, d1, d2), -1 when none: a path step's move,
    whose safe-rule cells are ``ms.union[ms.idx[ms.ptr[m]:ms.ptr[m + 1]]]``."""
    for m in range(ms.moves.shape[0]):
        if ms.moves[m, 0] == d0 and ms.moves[m, 1] == d1 and ms.moves[m, 2] == d2:
            return m
    return -1


@njit_cached(_nrt=False)
def on_rest(bx, v0, v1, v2):  # pragma: no cover - compiled
    """The box index of cell (v0, v1, v2) when its rest bit is set, else -1. Reads its
    block's bit first and its own only when that is set (module docstring)."""
    a, b, c = v0 - bx.lo[0], v1 - bx.lo[1], v2 - bx.lo[2]
    d0, d1, d2 = bx.dims[0], bx.dims[1], bx.dims[2]
    if 0 <= a < d0 and 0 <= b < d1 and 0 <= c < d2:
        q = ((a >> 2) * ((d1 + 3) >> 2) + (b >> 2)) * ((d2 + 3) >> 2) + (c >> 2)
        if (bx.rest_blocks[q >> 3] >> (q & 7)) & 1:
            k = (a * d1 + b) * d2 + c
            if (bx.rest[k >> 3] >> (k & 7)) & 1:
                return k
    return -1


@njit_cached(_nrt=False)
def keep_path(bx, counts, fs, start, path, step, cells):  # pragma: no cover
    """True when the stored path from ``start`` on is still a shortest path after the
    cells ``cells`` ((K, 3) int64), all of them blocked (the caller knows), were blocked
    and the planner has not repaired them (module docstring): then the replan's path is set (rows
    ``[st.path_from, st.path_to)`` of ``path``, cost ``fs[PATH_COST]``; ``st`` is ``counts[0]``,
    the planner's state record). Reads one or two bits per cell, no lookup.

    A kept replan is this function alone, called through
    :func:`planner.search.dstar.replan.keep_state` (one object to unbox)."""
    st = counts[0]
    if st.path_valid != 1:
        return False
    for i in range(cells.shape[0]):
        if on_rest(bx, cells[i, 0], cells[i, 1], cells[i, 2]) >= 0:
            return False
    k = st.path_len
    for j in range(st.path_at, k):
        if path[j, 0] == start[0] and path[j, 1] == start[1] and path[j, 2] == start[2]:
            cost = 0.0
            for i in range(j + 1, k):
                cost += step[i]
            st.path_at = j
            st.path_from = j
            st.path_to = k
            fs[PATH_COST] = cost
            return True
    return False



class CheckLines(NamedTuple):
    """Cache lines (64 bytes) a kept replan's check of some cells reads
    (:func:`check_lines`)."""

    cell_map: int  # with the per-cell rest map alone
    block_map: int  # with the block map first, then the cell map's lines of marked blocks


def check_lines(bx, cells: np.ndarray) -> CheckLines:
    """The cache lines a kept replan's check of ``cells`` ((K, 3) int64 lattice indices)
    reads on box ``bx`` (``DBox``), with the cell map alone and with the block map
    (module docstring); cells outside the box read nothing. For profiling
    (``benchmarks/explore_profile.py``)."""
    d = bx.dims
    a = np.asarray(cells, np.int64).reshape(-1, 3) - bx.lo
    a = a[((a >= 0) & (a < d)).all(axis=1)]
    k = (a[:, 0] * d[1] + a[:, 1]) * d[2] + a[:, 2]
    q = ((a[:, 0] >> 2) * ((d[1] + 3) >> 2) + (a[:, 1] >> 2)) * ((d[2] + 3) >> 2) + (a[:, 2] >> 2)
    marked = ((bx.rest_blocks[q >> 3] >> (q & 7)) & 1).astype(bool)
    line = 9  # 512 bits a line
    return CheckLines(cell_map=len(np.unique(k >> line)),
                      block_map=len(np.unique(q >> line)) + len(np.unique(k[marked] >> line)))
