"""The cell sets of :class:`planner.World`: which cells are blocked and which meet unknown
space, stored compactly, and the ways to change them.

Dense storage keeps them as bits over the world's index box (:func:`index_box`,
:class:`planner.occupancy.bits.BoxBits`): ``_free`` (in bounds and not blocked; the
occupancy lookups read it) and ``_unknown``; hash storage keeps the in-bounds blocked cells
as an (M, 3) list ``_blocked`` and the unknown ones as sorted keys. Lists of cells are views
made on request (24 bytes a cell).
"""

from __future__ import annotations

import numpy as np

from planner.errors import PlanError
from planner.occupancy import bits as ob
from planner.occupancy.bits import BoxBits
from planner.occupancy.keys import check_range, pack, unique_keys
from planner.occupancy.walk import as_cells, c_array
from planner.world.unknown import SortedKeys

__all__ = ["CellSets", "index_box"]


class CellSets:
    """Mixin of :class:`planner.World` (needs ``_free``, ``_blocked``, ``_unknown``,
    ``_lattice``, ``_checker``, ``_tol_bounds`` and ``in_bounds``)."""

    _free: BoxBits | None
    _blocked: np.ndarray | None
    _unknown: BoxBits | SortedKeys

    @property
    def blocked(self) -> np.ndarray:
        """(M, 3) int64 blocked cells in bounds: dense storage, distinct and in ascending key
        order, made on each call (module docstring); hash storage, as given."""
        if self._free is None:
            return self._blocked
        return self.blocked_bits().cells()

    @property
    def n_blocked(self) -> int:
        """Number of distinct blocked cells in bounds."""
        if self._free is None:
            return len(unique_keys(pack(self._blocked))) if len(self._blocked) else 0
        return self.blocked_bits().count()

    def blocked_bits(self) -> BoxBits:
        """The in-bounds cells that are not free, as bits over the index box (dense
        storage; a new array of one bit per box cell)."""
        f = self._free
        inb = self.in_bounds_bits(f.lo, f.dims)
        np.bitwise_and(inb.bits, np.invert(f.bits), out=inb.bits)
        return inb

    @property
    def storage(self) -> str:
        """``"dense"`` or ``"hash"`` (module docstring)."""
        return "dense" if self._free is not None else "hash"

    @property
    def free_bits(self) -> BoxBits | None:
        """The free cells of a dense world as bits over its index box (shared, not a
        copy: the occupancy lookups read it); None for hash storage."""
        return self._free

    @property
    def unknown_bits(self) -> BoxBits | None:
        """The cells meeting unknown space as bits over the index box (dense storage;
        shared, not a copy); None for hash storage."""
        return self._unknown if isinstance(self._unknown, BoxBits) else None

    def block_cells(self, cells: np.ndarray) -> None:
        """Block the cells ``cells`` ((N, 3) int, duplicates and cells out of bounds fine)."""
        w = np.ascontiguousarray(cells, dtype=np.int64).reshape(-1, 3)
        if not len(w):
            return
        if self._free is not None:
            self._free.update(w, False)
            return
        check_range(w, w, 3)  # now, not inside a kernel
        self._blocked = np.concatenate([self._blocked, w[self.in_bounds(w)]])
        self._checker = None

    def add_unknown(self, cells: np.ndarray) -> None:
        """Add the cells ``cells`` ((N, 3) int) to those meeting unknown space (dense
        storage keeps the in-bounds ones)."""
        w = np.ascontiguousarray(cells, dtype=np.int64).reshape(-1, 3)
        if not len(w):
            return
        if isinstance(self._unknown, BoxBits):
            u = self._unknown
            u.update(w, True)
            np.bitwise_and(u.bits, self.in_bounds_bits(u.lo, u.dims).bits, out=u.bits)
            u.changed()
            return
        self._unknown = SortedKeys(unique_keys(np.concatenate([self._unknown.keys,
                                                              pack(w[self.in_bounds(w)])])))

    def block_marked(self, grid: np.ndarray, lo: np.ndarray, dims: np.ndarray, mask: int,
                     unknown: bool = False) -> None:
        """Block (or with ``unknown`` add to the unknown set) every cell marked in a byte
        grid: ``grid`` (prod(dims),) uint8 over the index box ``lo`` (3,), ``dims`` (3,) in
        C order, a cell marked where ``grid & mask`` is nonzero. The builder's path from
        its inflation grids into the world without a list of every cell (dense storage;
        hash storage takes the list)."""
        lo = np.ascontiguousarray(lo, np.int64)
        dims = np.ascontiguousarray(dims, np.int64)
        target = self._unknown if unknown else self._free
        if isinstance(target, BoxBits):
            ob.mark_from_grid(target.bits, target.lo, target.dims, grid, lo, dims, int(mask),
                              bool(unknown))
            if unknown:  # in bounds only, as the free cells
                inside = self.in_bounds_bits(target.lo, target.dims)
                np.bitwise_and(target.bits, inside.bits, out=target.bits)
            target.changed()  # bits written directly: any() asks again
            return
        flat = np.flatnonzero(grid & mask)
        w = np.stack(np.unravel_index(flat, tuple(int(x) for x in dims)), axis=1) + lo
        if unknown:
            self.add_unknown(w)
        else:
            self.block_cells(w)

    def _box(self) -> tuple[np.ndarray, np.ndarray]:
        """The index box (lo (3,), dims (3,), int64) holding every in-bounds cell."""
        return index_box(self._lattice.generator, *self._tol_bounds())

    def in_bounds_bits(self, lo: np.ndarray, dims: np.ndarray) -> BoxBits:
        """The in-bounds cells (centre in the bounds, with the tolerance) of the index box
        ``lo`` (3,), ``dims`` (3,) as bits (a new array)."""
        g = c_array(self._lattice.generator, float)
        blo, bhi = (c_array(x, float) for x in self._tol_bounds())
        out = BoxBits.empty(lo, dims)
        ob.fill_in_bounds(out.bits, out.lo, out.dims, g, blo, bhi)
        return out

    def set_cells(self, cells: np.ndarray, blocked: bool) -> np.ndarray:
        """Block or free cells in place (dense storage only), for incremental planning.

        Cells outside the bounds stay out of bounds (blocked). Returns the (K, 3) int64
        distinct cells whose state changed, the batch to pass to an incremental search.
        """
        w = np.unique(as_cells(cells), axis=0)
        if self._free is None:
            raise PlanError("set_cells needs dense occupancy storage (a smaller world)")
        w = np.ascontiguousarray(w[self.in_bounds(w)])
        return w[self._free.update(w, not blocked)]


def index_box(g: np.ndarray, blo: np.ndarray, bhi: np.ndarray
              ) -> tuple[np.ndarray, np.ndarray]:
    """The index box ``(lo, dims)`` ((3,) int64 each) holding every cell whose centre
    ``g @ w`` lies in ``[blo, bhi]`` (m), with a margin of one cell a side.

    Parameters
    ----------
    g : ndarray, shape (3, 3)
        Lattice generator (m).
    blo, bhi : ndarray, shape (3,)
        Bounds box (m), already widened by the tolerance.
    """
    corners = np.array([[(blo, bhi)[c][a] for a, c in enumerate(bits)]
                        for bits in np.ndindex(2, 2, 2)], dtype=float)
    w = corners @ np.linalg.inv(np.asarray(g, dtype=float)).T
    lo = np.floor(w.min(axis=0)).astype(np.int64) - 1
    hi = np.ceil(w.max(axis=0)).astype(np.int64) + 1
    return lo, hi - lo + 1
