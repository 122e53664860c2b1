"""The occupied voxel list: storage, membership, construction from points and boxes, files.

An :class:`OccupiedVoxelList` is a sorted array of unique packed keys
(:mod:`planner.occupancy.keys`), 8 bytes per occupied cell, queried with
``np.searchsorted``. Keys sort lexicographically by index, so the list is also a sorted index list.

Robot-radius inflation (:meth:`OccupiedVoxelList.inflate`) and the exact (tight) sets for
points and boxes live in :mod:`planner.voxels.inflate`.

File layout (``.npz``, written atomically by :meth:`OccupiedVoxelList.save`), version 1:

==============  =============  ===========================================================
field           dtype, shape   meaning
==============  =============  ===========================================================
``format``      str, ()        ``"planner.OccupiedVoxelList"``
``version``     int64, ()      1
``dim``         int64, ()      lattice dimension d (2 or 3)
``lattice``     str, ()        lattice name (``""`` for an unnamed lattice)
``generator``   float64 (d,d)  lattice generator, columns are basis vectors (m)
``keys``        int64, (M,)    strictly increasing packed keys of the occupied cells
==============  =============  ===========================================================
"""

from __future__ import annotations

import contextlib
import os
import tempfile
import zipfile
from pathlib import Path

import numpy as np

from planner.checks import check_radius
from planner.errors import MapError
from planner.fsutil import file_mode
from planner.lattice import Lattice
from planner.occupancy.keys import BITS, index_limit, pack, unique_keys, unpack
from planner.voxels._checks import (
    DEFAULT_BUDGET,
    as_indices,
    as_points,
    check_lattice,
)
from planner.voxels.boxes import box_cell_keys
from planner.voxels.stencil import stencil_inflation

__all__ = ["OccupiedVoxelList", "FORMAT", "VERSION"]

FORMAT = "planner.OccupiedVoxelList"
VERSION = 1


