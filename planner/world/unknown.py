"""The unknown-space side of :class:`planner.World`: which cells meet unknown space, and why an
end point is blocked by it.

A world built from a tri-state map (:class:`planner.io.Obstacles`) keeps the sorted packed
keys of the cells whose closed Voronoi cell meets unknown space (``_unknown_keys``), its
``unknown_policy`` and its ``radius``; this mixin answers the questions about them.
"""

from __future__ import annotations

import numpy as np

from planner.occupancy.keys import pack, unpack

__all__ = ["UnknownSpace"]


class UnknownSpace:
    """Mixin of :class:`planner.World` (needs ``_unknown_keys``, ``unknown_policy``,
    ``radius``, ``_lattice``)."""

    _unknown_keys: np.ndarray
    unknown_policy: str
    radius: float

    @property
    def unknown(self) -> np.ndarray:
        """(U, 3) int64 cells whose closed Voronoi cell meets unknown space (empty when the
        map says nothing is unknown: a plain cloud, where everything not occupied is free)."""
        return unpack(self._unknown_keys, 3)

    @property
    def n_unknown(self) -> int:
        """Number of cells meeting unknown space."""
        return len(self._unknown_keys)

    def is_unknown(self, indices: np.ndarray) -> np.ndarray:
        """(N,) bool: the cell meets unknown space (no lookup counted).

        Each cell's state is one of: *blocked* (not :meth:`is_free`: out of bounds, within
        the radius of an obstacle, or, under ``unknown_policy == "blocked"``, within the
        radius of unknown space), *unknown* (free to plan through only under the ``"free"``
        policy; this test) or *free* (observed free, or a plain cloud's non-occupied space).
        """
        from planner.occupancy.walk import as_cells

        w = as_cells(indices)
        if not len(self._unknown_keys) or not len(w):
            return np.zeros(len(w), dtype=bool)
        k = pack(w)
        pos = np.minimum(np.searchsorted(self._unknown_keys, k), len(self._unknown_keys) - 1)
        return self._unknown_keys[pos] == k

    @property
    def unknown_note(self) -> str:
        """One line saying how unknown space is treated, for results and reports."""
        if self.unknown_policy == "blocked":
            return "unknown space blocked (with the robot radius)"
        if not len(self._unknown_keys):
            return "no free-space information: everything in bounds not occupied is free"
        return "unknown space planned through as free"

    def _near_unknown(self, cell: np.ndarray) -> bool:
        """Unknown space is blocked and the cell is unknown or within the radius of it."""
        if self.unknown_policy != "blocked" or not len(self._unknown_keys):
            return False
        from planner.voxels import inflation_stencil

        near = cell[None] + inflation_stencil(self._lattice, self.radius)
        return bool(self.is_unknown(near).any())

