"""Occupied voxel lists on any lattice: storage, membership, box obstacles, inflation, files.

An :class:`OccupiedVoxelList` is a sorted array of unique packed keys (:mod:`planner.keys`),
8 bytes per occupied cell, queried with ``np.searchsorted``. Keys sort lexicographically by
index, so the list is also a sorted index list.

Robot-radius inflation (:meth:`OccupiedVoxelList.inflate`) is a Minkowski sum of the
occupied cells with a stencil of lattice offsets derived exactly from the Voronoi cell; the
exact (tight) set for obstacle points is :func:`exact_inflation`.

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
import math
import os
import tempfile
import zipfile
from pathlib import Path

import numpy as np

from planner import _voxel_kernels as vk
from planner.errors import MapError
from planner.fsutil import file_mode
from planner.keys import BITS, index_limit, pack, unpack
from planner.lattice import Lattice

__all__ = ["OccupiedVoxelList", "exact_inflation", "inflation_stencil", "FORMAT", "VERSION"]

FORMAT = "planner.OccupiedVoxelList"
VERSION = 1
DEFAULT_BUDGET = 2**30  # bytes of scratch + result an inflation may use
_REL_TOL = 1e-9  # geometric tolerance, relative to the cell diameter
_BOX_CHUNK_KEYS = 1 << 24  # candidate keys per box chunk (128 MB of int64)


def _unique_keys(keys: np.ndarray) -> np.ndarray:
    """Sorted unique int64 keys. Sort + mask: numpy 2.x ``np.unique`` hashes first and is
    ~15x slower on 10^6 keys."""
    k = np.sort(np.asarray(keys, dtype=np.int64))
    if len(k) < 2:
        return k
    keep = np.empty(len(k), dtype=bool)
    keep[0] = True
    np.not_equal(k[1:], k[:-1], out=keep[1:])
    return k[keep]


# -- input checks ---------------------------------------------------------------------------
def _check_lattice(lattice) -> Lattice:
    if not isinstance(lattice, Lattice):
        raise MapError(f"lattice must be a Lattice, got {type(lattice).__name__}")
    return lattice


def _as_points(points, dim: int, what: str = "points") -> np.ndarray:
    """(N, dim) finite float64 contiguous array, or MapError naming the problem."""
    try:
        x = np.asarray(points, dtype=float)
    except (TypeError, ValueError):
        raise MapError(f"{what} must be a numeric (N, {dim}) array") from None
    if x.ndim == 1 and x.shape[0] == dim:
        x = x[None, :]
    if x.ndim != 2 or x.shape[1] != dim:
        raise MapError(f"{what} must have shape (N, {dim}), got {x.shape}")
    if not np.isfinite(x).all():
        row = int(np.flatnonzero(~np.isfinite(x).all(axis=1))[0])
        raise MapError(f"{what} contain NaN or infinite coordinates (row {row})")
    return np.ascontiguousarray(x)


def _as_indices(indices, dim: int) -> np.ndarray:
    """(N, dim) int64 array, or MapError."""
    w = np.asarray(indices)
    if w.size == 0:
        return np.zeros((0, dim), dtype=np.int64)
    if w.ndim == 1 and w.shape[0] == dim:
        w = w[None, :]
    if w.ndim != 2 or w.shape[1] != dim:
        raise MapError(f"indices must have shape (N, {dim}), got {w.shape}")
    if not np.issubdtype(w.dtype, np.integer):
        raise MapError(f"indices must be integers, got dtype {w.dtype}")
    return np.ascontiguousarray(w, dtype=np.int64)


def _check_radius(radius) -> float:
    try:
        r = float(radius)
    except (TypeError, ValueError):
        raise MapError(f"radius must be a number of metres, got {radius!r}") from None
    if not math.isfinite(r) or r < 0:
        raise MapError(f"radius must be a non-negative finite number of metres, got {radius!r}")
    return r


def _gb(nbytes: float) -> str:
    return f"{nbytes / 2**30:.3g} GB"


# -- lattice geometry used here ---------------------------------------------------------------
def _cell_diameter(lat: Lattice) -> float:
    """Edge of a cube of the cell's volume (m): the unit of geometric tolerances."""
    return lat.cell_volume ** (1 / lat.dim)


