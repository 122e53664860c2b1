"""Bit-packed cell sets over an index box: the compact storage of a world's cells.

A set of lattice cells inside the index box ``lo + [0, dims)`` is a flat uint8 array of
``ceil(prod(dims) / 8)`` bytes: the cell at box offset ``(a, b, c)`` has flat index
``f = (a * dims[1] + b) * dims[2] + c`` (C order) and is bit ``f & 7`` of byte ``f >> 3``
(``numpy.packbits(..., bitorder="little")`` order). Bits past the last cell are 0.

The kernels here build such sets (:func:`fill_in_bounds`, :func:`mark_from_grid` from the
byte scratch grids the inflation kernels mark, :func:`set_cells`) and read them back
(:func:`get_cells`, :func:`list_cells`). :class:`planner.occupancy.grid.Occupancy` reads the
free set of a dense world this way; :class:`BoxBits` bundles an array with its box.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from planner._numba import njit_cached

__all__ = ["BoxBits", "fill_in_bounds", "get_cells", "line_range", "list_cells",
           "mark_from_grid", "n_bytes", "set_cells"]


def n_bytes(dims: np.ndarray) -> int:
    """Bytes of a bit set over an index box of ``dims`` (3,) cells."""
    return (int(np.prod(np.asarray(dims, dtype=np.int64))) + 7) // 8


@njit_cached(_nrt=False)
def _test(y, bound, mode):  # pragma: no cover - compiled
    """``y >= bound``, ``y > bound``, ``y <= bound`` or ``y < bound`` (``mode`` 0 to 3)."""
    if mode == 0:
        return y >= bound
    if mode == 1:
        return y > bound
    if mode == 2:
        return y <= bound
    return y < bound


@njit_cached(_nrt=False)
def _first_k(x, g, k0, k1, bound, mode):  # pragma: no cover - compiled
    """The first k of ``[k0, k1)`` passing ``_test(x + g * k, bound, mode)`` (k1 if none),
    for a test that fails and then passes as k grows. Float products and sums are monotone
    in k, so bisection with the very expression the cells use finds the same cells."""
    a, b = k0, k1
    while a < b:
        mid = (a + b) // 2
        if _test(x + g * mid, bound, mode):
            b = mid
        else:
            a = mid + 1
    return a


@njit_cached(_nrt=False)
def line_range(x, g, lo, hi, k0, k1):  # pragma: no cover - compiled
    """``(a, b)``: the k of ``[k0, k1)`` with ``lo <= x + g * k <= hi`` are ``[a, b)`` (one
    coordinate of the cell centres ``G w`` along a line of the last index, ``x`` the sum of
    the other two terms)."""
    if g == 0.0:
        y = x + g * k0
        return (k0, k1) if lo <= y <= hi else (k0, k0)
    if g > 0.0:  # y grows with k: from y >= lo until y > hi
        a = _first_k(x, g, k0, k1, lo, 0)
        return a, _first_k(x, g, a, k1, hi, 1)
    a = _first_k(x, g, k0, k1, hi, 2)  # y falls: from y <= hi until y < lo
    return a, _first_k(x, g, a, k1, lo, 3)


@njit_cached
def fill_in_bounds(bits, lo, dims, g, blo, bhi):  # pragma: no cover - compiled
    """Set the bit of every cell whose centre ``g @ w`` (m) lies in ``[blo, bhi]``; clear
    the others. ``bits`` (ceil(n / 8),) uint8 over the box ``lo`` (3,), ``dims`` (3,).
    A line of the last index holds one interval of such cells (:func:`line_range`)."""
    bits[:] = 0
    k0, k1 = lo[2], lo[2] + dims[2]
    for a in range(dims[0]):
        i = lo[0] + a
        for b in range(dims[1]):
            j = lo[1] + b
            ka, kb = k0, k1
            for r in range(3):
                ra, rb = line_range(g[r, 0] * i + g[r, 1] * j, g[r, 2], blo[r], bhi[r], ka, kb)
                ka, kb = max(ka, ra), min(kb, rb)
            row = (a * dims[1] + b) * dims[2] - k0
            for f in range(row + ka, row + kb):
                bits[f >> 3] |= np.uint8(1 << (f & 7))


@njit_cached
def mark_from_grid(bits, lo, dims, src, slo, sdims, mask, value):  # pragma: no cover
    """For every cell of the byte grid ``src`` (one uint8 per cell of the box ``slo``,
    ``sdims``, C order) with ``src & mask`` nonzero that lies in the box ``lo``, ``dims``:
    set its bit in ``bits`` (``value`` True) or clear it (False). Returns the number of
    marked source cells inside the box."""
    n = 0
    a0 = max(lo[0], slo[0])
    a1 = min(lo[0] + dims[0], slo[0] + sdims[0])
    b0 = max(lo[1], slo[1])
    b1 = min(lo[1] + dims[1], slo[1] + sdims[1])
    c0 = max(lo[2], slo[2])
    c1 = min(lo[2] + dims[2], slo[2] + sdims[2])
    for i in range(a0, a1):
        for j in range(b0, b1):
            s = ((i - slo[0]) * sdims[1] + (j - slo[1])) * sdims[2] - slo[2]
            f = ((i - lo[0]) * dims[1] + (j - lo[1])) * dims[2] - lo[2]
            for k in range(c0, c1):
                if src[s + k] & mask:
                    n += 1
                    t = f + k
                    if value:
                        bits[t >> 3] |= np.uint8(1 << (t & 7))
                    else:
                        bits[t >> 3] &= np.uint8(~(1 << (t & 7)) & 0xFF)
    return n


@njit_cached
def set_cells(bits, lo, dims, w, value, changed):  # pragma: no cover - compiled
    """Set (``value`` True) or clear the bits of the cells ``w`` (N, 3) int64 inside the
    box; ``changed[n]`` says whether cell n's bit flipped (cells outside: False)."""
    for n in range(w.shape[0]):
        a = w[n, 0] - lo[0]
        b = w[n, 1] - lo[1]
        c = w[n, 2] - lo[2]
        changed[n] = False
        if 0 <= a < dims[0] and 0 <= b < dims[1] and 0 <= c < dims[2]:
            f = (a * dims[1] + b) * dims[2] + c
            m = np.uint8(1 << (f & 7))
            had = (bits[f >> 3] & m) != 0
            if had != value:
                changed[n] = True
                if value:
                    bits[f >> 3] |= m
                else:
                    bits[f >> 3] &= np.uint8(~m & 0xFF)