# -- the voxel list ---------------------------------------------------------------------------
class OccupiedVoxelList:
    """A set of occupied lattice cells.

    Storage: a sorted array of unique int64 packed keys (:mod:`planner.occupancy.keys`),
    **8 bytes per occupied cell** at rest (:attr:`nbytes`); membership is a binary search
    (``np.searchsorted``), O(log M) per query, vectorised.

    Parameters
    ----------
    lattice : Lattice
        2D or 3D lattice the indices refer to.
    indices : array_like of int, shape (M, d)
        Occupied cells; duplicates are removed.

    Examples
    --------
    >>> lat = Lattice.named("fcc", 0.001)
    >>> occ = OccupiedVoxelList.from_points(np.random.rand(1000, 3), lat)
    >>> blocked = occ.inflate(0.2)  # robot of radius 0.2 m
    >>> bool(blocked.contains(occ.indices).all())
    True
    """

    def __init__(self, lattice: Lattice, indices: np.ndarray):
        self._lattice = check_lattice(lattice)
        w = as_indices(indices, lattice.dim)
        self._keys = unique_keys(pack(w))

    @classmethod
    def _from_keys(cls, lattice: Lattice, keys: np.ndarray) -> OccupiedVoxelList:
        """Wrap already sorted unique keys (no copy, no checks)."""
        obj = cls.__new__(cls)
        obj._lattice = lattice
        obj._keys = np.ascontiguousarray(keys, dtype=np.int64)
        return obj

    # -- construction ---------------------------------------------------------------------
    @classmethod
    def from_indices(cls, indices: np.ndarray, lattice: Lattice) -> OccupiedVoxelList:
        """Same as ``OccupiedVoxelList(lattice, indices)``."""
        return cls(lattice, indices)

    @classmethod
    def from_points(cls, points: np.ndarray, lattice: Lattice) -> OccupiedVoxelList:
        """The cells containing the points (exact nearest lattice point).

        Parameters
        ----------
        points : array_like, shape (N, d)
            Obstacle points in metres, N >= 1, finite.
        lattice : Lattice
        """
        lat = check_lattice(lattice)
        x = as_points(points, lat.dim)
        if not len(x):
            raise MapError("point cloud is empty: no obstacle points to voxelise")
        return cls._from_keys(lat, unique_keys(pack(lat.quantize(x))))

    @classmethod
    def from_obstacles(cls, obst, lattice: Lattice) -> OccupiedVoxelList:
        """Cells of an :class:`planner.io.Obstacles`: points are quantized; each box (solid
        axis-aligned cube of edge ``obst.box_sizes[i]``) gives exactly the cells whose
        Voronoi cell overlaps it with positive volume (:func:`box_keys`; compiled, in bulk).

        Every point of a closed box then lies in the closed Voronoi cell of one of its cells,
        which is all :meth:`inflate`'s guarantee needs. Cells that merely touch a box face
        are left out, so a ``.3dmap`` on the unit cubic lattice gives exactly its voxels.

        Parameters
        ----------
        obst : planner.io.Obstacles
            3D obstacles (points and/or boxes, metres).
        lattice : Lattice
            A 3D lattice.
        """
        lat = check_lattice(lattice)
        if lat.dim != 3:
            raise MapError(f"obstacles are 3D; got a {lat.dim}D lattice")
        pts = as_points(obst.points, 3, f"{obst.source}: points")
        boxes = as_points(obst.boxes, 3, f"{obst.source}: box centres")
        parts = [unique_keys(pack(lat.quantize(pts)))] if len(pts) else []
        if len(boxes):
            half = np.asarray(obst.box_sizes, dtype=float)[:, None] / 2  # per leaf size
            parts.append(box_cell_keys(boxes - half, boxes + half, lat))
        if not parts:
            return cls._from_keys(lat, np.zeros(0, dtype=np.int64))
        return cls._from_keys(lat, unique_keys(np.concatenate(parts)))

    def add_points(self, points: np.ndarray) -> OccupiedVoxelList:
        """Add the cells containing ``points`` ((N, d), metres) in place; returns self.

        The new keys are merged into the sorted array (O(M + N log N)), not re-sorted."""
        x = as_points(points, self.dim)
        if not len(x):
            return self
        new = unique_keys(pack(self._lattice.quantize(x)))
        pos = np.searchsorted(self._keys, new)
        hit = pos < len(self._keys)
        hit[hit] = self._keys[pos[hit]] == new[hit]
        self._keys = np.insert(self._keys, pos[~hit], new[~hit])
        return self

    # -- queries ----------------------------------------------------------------------------
    @property
    def lattice(self) -> Lattice:
        return self._lattice

    @property
    def dim(self) -> int:
        return self._lattice.dim

    @property
    def keys(self) -> np.ndarray:
        """(M,) int64 sorted unique packed keys (read-only view)."""
        k = self._keys.view()
        k.setflags(write=False)
        return k

    @property
    def indices(self) -> np.ndarray:
        """(M, d) int64 occupied cells, sorted lexicographically (= by key)."""
        return unpack(self._keys, self.dim)

    @property
    def nbytes(self) -> int:
        """Bytes held: 8 per occupied cell."""
        return int(self._keys.nbytes)

    def __len__(self) -> int:
        return len(self._keys)

    def contains(self, indices: np.ndarray) -> np.ndarray:
        """(N,) bool: is each cell occupied? Indices beyond the key range are not.

        Parameters
        ----------
        indices : array_like of int, shape (N, d) or (d,)
        """
        w = as_indices(indices, self.dim)
        out = np.zeros(len(w), dtype=bool)
        if not len(w) or not len(self._keys):
            return out
        lim = index_limit(self.dim)
        ok = np.all((w >= -lim) & (w < lim), axis=1)
        q = pack(w if ok.all() else w[ok])
        found = _member(self._keys, q)
        if ok.all():
            return found
        out[ok] = found
        return out

    def centers(self) -> np.ndarray:
        """(M, d) float64 cell centres in metres."""
        return self._lattice.to_world(self.indices)

    def bounds(self) -> np.ndarray:
        """(2, d) ``[min, max]`` of the cell centres (m); MapError when empty."""
        if not len(self._keys):
            raise MapError("voxel list is empty: it has no bounds")
        c = self.centers()
        return np.stack([c.min(axis=0), c.max(axis=0)])

    def __eq__(self, other: object) -> bool:
        return (isinstance(other, OccupiedVoxelList) and self._lattice == other._lattice
                and np.array_equal(self._keys, other._keys))

    __hash__ = None  # mutable (add_points)

    def __repr__(self) -> str:
        return (f"OccupiedVoxelList({len(self)} cells, {self._lattice!r}, "
                f"{self.nbytes} bytes)")

    # -- inflation ----------------------------------------------------------------------------
    def inflate(self, radius: float, memory_budget: int | None = DEFAULT_BUDGET
                ) -> OccupiedVoxelList:
        """The cells a robot centre of radius ``radius`` (m) must not enter.

        Returns the occupied cells plus every cell ``c + delta`` (``c`` occupied, ``delta``
        in :func:`inflation_stencil`) whose closed Voronoi cell comes closer than ``radius``
        to the closed cell of an occupied cell.

        Guarantee: every obstacle point (or box point) lies in the closed Voronoi cell of an
        occupied cell. A path of straight segments between free cell centres that only
        touches free cells' closed Voronoi cells (``World.segment_free``) therefore stays at
        distance >= ``radius`` from every obstacle point. The result is conservative:
        :func:`exact_inflation` gives the tight set for points.

        Parameters
        ----------
        radius : float
            Robot radius, metres, >= 0.
        memory_budget : int
            Bytes the scratch grid plus the result may take (default: the memory
            budget of :mod:`planner.budget`).

        Raises
        ------
        MapError
            Bad radius, or the inflation would exceed ``memory_budget``.
        """
        r = check_radius(radius)
        if r == 0 or not len(self._keys):
            return OccupiedVoxelList._from_keys(self._lattice, self._keys.copy())
        keys = stencil_inflation(self._keys, self._lattice, r, memory_budget)
        return OccupiedVoxelList._from_keys(self._lattice, keys)

    # -- files --------------------------------------------------------------------------------
    def save(self, path: str | os.PathLike) -> None:
        """Write the list to ``path`` (``.npz``, layout in the module docstring), atomically:
        a temporary file in the same folder is renamed over ``path``; on failure nothing is
        left behind. MapError if the folder does not exist or cannot be written."""
        target = Path(path)
        if not target.parent.is_dir():
            raise MapError(f"{target}: cannot save, folder {target.parent} does not exist")
        lat = self._lattice
        fields = {
            "format": np.array(FORMAT),
            "version": np.array(VERSION, dtype=np.int64),
            "dim": np.array(lat.dim, dtype=np.int64),
            "lattice": np.array(lat.name or ""),
            "generator": np.asarray(lat.generator, dtype=np.float64),
            "keys": self._keys,
        }
        tmp = None
        try:
            fd, tmp = tempfile.mkstemp(prefix=f".{target.name}.", suffix=".tmp",
                                       dir=target.parent)
            with os.fdopen(fd, "wb") as fh:
                np.savez(fh, **fields)  # a file object: numpy does not append ".npz"
            os.chmod(tmp, file_mode())  # mkstemp makes 0600 files
            os.replace(tmp, target)
            tmp = None
        except OSError as exc:
            raise MapError(f"{target}: cannot save voxel list: {exc.strerror or exc}") from None
        finally:
            if tmp is not None:
                with contextlib.suppress(OSError):
                    os.unlink(tmp)

    @classmethod
    def load(cls, path: str | os.PathLike, lattice: Lattice | None = None
             ) -> OccupiedVoxelList:
        """Read a list written by :meth:`save`.

        Parameters
        ----------
        path : str or Path
        lattice : Lattice, optional
            Expected lattice; MapError if the file's generator differs. Default: rebuilt
            from the file.

        Raises
        ------
        MapError
            Missing, unreadable, corrupt or wrong-version file, or lattice mismatch.
        """
        p = Path(path)
        name = p.name
        try:
            with np.load(p, allow_pickle=False) as z:
                data = {k: z[k] for k in z.files}
        except FileNotFoundError:
            raise MapError(f"{name}: voxel list file not found") from None
        except (OSError, ValueError, zipfile.BadZipFile, EOFError, KeyError) as exc:
            # numpy calls any non-.npy/.npz bytes "pickled data": say what a user can act on
            why = "not an .npz archive" if "pickle" in str(exc) else str(exc).splitlines()[0]
            raise MapError(f"{name}: not a readable voxel list file ({why})") from None
        return cls._from_fields(data, name, lattice)

    @classmethod
    def _from_fields(cls, data: dict, name: str, lattice: Lattice | None) -> OccupiedVoxelList:
        need = ("format", "version", "dim", "lattice", "generator", "keys")
        missing = [k for k in need if k not in data]
        if missing:
            raise MapError(f"{name}: not a voxel list file (missing {', '.join(missing)})")
        if str(data["format"]) != FORMAT:
            raise MapError(f"{name}: not a voxel list file (format {str(data['format'])!r})")
        try:
            version = int(data["version"])
            dim = int(data["dim"])
        except (TypeError, ValueError):
            raise MapError(f"{name}: corrupt voxel list header") from None
        if version != VERSION:
            raise MapError(f"{name}: voxel list format version {version} is not supported "
                           f"(this version reads {VERSION})")
        g = data["generator"]
        keys = data["keys"]
        if dim not in BITS or g.shape != (dim, dim) or not np.isfinite(g).all():
            raise MapError(f"{name}: corrupt voxel list (bad dimension or generator)")
        if keys.ndim != 1 or keys.dtype != np.int64 or np.any(np.diff(keys) <= 0):
            raise MapError(f"{name}: corrupt voxel list (keys must be increasing int64)")
        saved = _saved_lattice(str(data["lattice"]), g, name)
        if lattice is not None:
            check_lattice(lattice)
            if lattice.dim != dim or not np.allclose(lattice.generator, g, rtol=1e-9,
                                                     atol=1e-12):
                raise MapError(f"{name}: map was saved with lattice {_label(saved)}, "
                               f"not {_label(lattice)}")
            saved = lattice
        return cls._from_keys(saved, keys)


