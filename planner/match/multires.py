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

    def score(self, pts: np.ndarray, wts: np.ndarray, rots: np.ndarray, trans: np.ndarray,
              rounding: str = "auto") -> np.ndarray:
        """(M,) scores of the poses (:meth:`MultiResVoxelList.score`; contiguous float
        arrays of checked shapes, as the matcher's loop passes them)."""
        cq = self.cosets
        if rounding == "auto":
            rounding = "generic" if cq is None else "cosets"
        out = np.empty(len(rots))
        if rounding == "cosets":
            if cq is None:
                raise LatticeError("this lattice has no coset rounding: use 'generic'")
            # the box frame folded into the poses: y = F (R p + t)
            _kernels.score_poses_cosets(pts, wts, np.ascontiguousarray(cq.frame @ rots),
                                        np.ascontiguousarray(trans @ cq.frame.T),
                                        cq.inv_sides, cq.sides, cq.shifts, cq.index_basis,
                                        cq.index_offsets, self.table, self.bits, out)
        elif rounding == "generic":
            _kernels.score_poses(pts, wts, rots, trans, *self.tables, self.table, self.bits,
                                 out)
        elif rounding == "cubic":
            g = self.lattice.generator
            if not np.array_equal(g, g[0, 0] * np.eye(3)) or g[0, 0] <= 0:
                raise LatticeError("rounding 'cubic' needs an axis-aligned cubic lattice, "
                                   f"got {self.lattice.name or 'a custom lattice'}")
            _kernels.score_poses_cubic(pts, wts, rots, trans, 1.0 / g[0, 0], self.table,
                                       self.bits, out)
        else:
            raise LatticeError(f"rounding must be auto, cosets, generic or cubic, got "
                               f"{rounding!r}")
        return out


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

    def score(self, points: np.ndarray, rotations: np.ndarray, translations: np.ndarray,
              level: int = 0, weights: np.ndarray | None = None,
              rounding: str = "auto") -> np.ndarray:
        """The match score of each pose: the summed weights of the ``points`` that the pose
        moves into occupied cells of ``level``, in one compiled pass (no (N, 3) temporary
        per pose).

        Parameters
        ----------
        points : array_like, shape (N, 3)
            Source points, metres.
        rotations : array_like, shape (M, 3, 3)
            Each pose's rotation (applied as ``R @ p + t``).
        translations : array_like, shape (M, 3)
            Each pose's translation, metres.
        level : int
            The level scored (0 = finest).
        weights : array_like, shape (N,), optional
            Each point's weight (default 1: the score counts points).
        rounding : {"auto", "cosets", "generic", "cubic"}
            How a moved point finds its cell; every choice gives the same scores.
            ``"cosets"``: the nearest of the box sublattice's coset roundings
            (:mod:`planner.lattice.cosets`, what :func:`planner.match.match` uses);
            ``"generic"``: the exact generic quantizer of :meth:`planner.Lattice.quantizer`
            (any lattice); ``"cubic"``: ``rint(x / side)`` per axis, only for an
            axis-aligned cubic lattice; ``"auto"``: cosets where the lattice has them,
            else generic.

        Returns
        -------
        ndarray, shape (M,)
            The score of each pose.

        Raises
        ------
        MapError
            Arrays of the wrong shape, or a level out of range.
        LatticeError
            A rounding the level's lattice does not support.
        """
        pts = np.ascontiguousarray(np.asarray(points, dtype=float))
        rots = np.ascontiguousarray(np.asarray(rotations, dtype=float))
        trans = np.ascontiguousarray(np.asarray(translations, dtype=float))
        if pts.ndim != 2 or pts.shape[1] != 3:
            raise MapError(f"points must have shape (N, 3), got {pts.shape}")
        if rots.ndim != 3 or rots.shape[1:] != (3, 3) or trans.shape != (len(rots), 3):
            raise MapError(f"rotations (M, 3, 3) and translations (M, 3) expected, got "
                           f"{rots.shape} and {trans.shape}")
        if int(level) != level or not 0 <= level < self.levels:
            raise MapError(f"level must be in 0..{self.levels - 1}, got {level!r}")
        wts = (np.ones(len(pts)) if weights is None
               else np.ascontiguousarray(np.asarray(weights, dtype=float)))
        if wts.shape != (len(pts),):
            raise MapError(f"weights must have shape ({len(pts)},), got {wts.shape}")
        return self._levels[int(level)].score(pts, wts, rots, trans, rounding)

    def __repr__(self) -> str:
        counts = ", ".join(str(len(v)) for v in self.voxels)
        return f"MultiResVoxelList({self.lattice.name or 'custom'}, cells per level [{counts}])"