@njit_cached
def get_cells(bits, lo, dims, w, out):  # pragma: no cover - compiled
    """``out[n]`` = cell ``w[n]`` (N, 3) int64 lies in the box and its bit is set."""
    for n in range(w.shape[0]):
        a = w[n, 0] - lo[0]
        b = w[n, 1] - lo[1]
        c = w[n, 2] - lo[2]
        if 0 <= a < dims[0] and 0 <= b < dims[1] and 0 <= c < dims[2]:
            f = (a * dims[1] + b) * dims[2] + c
            out[n] = (bits[f >> 3] >> (f & 7)) & 1 != 0
        else:
            out[n] = False


@njit_cached
def list_cells(bits, lo, dims, out):  # pragma: no cover - compiled
    """Indices of the set cells in C order (ascending packed keys) into ``out`` (M, 3)
    int64, M at least their number. Returns the number written."""
    n = 0
    plane = dims[1] * dims[2]
    for q in range(bits.shape[0]):
        v = bits[q]
        if v == 0:
            continue
        for t in range(8):
            if (v >> t) & 1:
                f = q * 8 + t
                out[n, 0] = lo[0] + f // plane
                out[n, 1] = lo[1] + (f // dims[2]) % dims[1]
                out[n, 2] = lo[2] + f % dims[2]
                n += 1
    return n


_POPCOUNT = np.array([bin(i).count("1") for i in range(256)], dtype=np.int64)


@dataclass
class BoxBits:
    """A cell set as bits over an index box (module docstring).

    Attributes
    ----------
    lo : ndarray, shape (3,), int64
        Lowest cell index of the box.
    dims : ndarray, shape (3,), int64
        Box size in cells.
    bits : ndarray, shape (ceil(prod(dims) / 8),), uint8
    """

    lo: np.ndarray
    dims: np.ndarray
    bits: np.ndarray
    _any: bool | None = field(default=None, repr=False, compare=False)

    @classmethod
    def empty(cls, lo: np.ndarray, dims: np.ndarray) -> BoxBits:
        """The empty set over the box."""
        return cls(np.ascontiguousarray(lo, np.int64), np.ascontiguousarray(dims, np.int64),
                   np.zeros(n_bytes(dims), np.uint8))

    def count(self) -> int:
        """Number of cells in the set."""
        return int(_POPCOUNT[self.bits].sum()) if self.bits.size < 1 << 24 else sum(
            int(_POPCOUNT[self.bits[i:i + (1 << 24)]].sum())
            for i in range(0, self.bits.size, 1 << 24))

    def any(self) -> bool:
        """The set is not empty. Remembered until :meth:`update` or :meth:`changed`: every
        plan asks, and a scan costs time proportional to the box."""
        if self._any is None:
            self._any = bool(np.count_nonzero(self.bits))
        return self._any

    def changed(self) -> None:
        """Forget what :meth:`any` remembered; call after writing :attr:`bits` directly."""
        self._any = None

    def contains(self, w: np.ndarray) -> np.ndarray:
        """(N,) bool: cell ``w[n]`` ((N, 3) int64, C-contiguous) is in the set."""
        out = np.empty(len(w), dtype=np.bool_)
        get_cells(self.bits, self.lo, self.dims, w, out)
        return out

    def cells(self) -> np.ndarray:
        """(M, 3) int64 cells of the set in ascending packed-key order (24 bytes each:
        made on each call)."""
        out = np.empty((self.count(), 3), dtype=np.int64)
        list_cells(self.bits, self.lo, self.dims, out)
        return out

    def update(self, w: np.ndarray, value: bool) -> np.ndarray:
        """Add (``value`` True) or remove cells ``w`` (N, 3) int64 in the box; returns the
        (N,) bool mask of those whose membership changed."""
        changed = np.empty(len(w), dtype=np.bool_)
        self._any = None
        set_cells(self.bits, self.lo, self.dims, np.ascontiguousarray(w, np.int64),
                  bool(value), changed)
        return changed