def _member(keys: np.ndarray, q: np.ndarray, presorted: bool = False) -> np.ndarray:
    """(N,) bool: ``q`` in the sorted ``keys``. Large query sets are sorted first: numpy's
    binary search then reuses the previous position (cache-friendly, unlike random order)."""
    if len(q) > 4096 and not presorted:
        order = np.argsort(q)
        found = np.empty(len(q), dtype=bool)
        found[order] = _member(keys, q[order], presorted=True)
        return found
    pos = np.searchsorted(keys, q)
    pos[pos == len(keys)] = 0
    return keys[pos] == q


def _label(lat: Lattice) -> str:
    return f"{lat.name or 'custom'} (cell volume {lat.cell_volume:.6g})"


def _saved_lattice(name: str, g: np.ndarray, fname: str) -> Lattice:
    """The lattice of a file: the named one (its fast quantizer) when the generator is the
    named generator at some scale, else a generic lattice."""
    try:
        if name and g.shape == (3, 3):
            with contextlib.suppress(Exception):
                named = Lattice.named(name, abs(float(np.linalg.det(g))))
                if np.allclose(named.generator, g, rtol=1e-9, atol=1e-12):
                    return named
        return Lattice(g, name=name or None)
    except Exception as exc:  # LatticeError: singular generator etc.
        raise MapError(f"{fname}: corrupt voxel list (bad generator: {exc})") from None
