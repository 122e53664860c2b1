"""Multi-resolution occupied voxel lists on any lattice (Ryde and Hu's data structure).

Level 0 is the finest; level ``k``'s generator is the finest one times ``scale**k`` (2 by
default, so each level's cells have 8x the volume of the next finer one). Each level is an
:class:`planner.voxels.OccupiedVoxelList` built from the same points in one pass (quantize,
pack, sort-unique), plus an open-addressing hash set of its keys for constant-time
membership in the matcher's compiled scoring loop.

Memory: per level, the sorted keys (8 bytes per occupied cell) and the hash table (8 bytes
per slot, 2 to 4 slots per cell: the next power of two at or above twice the cell count),
so 24 to 40 bytes per occupied cell; coarser levels hold far fewer cells than the finest
(about 4x fewer per level for surfaces), so the finest level dominates. :attr:`nbytes`
gives the exact figure. Build time is linear in the number of points per level (one
quantization of every point per level) plus a sort of the keys; it is measured, with the
memory, by ``python benchmarks/match_speed.py`` (``build`` rows).
"""

from __future__ import annotations

import math

import numpy as np

from planner.errors import LatticeError, MapError
from planner.lattice import Lattice, cosets
from planner.lattice.cosets import coset_quantizer
from planner.match import _kernels
from planner.match.refine import CellPlanes, cell_planes
from planner.occupancy.keys import build_key_set, pack
from planner.voxels import OccupiedVoxelList

__all__ = ["MultiResVoxelList", "level_lattices", "resolve_lattice"]


def resolve_lattice(lattice: str | Lattice, cell_volume: float) -> Lattice:
    """A named lattice scaled to ``cell_volume`` (m^3), or a given 3D :class:`Lattice`
    (its own cell volume; ``cell_volume`` is then ignored)."""
    if isinstance(lattice, Lattice):
        if lattice.dim != 3:
            raise LatticeError(f"scan matching needs a 3D lattice, got {lattice.dim}D")
        return lattice
    return Lattice.named(str(lattice), cell_volume)


def level_lattices(finest: Lattice, levels: int, scale: float = 2.0) -> list[Lattice]:
    """The lattice of each level, finest first: generator ``G * scale**k``."""
    if int(levels) != levels or levels < 1:
        raise LatticeError(f"levels must be a positive integer, got {levels!r}")
    if not (math.isfinite(scale) and scale > 1):
        raise LatticeError(f"scale must be a finite number above 1, got {scale!r}")
    return [Lattice(finest.generator * scale**k, name=finest.name) for k in range(levels)]


class _Level:
    """One resolution: the voxel list and its hash set."""

    def __init__(self, voxels: OccupiedVoxelList):
        self.voxels = voxels
        self.lattice = voxels.lattice
        n = max(len(voxels), 1)
        self.bits = max(4, int(math.ceil(math.log2(2 * n))))
        self.table = build_key_set(voxels.keys, 1 << self.bits)
        q = self.lattice.quantizer()
        self.tables = (q.basis, q.basis_inv, q.cand, q.cand_z, q.counts, q.reduction)
        self.cosets = coset_quantizer(self.lattice)  # None: the generic tables score
        self.side = self.lattice.cell_volume ** (1 / 3)


class MultiResVoxelList:
    """Occupied voxel lists of one point set at ``levels`` resolutions of one lattice.

    Parameters
    ----------
    points : array_like, shape (N, 3)
        Metres, N >= 1, finite.
    lattice : Lattice
        The finest level's 3D lattice (any generator).
    levels : int
        Number of resolutions, >= 1.
    scale : float
        Generator scale factor between successive levels (> 1).

    Examples
    --------
    >>> from planner.lattice import Lattice
    >>> pts = np.random.default_rng(0).uniform(-5, 5, (2000, 3))
    >>> mr = MultiResVoxelList(pts, Lattice.named("fcc", 0.001), levels=3)
    >>> [len(v) for v in mr.voxels][0] > len(mr.voxels[2])
    True
    """

    def __init__(self, points: np.ndarray, lattice: Lattice, levels: int = 4,
                 scale: float = 2.0):
        pts = np.ascontiguousarray(np.asarray(points, dtype=float))
        if pts.ndim != 2 or pts.shape[1] != 3:
            raise MapError(f"points must have shape (N, 3), got {pts.shape}")
        if not len(pts):
            raise MapError("point cloud is empty: nothing to match against")
        lattices = level_lattices(resolve_lattice(lattice, 1.0), levels, scale)
        self.scale = float(scale)
        self._levels = [_Level(OccupiedVoxelList.from_indices(cosets.quantize(lat, pts), lat))
                        for lat in lattices]
        self._points = pts
        self._planes: CellPlanes | None = None

    @property
    def levels(self) -> int:
        """Number of resolutions."""
        return len(self._levels)

    @property
    def lattice(self) -> Lattice:
        """The finest level's lattice."""
        return self._levels[0].lattice

    @property
    def voxels(self) -> list[OccupiedVoxelList]:
        """The voxel list of each level, finest first."""
        return [lv.voxels for lv in self._levels]

    @property
    def nbytes(self) -> int:
        """Bytes held: sorted keys plus hash tables of every level."""
        return sum(lv.voxels.nbytes + lv.table.nbytes for lv in self._levels)

    def level(self, k: int) -> _Level:
        """Level ``k`` (0 = finest) with its hash set and quantizer tables."""
        return self._levels[k]

    @property
    def plane_level(self) -> int:
        """The level whose cells carry the refinement's planes: 1 (the finest when there is
        one level; :mod:`planner.match.refine` says why)."""
        return min(1, self.levels - 1)

    def planes(self) -> CellPlanes:
        """The cell planes (:func:`planner.match.refine.cell_planes`) of
        :attr:`plane_level`, computed on first use and kept."""
        if self._planes is None:
            self._planes = cell_planes(self._points, self._levels[self.plane_level].lattice)
        return self._planes

    def contains(self, points: np.ndarray, level: int = 0) -> np.ndarray:
        """(N,) bool: whether each point ((N, 3), metres) falls in an occupied cell of
        ``level``."""
        lv = self._levels[level]
        keys = pack(cosets.quantize(lv.lattice, np.asarray(points, dtype=float)))
        return _kernels.contains_keys(lv.table, lv.bits, keys)

    def __repr__(self) -> str:
        counts = ", ".join(str(len(v)) for v in self.voxels)
        return f"MultiResVoxelList({self.lattice.name or 'custom'}, cells per level [{counts}])"
