"""The dense grid's tables of a move set for the search loop (numba,
:mod:`planner.search.astar.loop`): each stencil cell and move as one offset into the bit grid,
the stencil as a few bit windows (one per row of cells along the grid's fastest axis), each
move's key offset, the gauge's facets halved (:func:`planner.search.heuristic.half_facets`),
and the one read of the union stencil into a mask of free cells (:func:`stencil_mask`). Made
once per move set and world, kept in the driver's ``Bound``.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from planner._numba import njit_cached
from planner.occupancy.keys import step3
from planner.search.heuristic import half_facets

__all__ = ["DenseTables", "dense_tables", "grid_offsets", "stencil_mask", "stencil_rows"]


@njit_cached
def grid_offsets(ust, moves, d1, d2):  # pragma: no cover - compiled
    """Each stencil cell (U, 3) and move (M, 3) as one offset into a C-order grid of dims
    (., d1, d2), and the margin (cells) inside which no stencil cell leaves the box: an
    expansion there looks up its cells without bounds tests or index arithmetic."""
    uoff = np.empty(ust.shape[0], np.int64)
    reach = 0
    for j in range(ust.shape[0]):
        uoff[j] = (ust[j, 0] * d1 + ust[j, 1]) * d2 + ust[j, 2]
        reach = max(reach, abs(ust[j, 0]), abs(ust[j, 1]), abs(ust[j, 2]))
    moff = np.empty(moves.shape[0], np.int64)
    for m in range(moves.shape[0]):
        moff[m] = (moves[m, 0] * d1 + moves[m, 1]) * d2 + moves[m, 2]
    return uoff, moff, reach


@njit_cached(_nrt=False, inline="always")
def stencil_mask(grid, a0, b0, c0, d0, d1, d2, base, reach, ust, uoff, bit):  # pragma: no cover
    """The union stencil around grid cell (a0, b0, c0) read into a mask of its free cells:
    the one home of that read for the search loop.

    ``grid`` the bit grid (uint8, C order, dims (d0, d1, d2)), ``base`` the cell's offset
    in it, ``ust`` (U, 3) the stencil, ``uoff`` (U,) and ``reach`` its offsets and margin
    (:func:`grid_offsets`), ``bit`` (U,) each stencil cell's bit in the mask. Inside the
    margin the cells are read without bounds tests; a cell outside the box reads as
    blocked. Returns the mask (int64)."""
    free = np.int64(0)
    if (a0 >= reach and b0 >= reach and c0 >= reach and a0 < d0 - reach
            and b0 < d1 - reach and c0 < d2 - reach):
        for j in range(ust.shape[0]):
            f = base + uoff[j]
            free |= np.int64((grid[np.uint64(f >> 3)] >> (f & 7)) & 1) << bit[j]
    else:
        for j in range(ust.shape[0]):
            a = a0 + ust[j, 0]
            b = b0 + ust[j, 1]
            c = c0 + ust[j, 2]
            if a >= 0 and b >= 0 and c >= 0 and a < d0 and b < d1 and c < d2:
                f = (a * d1 + b) * d2 + c
                free |= np.int64((grid[f >> 3] >> (f & 7)) & 1) << bit[j]
    return free


@njit_cached
def stencil_rows(ust, need, d1, d2):  # pragma: no cover - compiled
    """The union stencil (U, 3) as runs of cells along the grid's fastest axis, read as
    one bit window each instead of one lookup per cell.

    Returns ``(roff, rshift, rmask, ubit, need2, all2, ok)``: per row (R,) its first cell's grid
    offset (int64, C-order grid of dims (., d1, d2)), the bit where its window starts in the
    free mask and the window's mask; per stencil cell (U,) its bit in that mask; each move's
    ``need`` (M,) and the mask of every stencil cell, with the bits renumbered so. A row
    spans at most 9 cells (its window then fits two bytes); ``ok`` False when the rows do
    not fit (more than 63 bits or a longer row): then the bits keep the stencil's order
    and each cell is read alone."""
    nu = ust.shape[0]
    row = np.full(nu, -1, np.int64)
    cmin = np.empty(nu, np.int64)
    span = np.empty(nu, np.int64)
    nr = 0
    for j in range(nu):
        if row[j] >= 0:
            continue
        lo_c = ust[j, 2]
        hi_c = ust[j, 2]
        for i in range(j, nu):
            if ust[i, 0] == ust[j, 0] and ust[i, 1] == ust[j, 1]:
                row[i] = nr
                lo_c = min(lo_c, ust[i, 2])
                hi_c = max(hi_c, ust[i, 2])
        cmin[nr] = lo_c
        span[nr] = hi_c - lo_c + 1
        nr += 1
    roff = np.empty(nr, np.int64)
    rshift = np.empty(nr, np.int64)
    rmask = np.empty(nr, np.int64)
    at = 0
    for r in range(nr):
        rshift[r] = at
        rmask[r] = (np.int64(1) << span[r]) - 1
        at += span[r]
    ubit = np.empty(nu, np.int64)
    all2 = np.int64(0)
    for j in range(nu):
        r = row[j]
        roff[r] = (ust[j, 0] * d1 + ust[j, 1]) * d2 + cmin[r]
        ubit[j] = rshift[r] + ust[j, 2] - cmin[r]
        all2 |= np.int64(1) << ubit[j]
    if at > 63 or span[:nr].max() > 9:  # no windows: the stencil's own bit order
        for j in range(nu):
            ubit[j] = j
        all_u = (np.int64(1) << nu) - 1 if nu < 64 else np.int64(-1)  # (no mask: unused)
        return roff, rshift, rmask, ubit, need.copy(), all_u, False
    need2 = np.zeros(need.shape[0], np.int64)
    for m in range(need.shape[0]):
        for j in range(nu):
            if (need[m] >> j) & 1:
                need2[m] |= np.int64(1) << ubit[j]
    return roff, rshift, rmask, ubit, need2, all2, True


class DenseTables(NamedTuple):
    """What the search loop (:func:`planner.search.astar.loop.search_loop`) needs of a move
    set on a grid of dims (., d1, d2) besides the move set itself: made once per move set
    and grid (:func:`dense_tables`, kept in the driver's ``Bound``) instead of on every
    search, where it cost more than a short search.
    Also the loop's per-search scratch, so that a search allocates nothing but its path."""

    uoff: np.ndarray  # (U,) int64 grid offset of each stencil cell (grid_offsets)
    moff: np.ndarray  # (M,) int64 grid offset of each move
    reach: int  # margin (cells) inside which no stencil cell leaves the box
    roff: np.ndarray  # (R,) int64 stencil rows (stencil_rows)
    rshift: np.ndarray  # (R,) int64
    rmask: np.ndarray  # (R,) int64
    ubit: np.ndarray  # (U,) int64
    need2: np.ndarray  # (M,) int64
    all_u: int  # mask of every stencil cell
    rows: bool  # the rows fit their windows
    mkey: np.ndarray  # (M,) int64 each move as an offset of the packed key
    hhalf: np.ndarray  # (H, 3) float64 the gauge's facets, one of each antipodal pair
    habs: bool  # hhalf halves the facets: the gauge is max |hhalf . e|, else max(0, .)
    todo: np.ndarray  # (M,) int64 scratch: the moves an expansion goes on to (search loop)


@njit_cached
def dense_tables(ms, dims):  # pragma: no cover - compiled
    """:class:`DenseTables` of move set ``ms`` on a grid of dims ``dims`` (3,) int64 (any
    dims on a hashed world: the loop then reads only the moves' key offsets and bits)."""
    moves, ust, hmat = ms.moves, ms.union, ms.hmat
    d1, d2 = dims[1], dims[2]
    nm = moves.shape[0]
    uoff, moff, reach = grid_offsets(ust, moves, d1, d2)
    roff, rshift, rmask, ubit, need2, all_u, rows = stencil_rows(ust, ms.need, d1, d2)
    mkey = np.empty(nm, np.int64)
    for m in range(nm):
        mkey[m] = step3(moves[m, 0], moves[m, 1], moves[m, 2])
    hhalf, habs = half_facets(hmat)
    return DenseTables(uoff, moff, reach, roff, rshift, rmask, ubit, need2, all_u, rows, mkey,
                       hhalf, habs, np.empty(nm, np.int64))
