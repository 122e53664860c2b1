"""The local frame of a world far from its map's origin (UTM, ECEF coordinates).

Lattice indices are packed into 21 bits per axis (:mod:`planner.occupancy.keys`), so a
world counted from the map's origin could only use cells of ``distance / 2**20``: 10 m for
a survey at 5.4e6 m. :func:`build_world <planner.world.build.build_world>` therefore builds
such a world in a local frame: the map moved by :func:`local_offset` (a lattice vector near
the centre of its box), so the index limit applies to the map's extent. Because the offset
is a lattice vector, the local cells are the map frame's own cells moved by it (cell
centres agree to float64 rounding), whatever box the offset was chosen from; because it is
near the data, ``point - offset`` is exact in float64 (the two are within a factor of two).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from planner.errors import MapError
from planner.lattice import Lattice

__all__ = ["FAR_CELLS", "LocalFrame", "local_offset", "shifted"]

#: a world box reaching farther from the origin than this many cell sizes is built in a
#: local frame (a sixteenth of the 2**20 index range: nearer maps keep the map's frame)
FAR_CELLS = 2**16


def local_offset(lattice: Lattice, bounds: np.ndarray) -> np.ndarray:
    """(3,) the local frame's origin for a world box (m): zero when the box lies within
    :data:`FAR_CELLS` cell sizes of the origin, else the lattice vector ``G @ n`` (integer
    ``n``) nearest the box's centre.

    Parameters
    ----------
    lattice : Lattice
        The 3D lattice of the world (a 2D map's prism: its z offset is then 0).
    bounds : ndarray, shape (2, 3)
        World box ``[min, max]`` in the map's frame (m).

    Examples
    --------
    >>> cubic = Lattice.named("cubic", 0.001)  # 0.1 m cells
    >>> local_offset(cubic, np.array([[0.0, 0, 0], [150, 150, 10]])).tolist()
    [0.0, 0.0, 0.0]
    >>> o = local_offset(cubic, np.array([[455000.0, 5410000, 320], [455150, 5410150, 330]]))
    >>> np.round(o, 6).tolist()
    [455075.0, 5410075.0, 325.0]
    """
    b = np.asarray(bounds, dtype=float)
    cell = 2.0 * lattice.packing_radius
    if np.abs(b).max() <= FAR_CELLS * cell:
        return np.zeros(3)
    g = lattice.generator
    n = np.rint(np.linalg.solve(g, b.mean(axis=0)))
    return g @ n


def shifted(obst, offset: np.ndarray):
    """The obstacles ``obst`` (a 3D :class:`planner.io.Obstacles`) in the local frame whose
    origin is ``offset`` (m): points, boxes, free boxes, sensor origins and bounds moved by
    ``-offset``."""
    def move(a):
        return None if a is None else np.asarray(a, dtype=float) - offset

    return dataclasses.replace(obst, points=move(obst.points), boxes=move(obst.boxes),
                               free_boxes=move(obst.free_boxes), origins=move(obst.origins),
                               bounds=move(obst.bounds))


class LocalFrame:
    """The frame part of :class:`planner.World`: where its local frame sits in the map's.

    Attributes
    ----------
    local_frame : bool
        The world has a non-zero :attr:`offset`.
    """

    def set_offset(self, offset) -> None:
        """Set :attr:`offset` ((3,) or (2,) m, None: zero); MapError unless finite."""
        if offset is None:
            o = np.zeros(3)
        else:
            o = np.asarray(offset, dtype=float).reshape(-1)
            if o.shape == (2,):
                o = np.append(o, 0.0)
            if o.shape != (3,) or not np.isfinite(o).all():
                raise MapError(f"offset must be three finite numbers (m), got {o.tolist()}")
        self._offset = o
        self.local_frame = bool(o.any())

    @property
    def offset(self) -> np.ndarray:
        """(3,) the local frame's origin in the map's frame (m): a map point ``p`` is the
        local point ``p - offset``."""
        return self._offset.copy()

    def to_local(self, points: np.ndarray) -> np.ndarray:
        """Map-frame points (m, shape (..., 3)) in the world's local frame (the same array
        when :attr:`offset` is zero)."""
        return points - self._offset if self.local_frame else points

    def to_map(self, points: np.ndarray) -> np.ndarray:
        """Local points (m, shape (..., 3)) in the map's frame (the same array when
        :attr:`offset` is zero)."""
        return points + self._offset if self.local_frame else points
