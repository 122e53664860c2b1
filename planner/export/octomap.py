"""OctoMap binary trees (``.bt``): the map's obstacles, or (on request) a world's C-space mask.

Two different things can be written, under two names:

* :func:`write_octomap` (``planner world MAP --out map.bt``): what OctoMap itself means by a
  ``.bt``, an occupancy map of the map's *obstacles*. A voxel is occupied where an obstacle
  point lies or an obstacle box reaches, free where the map says it was observed free (free
  boxes, and voxels crossed by a sensor ray from a known origin), and left out (unknown)
  otherwise. The voxels are OctoMap's own: key ``K`` per axis, centre ``(K - 32768 + 1/2)
  res`` in the map's frame, no shift. ``res`` is the world's cell edge (cubic lattices) or
  the edge of a cube of the world's cell volume (any other lattice), to 12 significant
  digits. The robot radius is
  not applied: the tree is the map, not the planner's view of it.
* :func:`write_cspace_octomap` (``planner world MAP --out mask.bt --bt-cspace``): the
  planner's blocked cells (obstacles inflated by the robot radius, plus unknown space when
  it is blocked), all occupied, for a cubic world only. Those cells are centred on ``k h``,
  half a cell off OctoMap's voxel centres, so the tree's frame is the world's shifted by
  ``h/2 (1, 1, 1)``: a header comment ``# planner_shift -h/2 -h/2 -h/2`` says so (OctoMap
  skips comment lines), and :func:`planner.io.octomap.read_octomap` applies it.

Both prune eight equal siblings into their parent, as OctoMap does.
"""

from __future__ import annotations

import math
import os
from typing import NamedTuple

import numpy as np

from planner.budget import require
from planner.errors import MapError
from planner.fsutil import atomic_path

__all__ = ["OctoMapCounts", "check_cubic", "check_cubic_name", "obstacle_voxels",
           "octree_stream", "write_cspace_octomap", "write_octomap"]

_DEPTH = 16
_CENTER = 32768
HEADER = "# Octomap OcTree binary file"
_FREE, _OCCUPIED, _INNER = 1, 2, 3
_EPS = 1e-6  # voxels: a box face this close to a voxel face is on it
_CHUNK = 1 << 22  # candidate voxels per box chunk


class OctoMapCounts(NamedTuple):
    """Finest voxels written to a ``.bt`` (before pruning)."""

    occupied: int
    free: int
    resolution: float


def check_cubic(generator: np.ndarray, what: str = "the world") -> float:
    """The cell edge ``h`` (m) of a cubic generator ``h I`` (3, 3); MapError otherwise."""
    g = np.asarray(generator, dtype=float)
    h = float(g[0, 0]) if g.shape == (3, 3) else 0.0
    if not (h > 0 and np.allclose(g, h * np.eye(3), rtol=0, atol=1e-12 * h)):
        raise MapError(f"{what}: a C-space .bt holds cubic cells only; build the world with "
                       f"--lattice cubic (the obstacle .bt, without --bt-cspace, takes any "
                       f"lattice)")
    return h


def check_cubic_name(lattice, map_path: str) -> None:
    """Refuse a non-cubic ``--lattice`` (a name or a Lattice) for a C-space ``.bt`` before a
    map is built; a saved world is checked once loaded."""
    from planner.world.file import is_world_file  # lazy: numba, scipy

    if is_world_file(map_path):
        return
    if isinstance(lattice, str):
        if lattice != "cubic":
            raise MapError(f"{lattice} lattice: a C-space .bt holds cubic cells only; use "
                           f"--lattice cubic (or drop --bt-cspace for the obstacle map)")
        return
    check_cubic(lattice.generator, f"{lattice.name or 'custom'} lattice")


# -- the tree ----------------------------------------------------------------------------------
def _morton(keys: np.ndarray) -> np.ndarray:
    """(N,) uint64 depth-first order codes of (N, 3) 16-bit keys: at each level the child
    index is x | y << 1 | z << 2, as in OctoMap."""
    k = keys.astype(np.uint64)
    code = np.zeros(len(k), dtype=np.uint64)
    for b in range(_DEPTH):
        for axis in range(3):
            code |= ((k[:, axis] >> np.uint64(b)) & np.uint64(1)) << np.uint64(3 * b + axis)
    return code


