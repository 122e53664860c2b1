"""Which lattice cells are free: the :class:`Occupancy` struct and its lookups (numba).

Everything here works on plain numpy arrays inside typed structs (``NamedTuple``s, which
numba compiles as tuples with named fields) so that it compiles once and caches on disk:

* :class:`Occupancy` - which cells are free. ``mode`` 0 (dense): ``grid`` is a bit-packed
  uint8 array over the index box ``lo + [0, dims)`` (cell ``f`` of the box in C order is bit
  ``f & 7`` of byte ``f >> 3``, :mod:`planner.occupancy.bits`) holding 1 for every cell
  that is in bounds and not blocked; any index outside the box is out of bounds. One byte
  load, a shift and a mask per lookup; one bit per cell of the box.
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

__all__ = ["Occupancy", "bit_free", "cell_free", "clear_cells", "free_many", "occ_free",
           "point_free"]


class Occupancy(NamedTuple):
    """Free-cell lookup structure (module docstring). Arrays C-contiguous and writable."""

    mode: int  # 0 dense, 1 hash
    grid: np.ndarray  # (ceil(n / 8),) uint8 free bits, dense mode (1 element in hash mode)
    lo: np.ndarray  # (3,) int64 lowest index of the dense box
    dims: np.ndarray  # (3,) int64 dense box size
    table: np.ndarray  # (T,) int64 hash set of blocked keys (1 element in dense mode)
    tmask: int  # T - 1
    gmat: np.ndarray  # (3, 3) float64 generator (m)
    blo: np.ndarray  # (3,) float64 bounds minimum, widened by the tolerance (m)
    bhi: np.ndarray  # (3,) float64 bounds maximum, widened by the tolerance (m)


# -- occupancy -----------------------------------------------------------------------------
@njit_cached(_nrt=False)
def cell_free(mode, grid, lo, dims, table, tmask, g, blo, bhi, i, j, k):  # pragma: no cover
    """True iff cell (i, j, k) is in bounds and not blocked (one occupancy lookup).

    Takes the occupancy tuple's members (unpacked once by the caller) and counts no
    references (``_nrt=False``): counting those of its array arguments would cost more
    than the lookup."""
    if mode == 0:
        a = i - lo[0]
        b = j - lo[1]
        c = k - lo[2]
        if a < 0 or b < 0 or c < 0 or a >= dims[0] or b >= dims[1] or c >= dims[2]:
            return False
        f = (a * dims[1] + b) * dims[2] + c
        return (grid[f >> 3] >> (f & 7)) & 1 != 0
    for r in range(3):
        x = g[r, 0] * i + g[r, 1] * j + g[r, 2] * k
        if x < blo[r] or x > bhi[r]:
            return False
    return not in_key_set(table, tmask, pack3(i, j, k))


@njit_cached(_nrt=False)
def bit_free(grid, f):  # pragma: no cover - compiled
    """True iff cell ``f`` (flat C-order index in the dense box) is free: bit ``f & 7`` of
    byte ``f >> 3`` of a dense ``grid``. For kernels that step flat indices themselves."""
    return (grid[f >> 3] >> (f & 7)) & 1 != 0


@njit_cached(_nrt=False)
def occ_free(occ, i, j, k):  # pragma: no cover - compiled
    """One lookup through the :class:`Occupancy` struct."""
    return cell_free(occ.mode, occ.grid, occ.lo, occ.dims, occ.table, occ.tmask, occ.gmat,
                 occ.blo, occ.bhi, i, j, k)


@njit_cached
def free_one(occ, i, j, k):  # pragma: no cover - compiled
    """Cell (i, j, k) is in bounds and free (one lookup)."""
    return occ_free(occ, i, j, k)


@njit_cached
def free_many(occ, w, out):  # pragma: no cover - compiled
    """out[n] = cell w[n] (N, 3) is in bounds and free."""
    for n in range(w.shape[0]):
        out[n] = occ_free(occ, w[n, 0], w[n, 1], w[n, 2])


@njit_cached
def clear_cells(grid, lo, dims, w):  # pragma: no cover - compiled
    """Set to 0 the listed cells (N, 3) of a byte grid (one uint8 per cell of the index box
    ``lo``, ``dims``; cells outside it are ignored)."""
    for n in range(w.shape[0]):
        a = w[n, 0] - lo[0]
        b = w[n, 1] - lo[1]
        c = w[n, 2] - lo[2]
        if 0 <= a < dims[0] and 0 <= b < dims[1] and 0 <= c < dims[2]:
            grid[(a * dims[1] + b) * dims[2] + c] = 0


@njit_cached
def point_cell(occ, kind, a, b, ginv, x0, x1, x2, cell):  # pragma: no cover - compiled
    """Write into ``cell`` (3,) int64 the cell containing point (x0, x1, x2) (m), rounded by
    the named lattice kernel ``kind`` (1 cubic, 2 FCC, 3 BCC, 4 hexagonal prism) with the
    arguments ``a``, ``b``, ``ginv`` that :func:`planner.lattice.quantize.run_named` gives it
    (its :func:`~planner.lattice.quantize.named_scalars`)
    (:meth:`planner.lattice.Lattice.point_rounding`): the cell ``Lattice.quantize`` returns.
    Returns whether it is in bounds and free (one lookup)."""
    x = np.empty((1, 3), np.float64)
    x[0, 0] = x0
    x[0, 1] = x1
    x[0, 2] = x2
    out = np.empty((1, 3), np.int64)
    qk.quantize_code(kind, a, b, ginv, x, out)
    cell[0] = out[0, 0]
    cell[1] = out[0, 1]
    cell[2] = out[0, 2]
    return occ_free(occ, out[0, 0], out[0, 1], out[0, 2])


@njit_cached
def point_cells(occ, kind, a, b, ginv, x0, x1, x2, y0, y1, y2, cells):
    # pragma: no cover - compiled
    """:func:`point_cell` of two points, (x0, x1, x2) and (y0, y1, y2) (m), in one call (a
    plan's start and goal): their cells in rows 0 and 1 of ``cells`` (2, 3) int64. Returns
    whether each is in bounds and free as bit 0 (the first) and bit 1 (two lookups)."""
    x = np.empty((2, 3), np.float64)
    x[0, 0] = x0
    x[0, 1] = x1
    x[0, 2] = x2
    x[1, 0] = y0
    x[1, 1] = y1
    x[1, 2] = y2
    qk.quantize_code(kind, a, b, ginv, x, cells)
    free = 0
    if occ_free(occ, cells[0, 0], cells[0, 1], cells[0, 2]):
        free = 1
    if occ_free(occ, cells[1, 0], cells[1, 1], cells[1, 2]):
        free |= 2
    return free


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