def _cell_polytope(lat: Lattice) -> tuple[np.ndarray, ...]:
    """Voronoi cell of the origin as ``(A, b, e0, e1)`` for :func:`vk.cell_distance`.

    ``A`` (k, d) unit facet normals, ``b`` (k,) offsets (V = {y : A y <= b}); ``e0``, ``e1``
    (m, d) edge end points (in 2D the edges are the facets).
    """
    rel = lat.relevant_vectors
    n = np.linalg.norm(rel, axis=1)
    a = rel / n[:, None]
    b = n / 2
    verts = lat.voronoi_vertices
    tol = 1e-7 * _cell_diameter(lat)
    on = np.abs(verts @ a.T - b) < tol  # (nv, k): vertex lies on facet
    # Two vertices bound an edge iff they share d-1 facets (a face of dimension <= 1).
    shared = on.astype(np.int64) @ on.T.astype(np.int64)
    i, j = np.nonzero(np.triu(shared >= lat.dim - 1, k=1))
    return (np.ascontiguousarray(a), np.ascontiguousarray(b),
            np.ascontiguousarray(verts[i]), np.ascontiguousarray(verts[j]))


def _offsets_within(lat: Lattice, radius: float, budget: float, asked: float | None = None
                    ) -> np.ndarray:
    """All index offsets ``w`` with ``|G w| <= radius``; (n, d) int64.

    Enumerated over a box in the LLL-reduced basis (tight for skewed generators); MapError
    (naming the caller's radius ``asked``) when that box alone would exceed ``budget`` bytes.
    """
    geo = lat._geo  # same package: reuse the cached reduced basis
    b, t = geo["reduced"], geo["reduction"]
    k = np.ceil(radius * np.linalg.norm(np.linalg.inv(b), axis=1) + 1e-9).astype(np.int64)
    count = float(np.prod((2 * k + 1).astype(float)))
    if count * lat.dim * 8 * 3 > budget:
        raise _over_budget(radius if asked is None else asked, count * lat.dim * 8 * 3, budget)
    axes = [np.arange(-x, x + 1) for x in k]
    z = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, lat.dim)
    w = z @ t.T
    keep = np.linalg.norm(w @ lat.generator.T, axis=1) <= radius
    return np.ascontiguousarray(w[keep], dtype=np.int64)


def inflation_stencil(lat: Lattice, radius: float, memory_budget: float = DEFAULT_BUDGET
                      ) -> np.ndarray:
    """Offsets ``delta`` whose closed Voronoi cell comes closer than ``radius`` to V(0).

    For the point-symmetric convex cell V, ``dist(V, V + G delta) = 2 dist(G delta / 2, V)``
    (``V - V = 2V``); it is computed exactly. Candidates have ``|G delta| < r + 2 R`` (R the
    covering radius). The zero offset is always included.

    Parameters
    ----------
    lat : Lattice
    radius : float
        Metres, >= 0.

    Returns
    -------
    ndarray, shape (n, d), int64
        Zero offset first, then by world length.
    """
    r = _check_radius(radius)
    zero = np.zeros((1, lat.dim), dtype=np.int64)
    if r == 0:
        return zero
    cand = _offsets_within(lat, r + 2 * lat.covering_radius, memory_budget, r)
    a, b, e0, e1 = _cell_polytope(lat)
    tol = _REL_TOL * _cell_diameter(lat)
    half = np.ascontiguousarray(cand @ lat.generator.T / 2)
    dist = np.empty(len(cand))
    vk.cell_distances(half, a, b, e0, e1, tol, dist)
    # Conservative by tol: a pair at distance exactly r (up to rounding) is blocked.
    sel = cand[(2 * dist < r + tol) & np.any(cand != 0, axis=1)]
    order = np.argsort(np.linalg.norm(sel @ lat.generator.T, axis=1), kind="stable")
    return np.concatenate([zero, sel[order]])


def _key_offsets(offsets: np.ndarray) -> np.ndarray:
    """Key difference of each index offset: ``key(w + o) - key(w)`` when both are packable."""
    d = offsets.shape[1]
    bits = BITS[d]
    out = np.zeros(len(offsets), dtype=np.int64)
    for j in range(d):
        out += offsets[:, j].astype(np.int64) << (bits * (d - 1 - j))
    return out


def _check_range(lo: np.ndarray, hi: np.ndarray, dim: int) -> None:
    lim = index_limit(dim)
    if lo.min() < -lim or hi.max() >= lim:
        raise MapError(f"lattice indices exceed +-{lim} cells per axis; use a larger cell volume")


