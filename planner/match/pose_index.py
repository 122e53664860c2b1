"""Pose proximity on a lattice voxel list: "is this pose within r of any stored pose?"

The paper's loop-closure use of lattice voxel lists. Stored positions are bucketed by their
lattice cell: a compiled open-addressing hash map from the cell's packed key to a linked
list of the rows stored there (:mod:`planner.match._pose_kernels`). A query looks at the
cells whose centres lie within ``r + 2 R`` of the query's cell centre (``R`` the covering
radius: every point within ``r`` of the query lies in one of them), nearest first, and
tests the exact distance to the positions stored there, stopping at the first one within
``r``. With the cell volume tied to ``r`` (by default a cell of the lattice's shape whose
covering radius is ``r``), that is a fixed set of cells per query however many poses are
stored; where poses pile up, the query's own and nearest cells answer at their first
stored position. The worst case left is a query just outside a dense pile (every position
of the cells it reaches lies beyond ``r``): it reads them all.

Adding is amortised O(1): positions go into an array whose capacity doubles when full and
the hash map doubles when half full (each doubling moves what is stored once), so no add
copies the whole index. ``python benchmarks/pose_index_speed.py`` times queries and adds
from 1e3 to 1e6 poses, uniform and piled up, against scipy's cKDTree.
"""

from __future__ import annotations

import numpy as np

from planner.errors import PlannerError
from planner.lattice import Lattice, cosets
from planner.match import _pose_kernels
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
        offsets = np.asarray(self.lattice.voronoi.offsets_within(reach), dtype=np.int64)
        dist = np.linalg.norm(offsets @ self.lattice.generator.T, axis=1)
        self._offsets = np.ascontiguousarray(offsets[np.argsort(dist, kind="stable")])
        self._n = 0
        self._pos = np.zeros((16, 3))
        self._nxt = np.full(16, -1, dtype=np.int64)
        self._cells = 0
        self._tkeys = np.full(64, -1, dtype=np.int64)
        self._theads = np.full(64, -1, dtype=np.int64)
        self._bitmap = np.zeros(16, dtype=np.uint64)  # 16 bits per slot
        self._cq = cosets.coset_quantizer(self.lattice)

    def __len__(self) -> int:
        return self._n

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

    def _quantize(self, x: np.ndarray) -> np.ndarray:
        if self._cq is None:
            return self.lattice.quantize(x)
        return cosets.quantize_with(self._cq, x)

    def _reserve(self, n: int) -> None:
        """Room for ``n`` more rows and up to ``n`` more cells (capacities doubled)."""
        need = self._n + n
        if need > len(self._pos):
            cap = max(need, 2 * len(self._pos))
            pos = np.empty((cap, 3))
            pos[:self._n] = self._pos[:self._n]
            nxt = np.full(cap, -1, dtype=np.int64)
            nxt[:self._n] = self._nxt[:self._n]
            self._pos, self._nxt = pos, nxt
        slots = len(self._tkeys)
        while 2 * (self._cells + n) > slots:
            slots *= 2
        if slots != len(self._tkeys):
            keys = np.full(slots, -1, dtype=np.int64)
            heads = np.full(slots, -1, dtype=np.int64)
            bitmap = np.zeros(slots // 4, dtype=np.uint64)
            _pose_kernels.rehash(self._tkeys, self._theads, keys, heads, bitmap)
            self._tkeys, self._theads, self._bitmap = keys, heads, bitmap

    def add(self, poses) -> None:
        """Store positions: (N, 3) metres, or (N, 7) rows ``x, y, z, qx, qy, qz, qw``
        (the position is used). Amortised O(1) per position."""
        x = self._check(poses)
        if not len(x):
            return
        keys = pack(self._quantize(x))
        self._reserve(len(x))
        self._pos[self._n:self._n + len(x)] = x
        self._cells += _pose_kernels.insert(self._tkeys, self._theads, self._bitmap, self._nxt,
                                            keys, self._n)
        self._n += len(x)

    def near(self, poses) -> np.ndarray:
        """(N,) bool: whether each query position lies within ``radius`` of a stored one."""
        x = self._check(poses)
        out = np.zeros(len(x), dtype=bool)
        if self._n and len(x):
            _pose_kernels.near(x, self._quantize(x), self._offsets, self._pos, self._nxt,
                               self._tkeys, self._theads, self._bitmap, self.radius ** 2, out)
        return out