def octree_stream(occupied: np.ndarray, free: np.ndarray | None = None) -> tuple[bytes, int]:
    """OctoMap's depth-first bit stream of finest voxels, and the node count (root
    included) for the header's ``size``.

    Parameters
    ----------
    occupied, free : ndarray, shape (N, 3) and (F, 3), int
        Voxel keys in 0..65535; the two sets must not share a voxel. Eight siblings of one
        state become one leaf of their parent (recursively, below the root).
    """
    free = np.zeros((0, 3), np.int64) if free is None else free
    codes = np.concatenate([_morton(occupied), _morton(free)])
    states = np.concatenate([np.full(len(occupied), _OCCUPIED, np.int8),
                             np.full(len(free), _FREE, np.int8)])
    order = np.argsort(codes, kind="stable")
    codes, states = codes[order], states[order]
    if len(codes) > 1 and np.any(codes[1:] == codes[:-1]):
        raise MapError("a voxel cannot be both occupied and free in an OctoMap tree")
    level_codes, level_state = {_DEPTH: codes}, {_DEPTH: states}  # state 0: inner node
    for d in range(_DEPTH - 1, -1, -1):
        kids, kid_state = level_codes[d + 1], level_state[d + 1]
        parent = kids >> np.uint64(3)
        first = np.flatnonzero(np.r_[True, parent[1:] != parent[:-1]]) if len(kids) else \
            np.zeros(0, np.int64)
        count = np.diff(np.r_[first, len(kids)])
        lo = np.minimum.reduceat(kid_state, first) if len(first) else kid_state[:0]
        hi = np.maximum.reduceat(kid_state, first) if len(first) else kid_state[:0]
        state = np.where((count == 8) & (lo == hi) & (lo > 0), lo, 0).astype(np.int8)
        if d == 0:
            state[:] = 0  # the root stays a node
        level_codes[d], level_state[d] = parent[first], state
    starts, depths, bits = [], [], []
    n_leaves = 0
    for d in range(_DEPTH):
        inner = level_codes[d][level_state[d] == 0]
        kids, kid_state = level_codes[d + 1], level_state[d + 1]
        keep = np.isin(kids >> np.uint64(3), inner)
        kids, kid_state = kids[keep], kid_state[keep]
        state = np.where(kid_state > 0, kid_state, _INNER).astype(np.int64)
        n_leaves += int((kid_state > 0).sum())
        slot = (kids & np.uint64(7)).astype(np.int64)
        owner = np.searchsorted(inner, kids >> np.uint64(3))
        b = np.zeros(len(inner), dtype=np.int64)
        np.add.at(b, owner, state << (2 * slot))
        starts.append(inner << np.uint64(3 * (_DEPTH - d)))
        depths.append(np.full(len(inner), d))
        bits.append(b)
    start, depth, b = (np.concatenate(x) for x in (starts, depths, bits))
    order = np.lexsort((depth, start))  # pre-order: a node before its first child
    b = b[order]
    stream = np.empty(2 * len(b), dtype=np.uint8)
    stream[0::2] = b & 0xFF  # children 0-3
    stream[1::2] = b >> 8  # children 4-7
    return stream.tobytes(), len(b) + n_leaves


def _write_tree(out, res: float, occupied: np.ndarray, free: np.ndarray,
                comments: list[str]) -> None:
    """Write the tree of voxel keys (0..65535) atomically."""
    stream, size = octree_stream(occupied, free)
    head = "".join(f"# {c}\n" for c in comments)
    head = f"{HEADER}\n{head}id OcTree\nsize {size}\nres {res!r}\ndata\n"
    with atomic_path(out) as tmp:
        tmp.write_bytes(head.encode("ascii") + stream)


# -- the obstacle map --------------------------------------------------------------------------
def _code(j: np.ndarray) -> np.ndarray:
    """(N,) int64 sortable codes of (N, 3) signed voxel indices (key - 32768)."""
    k = np.asarray(j, dtype=np.int64) + _CENTER
    return (k[:, 0] << 32) | (k[:, 1] << 16) | k[:, 2]