# -- the voxel list ---------------------------------------------------------------------------
class OccupiedVoxelList:
    """A set of occupied lattice cells.

    Storage: a sorted array of unique int64 packed keys (:mod:`planner.keys`), **8 bytes per
    occupied cell** at rest (:attr:`nbytes`); membership is a binary search
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
        self._lattice = _check_lattice(lattice)
        w = _as_indices(indices, lattice.dim)
        self._keys = _unique_keys(pack(w))

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
        lat = _check_lattice(lattice)
        x = _as_points(points, lat.dim)
        if not len(x):
            raise MapError("point cloud is empty: no obstacle points to voxelise")
        return cls._from_keys(lat, _unique_keys(pack(lat.quantize(x))))

    @classmethod
    def from_obstacles(cls, obst, lattice: Lattice) -> OccupiedVoxelList:
        """Cells of an :class:`planner.io.Obstacles`: points are quantized; each box (solid
        axis-aligned cube of edge ``obst.box_size``) gives exactly the cells whose Voronoi
        cell overlaps it with positive volume (:func:`box_keys`; compiled, in bulk).

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
        lat = _check_lattice(lattice)
        if lat.dim != 3:
            raise MapError(f"obstacles are 3D; got a {lat.dim}D lattice")
        pts = _as_points(obst.points, 3, f"{obst.source}: points")
        boxes = _as_points(obst.boxes, 3, f"{obst.source}: box centres")
        parts = [_unique_keys(pack(lat.quantize(pts)))] if len(pts) else []
        if len(boxes):
            parts.append(box_keys(boxes, obst.box_size, lat))
        if not parts:
            return cls._from_keys(lat, np.zeros(0, dtype=np.int64))
        return cls._from_keys(lat, _unique_keys(np.concatenate(parts)))

    def add_points(self, points: np.ndarray) -> OccupiedVoxelList:
        """Add the cells containing ``points`` ((N, d), metres) in place; returns self.

        The new keys are merged into the sorted array (O(M + N log N)), not re-sorted."""
        x = _as_points(points, self.dim)
        if not len(x):
            return self
        new = _unique_keys(pack(self._lattice.quantize(x)))
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
        w = _as_indices(indices, self.dim)
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
    def inflate(self, radius: float, memory_budget: int = DEFAULT_BUDGET) -> OccupiedVoxelList:
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
            Bytes the scratch grid plus the result may take (default 1 GiB).

        Raises
        ------
        MapError
            Bad radius, or the inflation would exceed ``memory_budget``.
        """
        r = _check_radius(radius)
        budget = float(memory_budget)
        if r == 0 or not len(self._keys):
            return OccupiedVoxelList._from_keys(self._lattice, self._keys.copy())
        lat = self._lattice
        stencil = inflation_stencil(lat, r, budget)
        full = lat.neighbors("full")
        w = self.indices
        ext = np.maximum(np.abs(stencil).max(axis=0), np.abs(full).max(axis=0))
        lo, hi = w.min(axis=0) - ext, w.max(axis=0) + ext
        _check_range(lo, hi, self.dim)
        # The result holds at least one whole stencil: a cheap lower bound for the budget.
        least = len(stencil) * 8
        dims = hi - lo + 1
        cells = float(np.prod(dims.astype(float)))
        if least > budget:
            raise _over_budget(r, least, budget)
        if cells + 8 * len(self._keys) <= budget:
            keys = _dilate_dense(self._keys, lo, dims, stencil, full, budget, r)
        else:
            keys = _dilate_keys(self._keys, stencil, full, budget, r)
        return OccupiedVoxelList._from_keys(lat, keys)

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
            raise MapError(f"{name}: not a readable voxel list file ({exc})") from None
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
            _check_lattice(lattice)
            if lattice.dim != dim or not np.allclose(lattice.generator, g, rtol=1e-9,
                                                     atol=1e-12):
                raise MapError(f"{name}: map was saved with lattice {_label(saved)}, "
                               f"not {_label(lattice)}")
            saved = lattice
        return cls._from_keys(saved, keys)


def _member(keys: np.ndarray, q: np.ndarray, presorted: bool = False) -> np.ndarray:
    """(N,) bool: ``q`` in the sorted ``keys``. Large query sets are sorted first: numpy's
    binary search then reuses the previous position, ~5x faster than random order."""
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


def _over_budget(radius: float, need: float, budget: float) -> MapError:
    return MapError(f"radius {radius:.6g} m needs ~{_gb(need)} for inflation, over the budget "
                    f"of {_gb(budget)}; use a larger cell volume or raise memory_budget")


# -- inflation back ends ------------------------------------------------------------------------
def _strides(dims: np.ndarray) -> np.ndarray:
    s = np.ones(len(dims), dtype=np.int64)
    for j in range(len(dims) - 2, -1, -1):
        s[j] = s[j + 1] * dims[j + 1]
    return s


def _dilate_dense(keys: np.ndarray, lo: np.ndarray, dims: np.ndarray, stencil: np.ndarray,
                  full: np.ndarray, budget: float, radius: float) -> np.ndarray:
    """Minkowski sum on a dense uint8 scratch grid over the padded index box."""
    d = len(dims)
    strides = _strides(dims)
    grid = np.zeros(int(np.prod(dims)), dtype=np.uint8)
    flat = np.empty(len(keys), dtype=np.int64)
    vk.flat_positions(keys, lo.astype(np.int64), strides, BITS[d], index_limit(d), flat)
    vk.dilate(grid, flat, stencil @ strides, full @ strides)
    n = int(np.count_nonzero(grid))
    if grid.nbytes + 8 * n > budget:
        raise _over_budget(radius, grid.nbytes + 8 * n, budget)
    out = np.empty(n, dtype=np.int64)
    vk.grid_keys(grid, lo.astype(np.int64), dims.astype(np.int64), BITS[d], index_limit(d), out)
    return out


def _dilate_keys(keys: np.ndarray, stencil: np.ndarray, full: np.ndarray, budget: float,
                 radius: float) -> np.ndarray:
    """Minkowski sum by key arithmetic in chunks (no scratch grid), for sparse huge boxes."""
    nb = _key_offsets(full)
    # Boundary cells: some full neighbour is free (interior cells add nothing, see vk.dilate).
    boundary = np.zeros(len(keys), dtype=bool)
    for o in nb:
        q = keys + o
        pos = np.minimum(np.searchsorted(keys, q), len(keys) - 1)
        boundary |= keys[pos] != q
    src = keys[boundary]
    sk = _key_offsets(stencil)
    chunk = max(1, int(budget / 4 / 8 / len(sk)))
    out = keys
    for s in range(0, len(src), chunk):
        part = _unique_keys((src[s: s + chunk, None] + sk[None, :]).ravel())
        out = _unique_keys(np.concatenate([out, part]))
        if out.nbytes * 2 > budget:
            raise _over_budget(radius, out.nbytes * 2, budget)
    return out


# -- boxes ----------------------------------------------------------------------------------------
def _separating_axes(lat: Lattice) -> np.ndarray:
    """Unit axes (one per +- pair) that decide whether a box and a Voronoi cell overlap:
    box face normals, cell facet normals and (3D) cross products of their edge directions."""
    d = lat.dim
    a, _, e0, e1 = _cell_polytope(lat)
    axes = [np.eye(d), a]
    if d == 3:
        edges = e1 - e0
        edges /= np.linalg.norm(edges, axis=1)[:, None]
        cr = np.cross(np.eye(3)[:, None, :], edges[None, :, :]).reshape(-1, 3)
        n = np.linalg.norm(cr, axis=1)
        axes.append(cr[n > 1e-9] / n[n > 1e-9, None])
    ax = np.concatenate(axes)
    # Canonical sign (first nonzero component positive), then drop duplicates.
    first = ax[np.arange(len(ax)), np.argmax(np.abs(ax) > 1e-9, axis=1)]
    ax = ax * np.sign(first)[:, None]
    _, keep = np.unique(np.round(ax, 9), axis=0, return_index=True)
    return np.ascontiguousarray(ax[np.sort(keep)])


def box_keys(centres: np.ndarray, size: float, lattice: Lattice) -> np.ndarray:
    """Sorted unique keys of the cells whose Voronoi cell overlaps a box (positive volume).

    Exact up to a tolerance of 1e-9 cell diameters: overlaps thinner than that (touching
    faces, edges, corners) do not count. The cell containing each box centre always counts.
    A box of size 0 is a point (its containing cell).

    Parameters
    ----------
    centres : ndarray, shape (M, d)
        Box centres (m).
    size : float
        Box edge length (m), >= 0.
    lattice : Lattice

    Returns
    -------
    ndarray, shape (K,), int64
    """
    lat = lattice
    d = lat.dim
    c = _as_points(centres, d, "box centres")
    s = float(size)
    if not math.isfinite(s) or s < 0:
        raise MapError(f"box size must be a non-negative number of metres, got {size!r}")
    if not len(c):
        return np.zeros(0, dtype=np.int64)
    tol = _REL_TOL * max(_cell_diameter(lat), s)
    axes = _separating_axes(lat)
    verts = lat.voronoi_vertices
    # Support of box + V along each axis. The kernel's "|s| < thr" with thr = support - tol
    # drops mere touching: aligned grids (.3dmap boxes on a cubic lattice) stay tight.
    thr = s / 2 * np.abs(axes).sum(axis=1) + np.abs(verts @ axes.T).max(axis=0) - tol
    big_r = lat.covering_radius
    r_out = s / 2 * math.sqrt(d) + big_r + tol
    r_in = s / 2 + lat.packing_radius - tol
    offs = _offsets_within(lat, r_out + big_r, DEFAULT_BUDGET)
    base = lat.quantize(c)
    if s == 0:
        return _unique_keys(pack(base))
    ext = np.abs(offs).max(axis=0)
    _check_range(base.min(axis=0) - ext, base.max(axis=0) + ext, d)
    base_keys = pack(base)
    resid = lat.to_world(base) - c
    offs_world = np.ascontiguousarray(offs @ lat.generator.T, dtype=float)
    offs_key = _key_offsets(offs)
    chunk = max(1, _BOX_CHUNK_KEYS // len(offs))
    parts = []
    buf = np.empty(min(chunk, len(c)) * len(offs), dtype=np.int64)
    for i in range(0, len(c), chunk):
        n = vk.box_cells(base_keys[i: i + chunk], np.ascontiguousarray(resid[i: i + chunk]),
                         offs_world, offs_key, axes, thr, r_in, r_out, buf)
        parts.append(_unique_keys(buf[:n]))  # per chunk: neighbouring boxes share cells
    parts.append(base_keys)  # the centre's cell, even for boxes thinner than the tolerance
    return _unique_keys(np.concatenate(parts))


# -- exact inflation ------------------------------------------------------------------------------
def exact_inflation(points: np.ndarray, lattice: Lattice, radius: float,
                    memory_budget: int = DEFAULT_BUDGET) -> OccupiedVoxelList:
    """The exact set of cells whose closed Voronoi cell is closer than ``radius`` to a point.

    Tight reference for :meth:`OccupiedVoxelList.inflate` (which is a superset when built
    from the same points): exact point-to-polytope distances, compiled, with ball bounds
    ``|y| - R <= dist <= |y| - rho`` deciding most candidates without them.

    Parameters
    ----------
    points : array_like, shape (N, d)
        Obstacle points (m).
    lattice : Lattice
    radius : float
        Metres, >= 0 (0 gives the cells containing the points).
    memory_budget : int
        Bytes for the dense scratch grid over the result's index box.

    Returns
    -------
    OccupiedVoxelList
    """
    lat = _check_lattice(lattice)
    r = _check_radius(radius)
    x = _as_points(points, lat.dim)
    if not len(x):
        raise MapError("point cloud is empty: no obstacle points to inflate")
    base = lat.quantize(x)
    if r == 0:
        return OccupiedVoxelList._from_keys(lat, _unique_keys(pack(base)))
    big_r, rho = lat.covering_radius, lat.packing_radius
    cand = _offsets_within(lat, r + 2 * big_r, memory_budget, r)
    ext = np.abs(cand).max(axis=0)
    lo, hi = base.min(axis=0) - ext, base.max(axis=0) + ext
    _check_range(lo, hi, lat.dim)
    dims = hi - lo + 1
    cells = float(np.prod(dims.astype(float)))
    if cells > memory_budget:
        raise _over_budget(r, cells, memory_budget)
    strides = _strides(dims)
    grid = np.zeros(int(cells), dtype=np.uint8)
    base_flat = np.ascontiguousarray((base - lo) @ strides)
    a, b, e0, e1 = _cell_polytope(lat)
    tol = _REL_TOL * _cell_diameter(lat)
    vk.exact_mark(x, np.ascontiguousarray(lat.to_world(base)), base_flat, grid,
                  np.ascontiguousarray(cand @ strides),
                  np.ascontiguousarray(cand @ lat.generator.T, dtype=float), a, b, e0, e1, tol,
                  r, rho, big_r)
    n = int(np.count_nonzero(grid))
    out = np.empty(n, dtype=np.int64)
    vk.grid_keys(grid, lo.astype(np.int64), dims.astype(np.int64), BITS[lat.dim],
                 index_limit(lat.dim), out)
    return OccupiedVoxelList._from_keys(lat, out)
