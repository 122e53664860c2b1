"""Which lattice cells are free: the :class:`Occupancy` struct and its lookups (numba).

Everything here works on plain numpy arrays inside typed structs (``NamedTuple``s, which
numba compiles as tuples with named fields) so that it compiles once and caches on disk:

* :class:`Occupancy` - which cells are free. ``mode`` 0 (dense): ``grid`` is a flat uint8
  array over the index box ``lo + [0, dims)`` holding 1 for every cell that is in bounds and
  not blocked; any index outside the box is out of bounds. One byte load per lookup.
  ``mode`` 1 (hash): ``table`` is an open-addressing set (size ``tmask + 1``, a power of two,
  load <= 0.5, empty slots -1) of packed keys of blocked cells; a cell is free iff its centre
  ``gmat @ w`` lies in ``[blo, bhi]`` (bounds already widened by the tolerance) and its key
  is not in the table.
* :class:`planner.occupancy.walk.Walk` - the lattice data of the exact segment walk.

Every array in them is C-contiguous, writable and of a fixed dtype for every lattice and
storage mode: one numba type, so one compilation (MCC's generator is not C-contiguous and
once forced a second one).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from planner._numba import njit_cached
from planner.lattice import quantize as qk
from planner.occupancy.keys import in_key_set, pack3

__all__ = ["Occupancy", "cell_free", "clear_cells", "fill_in_bounds", "free_many", "occ_free",
           "point_free"]


class Occupancy(NamedTuple):
    """Free-cell lookup structure (module docstring). Arrays C-contiguous and writable."""

    mode: int  # 0 dense, 1 hash
    grid: np.ndarray  # (n,) uint8, dense mode (1 element in hash mode)
    lo: np.ndarray  # (3,) int64 lowest index of the dense box
    dims: np.ndarray  # (3,) int64 dense box size
    table: np.ndarray  # (T,) int64 hash set of blocked keys (1 element in dense mode)
    tmask: int  # T - 1
    gmat: np.ndarray  # (3, 3) float64 generator (m)
    blo: np.ndarray  # (3,) float64 bounds minimum, widened by the tolerance (m)
    bhi: np.ndarray  # (3,) float64 bounds maximum, widened by the tolerance (m)


# -- occupancy -----------------------------------------------------------------------------
@njit_cached(inline="always")
def cell_free(mode, grid, lo, dims, table, tmask, g, blo, bhi, i, j, k):  # pragma: no cover
    """True iff cell (i, j, k) is in bounds and not blocked (one occupancy lookup).

    Takes the occupancy tuple's members (unpacked once by the caller) and is inlined:
    a non-inlined call with array arguments pays reference counting on every call."""
    if mode == 0:
        a = i - lo[0]
        b = j - lo[1]
        c = k - lo[2]
        if a < 0 or b < 0 or c < 0 or a >= dims[0] or b >= dims[1] or c >= dims[2]:
            return False
        return grid[(a * dims[1] + b) * dims[2] + c] != 0
    for r in range(3):
        x = g[r, 0] * i + g[r, 1] * j + g[r, 2] * k
        if x < blo[r] or x > bhi[r]:
            return False
    return not in_key_set(table, tmask, pack3(i, j, k))


@njit_cached(inline="always")
def occ_free(occ, i, j, k):  # pragma: no cover - compiled
    """One lookup through the :class:`Occupancy` struct (inlined)."""
    return cell_free(occ.mode, occ.grid, occ.lo, occ.dims, occ.table, occ.tmask, occ.gmat,
                 occ.blo, occ.bhi, i, j, k)


@njit_cached
def free_many(occ, w, out):  # pragma: no cover - compiled
    """out[n] = cell w[n] (N, 3) is in bounds and free."""
    for n in range(w.shape[0]):
        out[n] = occ_free(occ, w[n, 0], w[n, 1], w[n, 2])


@njit_cached
def fill_in_bounds(grid, lo, dims, g, blo, bhi):  # pragma: no cover - compiled
    """grid[cell] = 1 iff the cell centre lies in [blo, bhi] (dense mode construction)."""
    for a in range(dims[0]):
        i = lo[0] + a
        for b in range(dims[1]):
            j = lo[1] + b
            base = (a * dims[1] + b) * dims[2]
            for c in range(dims[2]):
                k = lo[2] + c
                ok = True
                for r in range(3):
                    x = g[r, 0] * i + g[r, 1] * j + g[r, 2] * k
                    if x < blo[r] or x > bhi[r]:
                        ok = False
                        break
                grid[base + c] = 1 if ok else 0


@njit_cached
def clear_cells(grid, lo, dims, w):  # pragma: no cover - compiled
    """Mark the listed cells (N, 3) not free in a dense grid (cells outside are ignored)."""
    for n in range(w.shape[0]):
        a = w[n, 0] - lo[0]
        b = w[n, 1] - lo[1]
        c = w[n, 2] - lo[2]
        if 0 <= a < dims[0] and 0 <= b < dims[1] and 0 <= c < dims[2]:
            grid[(a * dims[1] + b) * dims[2] + c] = 0


@njit_cached
def point_free(occ, quant, x0, x1, x2, buf, out):  # pragma: no cover - compiled
    """Is the cell containing point (x0, x1, x2) (m) in bounds and free? One lookup.
    ``quant``: ``Lattice.quantizer()``; ``buf`` (2, 3) float64 and ``out`` (1, 3) int64 are
    caller-owned scratch."""
    buf[0, 0] = x0
    buf[0, 1] = x1
    buf[0, 2] = x2
    qk.quantize_generic3(buf[:1], quant.basis, quant.basis_inv, quant.cand, quant.cand_z,
                         quant.counts, quant.reduction, out)
    return occ_free(occ, out[0, 0], out[0, 1], out[0, 2])