def _uncode(c: np.ndarray) -> np.ndarray:
    """(N, 3) OctoMap keys (0..65535) of :func:`_code` codes."""
    return np.stack([(c >> 32) & 0xFFFF, (c >> 16) & 0xFFFF, c & 0xFFFF], axis=1)


def _check_keys(lo: np.ndarray, hi: np.ndarray, res: float, where: str) -> None:
    if len(lo) and (lo.min() < -_CENTER or hi.max() >= _CENTER):
        raise MapError(f"{where}: the map reaches beyond +-{_CENTER * res:g} m (32768 voxels "
                       f"of {res:g} m) from the origin, outside any OctoMap tree; use a larger "
                       f"cell volume")


def _box_voxels(centres: np.ndarray, sizes: np.ndarray, res: float, inside: bool,
                where: str) -> np.ndarray:
    """Codes of the voxels (edge ``res``, voxel ``j`` spanning ``[j, j + 1) res``) that
    overlap the boxes with positive volume (``inside`` False: occupied boxes) or lie wholly
    inside them (``inside`` True: free boxes)."""
    if not len(centres):
        return np.zeros(0, np.int64)
    half = sizes[:, None] / 2
    a, b = (centres - half) / res, (centres + half) / res
    if inside:
        lo, hi = np.ceil(a - _EPS), np.floor(b + _EPS) - 1
    else:
        lo, hi = np.floor(a + _EPS), np.ceil(b - _EPS) - 1
    lo, hi = lo.astype(np.int64), hi.astype(np.int64)
    ok = np.all(hi >= lo, axis=1)
    lo, hi = lo[ok], hi[ok]
    _check_keys(lo, hi, res, where)
    n = hi - lo + 1
    total = float(np.prod(n, axis=1, dtype=float).sum())
    require(16.0 * total, f"the OctoMap voxels of {where} (~{total:,.0f} voxels)")
    parts = [np.zeros(0, np.int64)]
    for size in np.unique(n, axis=0):  # boxes spanning the same voxel counts at once
        sel = np.all(n == size, axis=1)
        g = np.stack(np.meshgrid(*[np.arange(s) for s in size], indexing="ij"),
                     -1).reshape(-1, 3)
        base = lo[sel]
        step = max(1, _CHUNK // len(g))
        for i in range(0, len(base), step):
            parts.append(np.unique(_code((base[i: i + step, None, :] + g).reshape(-1, 3))))
    return np.unique(np.concatenate(parts))


def obstacle_voxels(obst, res: float) -> tuple[np.ndarray, np.ndarray]:
    """OctoMap voxel keys of a map: occupied and observed free (module docstring).

    Parameters
    ----------
    obst : planner.io.Obstacles
        A 3D map (points, boxes, free boxes, sensor origins).
    res : float
        Voxel edge (m).

    Returns
    -------
    occupied, free : ndarray, shape (N, 3) and (F, 3), int64
        Keys in 0..65535 (centre ``(K - 32768 + 1/2) res``), disjoint, sorted.
    """
    where = str(obst.source)
    if obst.dim != 3:
        raise MapError(f"{where}: a 2D map has no OctoMap tree; write .ply or .npz instead")
    pts = np.asarray(obst.points, dtype=float)
    j = np.floor(pts / res).astype(np.int64)
    _check_keys(j, j, res, where)
    occ = np.union1d(np.unique(_code(j)),
                     _box_voxels(obst.boxes, obst.box_sizes, res, False, where))
    free = [_box_voxels(obst.free_boxes, obst.free_box_sizes, res, True, where)]
    if obst.origins is not None and len(pts):
        free.append(_ray_voxels(obst, res, where))
    free = np.setdiff1d(np.unique(np.concatenate(free)), occ, assume_unique=True)
    return _uncode(occ), _uncode(free)


def _ray_voxels(obst, res: float, where: str) -> np.ndarray:
    """Codes of the voxels the sensor rays cross (their end voxels excluded), by the
    world's own ray walk on a cubic lattice of edge ``res`` moved half a voxel so that its
    cells are OctoMap's voxels."""
    from planner.lattice import Lattice  # lazy: numba (the package imports without it)
    from planner.occupancy.keys import unpack  # lazy: numba
    from planner.voxels.unknown import ray_free_keys  # lazy: numba

    lat = Lattice.named("cubic", cell_volume=res ** 3)
    shift = lat.generator[0, 0] / 2
    keys = ray_free_keys(obst.points - shift, obst.origins - shift, obst.point_origin, lat)
    j = unpack(keys, 3)
    _check_keys(j, j, res, where)
    return _code(j)


def octomap_resolution(lattice) -> float:
    """The voxel edge (m) of a world's obstacle ``.bt``: the cell edge of a cubic lattice,
    else the edge of a cube of its cell volume."""
    g = np.asarray(lattice.generator, dtype=float)
    if g.shape == (3, 3) and np.allclose(g, g[0, 0] * np.eye(3), rtol=0,
                                          atol=1e-12 * abs(g[0, 0])):
        h = float(g[0, 0])
    else:
        h = float(lattice.cell_volume) ** (1 / 3)
    # A cube root's last bits (0.1 ** 3 -> 0.10000000000000002) would move points lying on
    # voxel faces (a grid map's, a rounded cloud's) into the next voxel: 12 digits are kept.
    return float(f"{h:.12g}")


def write_octomap(out: str | os.PathLike, source, resolution: float | None = None
                  ) -> OctoMapCounts:
    """Write a map's obstacles as an OctoMap ``.bt`` (module docstring), atomically.

    Parameters
    ----------
    out : str or PathLike
        Output ``.bt``.
    source : World or planner.io.Obstacles
        A world built from a map (its ``obstacles``; a saved world keeps none) or the map.
    resolution : float, optional
        Voxel edge (m). Default: :func:`octomap_resolution` of the world's lattice, or the
        map's native resolution.

    Returns
    -------
    OctoMapCounts
    """
    obst = getattr(source, "obstacles", source)
    if getattr(source, "dim", 3) == 2:
        raise MapError(f"{out}: a 2D map has no OctoMap tree; write .ply or .npz instead")
    if obst is None or not hasattr(obst, "points"):
        raise MapError(f"{out}: a saved world keeps no obstacles; write the .bt from the map "
                       f"itself, or give --bt-cspace for the blocked cells")
    if resolution is None:
        resolution = (octomap_resolution(source.lattice) if hasattr(source, "lattice")
                      else obst.resolution)
        native = obst.resolution
        if native and resolution and math.isclose(resolution, native, rel_tol=1e-9):
            resolution = native  # the map's own voxels, not a cube root's last bit
    if resolution is None or not (math.isfinite(resolution) and resolution > 0):
        raise MapError(f"{out}: an OctoMap needs a positive voxel edge, got {resolution!r}")
    res = float(resolution)
    occ, free = obstacle_voxels(obst, res)
    if not len(occ) and not len(free):
        raise MapError(f"{out}: the map has no obstacle to write")
    _write_tree(out, res, occ, free,
                [f"obstacles of {os.path.basename(str(obst.source))}: occupied, observed free,"
                 f" unknown left out; voxel centres (key - 32768 + 1/2) * res"])
    return OctoMapCounts(len(occ), len(free), res)


# -- the C-space mask --------------------------------------------------------------------------
def write_cspace_octomap(out: str | os.PathLike, world) -> int:
    """Write the blocked cells of a cubic ``world`` as an OctoMap ``.bt`` (the C-space mask,
    module docstring), atomically; returns the number of cells written."""
    h = check_cubic(world.lattice.generator, str(out))
    cells = np.unique(np.asarray(world.blocked, dtype=np.int64), axis=0)
    if not len(cells):
        raise MapError(f"{out}: the world has no blocked cell to write")
    if cells.min() < -_CENTER or cells.max() >= _CENTER:
        raise MapError(f"{out}: cells beyond +-{_CENTER} cells from the origin do not fit an "
                       f"OctoMap tree; use a larger cell volume")
    shift = " ".join([repr(-h / 2)] * 3)
    _write_tree(out, h, cells + _CENTER, np.zeros((0, 3), np.int64),
                [f"C-space mask: the planner's blocked cells (radius {world.radius:g} m), "
                 f"not the obstacles", "cubic cells of edge res, centres at key * res in the "
                 "world", f"planner_shift {shift}"])
    return len(cells)
