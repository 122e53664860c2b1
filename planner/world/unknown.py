"""The unknown-space side of :class:`planner.World`: which cells meet unknown space, and why an
end point is blocked by it.

A world built from a tri-state map (:class:`planner.io.Obstacles`) keeps the set of cells
whose closed Voronoi cell meets unknown space (``_unknown``: bits over the world's index box,
:class:`planner.occupancy.bits.BoxBits`, or for a world too large for them the sorted packed
keys, :class:`SortedKeys`), its ``unknown_policy`` and its ``radius``; this mixin answers
the questions about them.
"""

from __future__ import annotations

import numpy as np

from planner.occupancy.keys import pack, unpack
from planner.occupancy.walk import as_cells
from planner.voxels import inflation_stencil

__all__ = ["SortedKeys", "UnknownSpace"]


class SortedKeys:
    """A cell set as sorted distinct packed keys (8 bytes a cell), with the interface of
    :class:`planner.occupancy.bits.BoxBits` (``count``, ``contains``, ``cells``).

    Parameters
    ----------
    keys : ndarray, shape (K,), int64
        Sorted distinct keys (:func:`planner.occupancy.keys.pack`).
    """

    def __init__(self, keys: np.ndarray):
        self.keys = keys

    def count(self) -> int:
        """Number of cells."""
        return len(self.keys)

    def any(self) -> bool:
        """The set is not empty."""
        return len(self.keys) > 0

    def contains(self, w: np.ndarray) -> np.ndarray:
        """(N,) bool: cell ``w[n]`` ((N, 3) int64) is in the set."""
        if not len(self.keys) or not len(w):
            return np.zeros(len(w), dtype=bool)
        k = pack(w)
        pos = np.minimum(np.searchsorted(self.keys, k), len(self.keys) - 1)
        return self.keys[pos] == k

    def cells(self) -> np.ndarray:
        """(K, 3) int64 cells in ascending key order."""
        return unpack(self.keys, 3)


class UnknownSpace:
    """Mixin of :class:`planner.World` (needs ``_unknown``, ``unknown_policy``,
    ``radius``, ``_lattice``)."""

    _unknown: SortedKeys
    unknown_policy: str
    radius: float

    @property
    def unknown(self) -> np.ndarray:
        """(U, 3) int64 cells whose closed Voronoi cell meets unknown space (empty when the
        map says nothing is unknown: a plain cloud, where everything not occupied is free),
        in ascending key order. Made on each call from the compact set (24 bytes a cell)."""
        return self._unknown.cells()

    @property
    def n_unknown(self) -> int:
        """Number of cells meeting unknown space."""
        return self._unknown.count()

    @property
    def has_unknown(self) -> bool:
        """Some cell meets unknown space (cheaper than counting them: every plan asks)."""
        return self._unknown.any()

    def is_unknown(self, indices: np.ndarray) -> np.ndarray:
        """(N,) bool: the cell meets unknown space (no lookup counted).

        Each cell's state is one of: *blocked* (not :meth:`is_free`: out of bounds, within
        the radius of an obstacle, or, under ``unknown_policy == "blocked"``, within the
        radius of unknown space), *unknown* (free to plan through only under the ``"free"``
        policy; this test) or *free* (observed free, or a plain cloud's non-occupied space).
        """
        return self._unknown.contains(as_cells(indices))

    @property
    def unknown_note(self) -> str:
        """One line saying how unknown space is treated, for results and reports."""
        if self.unknown_policy == "blocked":
            return "unknown space blocked (with the robot radius)"
        if not self.has_unknown:
            return "no free-space information: everything in bounds not occupied is free"
        return "unknown space planned through as free"

    def _near_unknown(self, cell: np.ndarray) -> bool:
        """Unknown space is blocked and the cell is unknown or within the radius of it."""
        if self.unknown_policy != "blocked" or not self.has_unknown:
            return False
        near = cell[None] + inflation_stencil(self._lattice, self.radius)
        return bool(self.is_unknown(near).any())

