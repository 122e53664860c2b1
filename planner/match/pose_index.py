"""Pose proximity on a lattice voxel list: "is this pose within r of any stored pose?"

The paper's loop-closure use of lattice voxel lists. Stored positions are bucketed by their
lattice cell (a dict from packed key to the row numbers in that cell). A query looks at the
cells whose centres lie within ``r + 2 R`` of the query's cell centre (``R`` the covering
radius: every point within ``r`` of the query lies in one of them) and tests the exact
distance to the positions stored there. With the cell volume tied to ``r`` (by default a
cell of the lattice's shape whose covering radius is ``r``), that is a fixed set of cells
per query: constant time however many poses are stored, as long as poses are not piled up
far denser than one per cell.
"""

from __future__ import annotations

import numpy as np

from planner.errors import PlannerError
from planner.lattice import Lattice
from planner.occupancy.keys import pack

__all__ = ["PoseIndex"]


class PoseIndex:
    """Stored positions (the translation part of poses) on a lattice voxel list.

    Parameters
    ----------
    radius : float
        Proximity radius r (metres), > 0.
    lattice : str
        Named lattice (``cubic``, ``bcc``, ``fcc``, ``mcc``, ``hex``).
    cell_volume : float, optional
        Cell volume (m^3); default: the cell whose covering radius equals ``radius``.

    Examples
    --------
    >>> idx = PoseIndex(0.5)
    >>> idx.add([[0.0, 0.0, 0.0], [3.0, 0.0, 0.0]])
    >>> idx.near([[0.3, 0.2, 0.0], [1.5, 0.0, 0.0]]).tolist()
    [True, False]
    """

    def __init__(self, radius: float, lattice: str = "fcc", cell_volume: float | None = None):
        r = float(radius)
        if not (np.isfinite(r) and r > 0):
            raise PlannerError(f"radius must be positive and finite, got {radius!r}")
        if cell_volume is None:
            unit = Lattice.named(lattice, 1.0)
            cell_volume = (r / unit.covering_radius) ** 3
        self.radius = r
        self.lattice = Lattice.named(lattice, cell_volume)
        reach = r + 2 * self.lattice.covering_radius
        self._offsets = self.lattice.voronoi.offsets_within(reach)
        self._cells: dict[int, list[int]] = {}
        self._pos = np.zeros((0, 3))

    def __len__(self) -> int:
        return len(self._pos)

    @property
    def cells_per_query(self) -> int:
        """Cells a query looks at (fixed by the lattice and the ratio of r to the cell)."""
        return len(self._offsets)

    def _check(self, poses) -> np.ndarray:
        x = np.asarray(poses, dtype=float)
        if x.ndim == 1:
            x = x[None]
        if x.ndim != 2 or x.shape[1] not in (3, 4, 7) and x.shape[-2:] != (4, 4):
            raise PlannerError(f"poses must be (N, 3) positions or (N, 7) x,y,z,qx,qy,qz,qw "
                               f"rows, got shape {x.shape}")
        x = x[:, :3]
        if not np.isfinite(x).all():
            raise PlannerError("poses contain NaN or infinite coordinates")
        return np.ascontiguousarray(x)

    def add(self, poses) -> None:
        """Store positions: (N, 3) metres, or (N, 7) rows ``x, y, z, qx, qy, qz, qw``
        (the position is used)."""
        x = self._check(poses)
        keys = pack(self.lattice.quantize(x))
        base = len(self._pos)
        for i, k in enumerate(keys.tolist()):
            self._cells.setdefault(k, []).append(base + i)
        self._pos = np.concatenate([self._pos, x])

    def near(self, poses) -> np.ndarray:
        """(N,) bool: whether each query position lies within ``radius`` of a stored one."""
        x = self._check(poses)
        w = self.lattice.quantize(x)
        out = np.zeros(len(x), dtype=bool)
        r2 = self.radius ** 2
        for i in range(len(x)):
            for k in pack(w[i] + self._offsets).tolist():
                rows = self._cells.get(k)
                if rows is not None and (((self._pos[rows] - x[i]) ** 2).sum(axis=1)
                                         <= r2).any():
                    out[i] = True
                    break
        return out
