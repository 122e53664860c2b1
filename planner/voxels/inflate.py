"""Robot-radius inflation and exact cell sets of obstacle points and boxes.

* :func:`inflation_stencil` / :func:`stencil_inflation`: Minkowski sum of occupied cells
  with a stencil of lattice offsets derived exactly from the Voronoi cell (what
  :meth:`OccupiedVoxelList.inflate` runs; conservative).
* :func:`exact_inflation`: the tight set of cells closer than r to obstacle *points*.
* :func:`box_keys`: cells overlapping boxes (positive volume).
* :func:`exact_box_inflation`: the tight set of cells closer than r to (rotated) *boxes*.

All cell geometry comes from :attr:`planner.Lattice.voronoi` (:class:`VoronoiCell`).
"""

from __future__ import annotations

import math

import numpy as np

from planner.budget import require
from planner.errors import MapError
from planner.keys import BITS, check_range, index_limit, pack, unpack
from planner.lattice import Lattice
from planner.voxels import _box_kernels as bk
from planner.voxels import _kernels as vk
from planner.voxels._checks import (
    DEFAULT_BUDGET,
    REL_TOL,
    as_points,
    cell_diameter,
    check_lattice,
    check_radius,
    grid_strides,
    key_offsets,
    offsets_within,
    over_budget,
    resolve_budget,
    unique_keys,
)
from planner.voxels._list import OccupiedVoxelList

__all__ = ["box_keys", "exact_box_inflation", "exact_inflation", "inflation_stencil",
           "stencil_inflation"]

_BOX_CHUNK_KEYS = 1 << 24  # candidate keys per box chunk (128 MB of int64)


# -- stencil inflation --------------------------------------------------------------------------
def inflation_stencil(lat: Lattice, radius: float, memory_budget: float | None = DEFAULT_BUDGET
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
    r = check_radius(radius)
    zero = np.zeros((1, lat.dim), dtype=np.int64)
    if r == 0:
        return zero
    cand = offsets_within(lat, r + 2 * lat.covering_radius, memory_budget, r)
    tol = REL_TOL * cell_diameter(lat)
    half = np.ascontiguousarray(cand @ lat.generator.T / 2)
    dist = np.empty(len(cand))
    vk.cell_distances(half, vk.cell_polytope(lat.voronoi), tol, dist)
    # Conservative by tol: a pair at distance exactly r (up to rounding) is blocked.
    sel = cand[(2 * dist < r + tol) & np.any(cand != 0, axis=1)]
    order = np.argsort(np.linalg.norm(sel @ lat.generator.T, axis=1), kind="stable")
    return np.concatenate([zero, sel[order]])

def stencil_inflation(keys: np.ndarray, lat: Lattice, r: float, budget: float | None
                      ) -> np.ndarray:
    """Keys of :meth:`OccupiedVoxelList.inflate`: sorted unique ``keys`` (M,) dilated by
    :func:`inflation_stencil` (``r`` > 0 metres), on a dense grid when it fits ``budget``
    bytes (None: the memory budget), else by key arithmetic in chunks."""
    budget = resolve_budget(budget)
    stencil = inflation_stencil(lat, r, budget)
    full = lat.neighbors("full")
    w = unpack(keys, lat.dim)
    ext = np.maximum(np.abs(stencil).max(axis=0), np.abs(full).max(axis=0))
    lo, hi = w.min(axis=0) - ext, w.max(axis=0) + ext
    check_range(lo, hi, lat.dim)
    # The result holds at least one whole stencil: a cheap lower bound for the budget.
    least = len(stencil) * 8
    dims = hi - lo + 1
    cells = float(np.prod(dims.astype(float)))
    if least > budget:
        raise over_budget(r, least, budget)
    if cells + 8 * len(keys) <= budget:
        return _dilate_dense(keys, lo, dims, stencil, full, budget, r)
    return _dilate_keys(keys, stencil, full, budget, r)


def _dilate_dense(keys: np.ndarray, lo: np.ndarray, dims: np.ndarray, stencil: np.ndarray,
                  full: np.ndarray, budget: float, radius: float) -> np.ndarray:
    """Minkowski sum on a dense uint8 scratch grid over the padded index box."""
    d = len(dims)
    strides = grid_strides(dims)
    grid = np.zeros(int(np.prod(dims)), dtype=np.uint8)
    flat = np.empty(len(keys), dtype=np.int64)
    vk.flat_positions(keys, lo.astype(np.int64), strides, BITS[d], index_limit(d), flat)
    runs = _stencil_runs(stencil)
    if runs is not None and grid.nbytes * 5 + 8 * len(keys) <= budget:  # + int32 diff
        diff = np.zeros(grid.size + 1, dtype=np.int32)
        vk.dilate_rows(grid, flat, full @ strides, runs[0] @ strides, runs[1], diff)
        del diff
    else:
        vk.dilate(grid, flat, stencil @ strides, full @ strides)
    n = int(np.count_nonzero(grid))
    if grid.nbytes + 8 * n > budget:
        raise over_budget(radius, grid.nbytes + 8 * n, budget)
    out = np.empty(n, dtype=np.int64)
    vk.grid_keys(grid, lo.astype(np.int64), dims.astype(np.int64), BITS[d], index_limit(d), out)
    return out


def _stencil_runs(stencil: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    """The stencil (S, d) as runs along its last axis: ``(starts (R, d), lengths (R,))``
    covering exactly the same offsets, or None when a row has a gap (the stencil is the
    lattice points of a convex set, so rows are runs; None only guards rounding)."""
    order = np.lexsort(stencil.T[::-1])
    s = stencil[order]
    new_row = np.ones(len(s), dtype=bool)
    new_row[1:] = (s[1:, :-1] != s[:-1, :-1]).any(axis=1)
    first = np.flatnonzero(new_row)
    lengths = np.diff(np.append(first, len(s)))
    last = s[np.append(first[1:], len(s)) - 1, -1]
    if not np.array_equal(last - s[first, -1] + 1, lengths):
        return None
    return np.ascontiguousarray(s[first]), lengths.astype(np.int64)


def _dilate_keys(keys: np.ndarray, stencil: np.ndarray, full: np.ndarray, budget: float,
                 radius: float) -> np.ndarray:
    """Minkowski sum by key arithmetic in chunks (no scratch grid), for sparse huge boxes."""
    nb = key_offsets(full)
    # Boundary cells: some full neighbour is free (interior cells add nothing, see vk.dilate).
    boundary = np.zeros(len(keys), dtype=bool)
    for o in nb:
        q = keys + o
        pos = np.minimum(np.searchsorted(keys, q), len(keys) - 1)
        boundary |= keys[pos] != q
    src = keys[boundary]
    sk = key_offsets(stencil)
    chunk = max(1, int(budget / 4 / 8 / len(sk)))
    out = keys
    for s in range(0, len(src), chunk):
        part = unique_keys((src[s: s + chunk, None] + sk[None, :]).ravel())
        out = unique_keys(np.concatenate([out, part]))
        if out.nbytes * 2 > budget:
            raise over_budget(radius, out.nbytes * 2, budget)
    return out

# -- exact inflation ------------------------------------------------------------------------------
def exact_inflation(points: np.ndarray, lattice: Lattice, radius: float,
                    memory_budget: int | None = DEFAULT_BUDGET) -> OccupiedVoxelList:
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
        Bytes for the dense scratch grid over the result's index box (default: the
        memory budget of :mod:`planner.budget`).

    Returns
    -------
    OccupiedVoxelList
    """
    lat = check_lattice(lattice)
    r = check_radius(radius)
    x = as_points(points, lat.dim)
    if not len(x):
        raise MapError("point cloud is empty: no obstacle points to inflate")
    base = lat.quantize(x)
    if r == 0:
        return OccupiedVoxelList._from_keys(lat, unique_keys(pack(base)))
    memory_budget = resolve_budget(memory_budget)
    # Each point blocks every cell whose centre is within rho = r - covering of it: about
    # that ball's volume in cells (halved for the lattice-point-count error), times the
    # points whose balls are disjoint, known before any enumeration.
    rho = r - lat.covering_radius
    if rho > 0:
        ball = 0.5 * math.pi * 4 / 3 * min(rho, 1e100) ** lat.dim / lat.cell_volume
        _check_result(r, 0.0, ball * _disjoint_balls(x, rho), memory_budget)
    cand = offsets_within(lat, r + 2 * lat.covering_radius, memory_budget, r)
    ext = np.abs(cand).max(axis=0)
    lo, hi = base.min(axis=0) - ext, base.max(axis=0) + ext
    check_range(lo, hi, lat.dim)
    dims = hi - lo + 1
    cells = float(np.prod(dims.astype(float)))
    if cells > memory_budget:
        raise over_budget(r, cells, memory_budget)
    strides = grid_strides(dims)
    grid = np.zeros(int(cells), dtype=np.uint8)
    base_flat = np.ascontiguousarray((base - lo) @ strides)
    tol = REL_TOL * cell_diameter(lat)
    vk.exact_mark(x, np.ascontiguousarray(lat.to_world(base)), base_flat, grid,
                  np.ascontiguousarray(cand @ strides),
                  np.ascontiguousarray(cand @ lat.generator.T, dtype=float),
                  vk.cell_polytope(lat.voronoi), tol, r)
    n = int(np.count_nonzero(grid))
    _check_result(r, cells, n, memory_budget)
    out = np.empty(n, dtype=np.int64)
    vk.grid_keys(grid, lo.astype(np.int64), dims.astype(np.int64), BITS[lat.dim],
                 index_limit(lat.dim), out)
    return OccupiedVoxelList._from_keys(lat, out)


def _disjoint_balls(x: np.ndarray, rho: float) -> int:
    """A count of points of ``x`` (N, d) pairwise >= 2 ``rho`` apart: occupied cells of a
    grid of edge 2 ``rho``, in the best of the 2^d index-parity classes (two cells of one
    class are a whole cell apart)."""
    c = np.floor(x / (2 * rho)).astype(np.int64) & 0x1FFFFF  # 21 bits an axis: cells that
    key = np.zeros(len(x), dtype=np.int64)  # share them merge, which keeps a lower bound
    for j in range(x.shape[1]):
        key |= c[:, j] << (21 * j)
    key = unique_keys(key)
    parity = np.zeros(len(key), dtype=np.int64)
    for j in range(x.shape[1]):
        parity |= ((key >> (21 * j)) & 1) << j
    return int(np.bincount(parity).max())


def _check_result(r: float, cells: float, n: int, budget: float) -> None:
    """Refuse ``n`` blocked cells whose keys, and the (n, 3) indices and sorts callers make
    of them (~40 bytes a cell), do not fit the budget next to the ``cells``-byte grid."""
    if cells + 40.0 * n > budget:
        raise over_budget(r, cells + 40.0 * n, budget)


# -- boxes --------------------------------------------------------------------------------------
def box_keys(centres: np.ndarray, size: float, lattice: Lattice) -> np.ndarray:
    """Sorted unique keys of the cells whose Voronoi cell overlaps a box (positive volume).

    Exact up to a tolerance of 1e-9 cell diameters: overlaps thinner than that (touching
    faces, edges, corners) do not count. The cell containing each box centre always counts.
    A box of size 0 is a point (its containing cell).

    Parameters
    ----------
    centres : ndarray, shape (M, d)
        Centres of axis-aligned cubes (m).
    size : float
        Cube edge length (m), >= 0.
    lattice : Lattice

    Returns
    -------
    ndarray, shape (K,), int64
    """
    lat = check_lattice(lattice)
    c = as_points(centres, lat.dim, "box centres")
    s = float(size)
    if not math.isfinite(s) or s < 0:
        raise MapError(f"box size must be a non-negative number of metres, got {size!r}")
    return _overlap_keys(c, np.full(c.shape, s / 2), np.eye(lat.dim), lat)


def _overlap_keys(centres: np.ndarray, half: np.ndarray, rot: np.ndarray, lat: Lattice
                  ) -> np.ndarray:
    """Keys of the cells overlapping boxes ``{C + R x : |x| <= H}`` with positive volume,
    plus the cell of each centre; ``centres``, ``half`` (K, d) metres, ``rot`` (d, d)."""
    d = lat.dim
    if not len(centres):
        return np.zeros(0, dtype=np.int64)
    base = lat.quantize(centres)
    base_keys = pack(base)
    if not half.any():
        return unique_keys(base_keys)
    # Each box overlaps at least its volume in cells (per chunk, before the merge): refuse a
    # box set whose key lists alone exceed the budget before enumerating anything.
    need = 8.0 * float(np.prod(2 * half, axis=1).sum()) / lat.cell_volume
    require(need, f"the cells of {len(centres)} boxes")
    t = bk.overlap_tests(lat, half, rot)
    offs = t.offsets
    ext = np.abs(offs).max(axis=0)
    check_range(base.min(axis=0) - ext, base.max(axis=0) + ext, d)
    base_world = lat.to_world(base)
    offs_key = key_offsets(offs)
    chunk = max(1, _BOX_CHUNK_KEYS // len(offs))
    parts = []
    buf = np.empty(min(chunk, len(centres)) * len(offs), dtype=np.int64)
    for i in range(0, len(centres), chunk):
        sl = slice(i, i + chunk)
        n = bk.overlap_keys(np.ascontiguousarray(centres[sl]), np.ascontiguousarray(half[sl]),
                            base_keys[sl], np.ascontiguousarray(base_world[sl]), t.offs_world,
                            offs_key, t.axes, t.axes_box, t.support_v, t.packing, t.covering,
                            t.tol, buf)
        parts.append(unique_keys(buf[:n]))  # per chunk: neighbouring boxes share cells
    parts.append(base_keys)  # the centre's cell, even for boxes thinner than the tolerance
    return unique_keys(np.concatenate(parts))


def _box_frame(lo, hi, rotation, translation, d: int) -> tuple[np.ndarray, ...]:
    """Checked ``(centres (K, d) world, half sizes (K, d), R (d, d))`` of boxes
    ``{R x + t : lo <= x <= hi}``."""
    a = as_points(lo, d, "box lower corners")
    b = as_points(hi, d, "box upper corners")
    if a.shape != b.shape:
        raise MapError(f"box corners differ in shape: lo {a.shape}, hi {b.shape}")
    if len(a) and (b < a).any():
        row = int(np.flatnonzero((b < a).any(axis=1))[0])
        raise MapError(f"box {row}: upper corner {b[row].tolist()} is below the lower corner "
                       f"{a[row].tolist()}")
    rot = np.eye(d) if rotation is None else np.asarray(rotation, dtype=float)
    if rot.shape != (d, d) or not np.isfinite(rot).all() or not np.allclose(
            rot.T @ rot, np.eye(d), atol=1e-9) or np.linalg.det(rot) < 0:
        raise MapError(f"rotation must be a proper {d}x{d} rotation matrix, got "
                       f"{np.array2string(rot, separator=', ').replace(chr(10), '')}")
    t = np.zeros(d) if translation is None else np.asarray(translation, dtype=float).ravel()
    if t.shape != (d,) or not np.isfinite(t).all():
        raise MapError(f"translation must be {d} finite numbers (m), got {translation!r}")
    mid = (a + b) / 2
    # No product with the identity (the same numbers; a small BLAS call can cost more than
    # the whole inflation on a loaded machine).
    centres = np.ascontiguousarray((mid if rotation is None else mid @ rot.T) + t)
    return centres, np.ascontiguousarray((b - a) / 2), np.ascontiguousarray(rot)


def _split_boxes(centres: np.ndarray, half: np.ndarray, rot: np.ndarray, max_half: float,
                 budget: float | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Boxes cut into equal sub-boxes of half sizes <= ``max_half`` (same union, so the same
    distances): per-box candidate balls then stay proportionate to the box (a large slab
    would otherwise enumerate a ball of its half diagonal). The piece count is checked
    against ``budget`` bytes (None: the memory budget) before any piece is made."""
    ratio = np.maximum(np.ceil(half / max_half - 1e-9), 1)
    # float product: a coarse leaf of a lying file asks for more pieces than int64 holds
    n_pieces = float(np.prod(ratio, axis=1).sum())
    # per piece: its centre and half sizes, the step indices and the box-frame offsets
    require(n_pieces * half.shape[1] * 8 * 4, f"the {n_pieces:.3g} sub-boxes of "
            f"{len(half)} obstacle boxes (largest {2 * float(half.max()):.3g} m across)", budget)
    pieces = ratio.astype(np.int64)
    if (pieces == 1).all():
        return centres, half
    out_c, out_h = [], []
    for n in np.unique(pieces, axis=0):
        sel = np.flatnonzero((pieces == n).all(axis=1))
        sub = half[sel] / n  # (k, d) half sizes of the pieces
        steps = np.stack(np.meshgrid(*[np.arange(m) for m in n], indexing="ij"),
                         axis=-1).reshape(-1, len(n))
        # Piece centres in the box frame: -half + (2 i + 1) sub, i per axis.
        local = -half[sel, None, :] + (2 * steps[None, :, :] + 1) * sub[:, None, :]
        out_c.append((centres[sel, None, :] + local @ rot.T).reshape(-1, len(n)))
        out_h.append(np.repeat(sub, len(steps), axis=0))
    return np.ascontiguousarray(np.concatenate(out_c)), np.ascontiguousarray(
        np.concatenate(out_h))


def _sure_and_tested(cand_world: np.ndarray, half: np.ndarray, cell, r: float, tol: float
                     ) -> tuple[np.ndarray, np.ndarray]:
    """Masks of the candidates (box-frame offsets ``cand_world`` (n, 3), m) that
    :func:`bk.within_mark` would mark for every box of half sizes among ``half`` (K, 3)
    whatever the base cell's position (within the covering radius R of the box centre),
    and of those it must test (the others it would skip for every box).

    With ``c`` a candidate, ``b`` the base cell centre (``|b| <= R``) and ``dist(x, h)`` the
    distance from x to ``[-h, h]``: ``dist(b + c, h_i) <= dist(c, h_min) + R`` and
    ``>= dist(c, h_max) - R``, compared with the kernel's first bounds ``r + packing`` and
    ``r + tol + R`` with a margin for rounding."""
    def dist(h: np.ndarray) -> np.ndarray:
        return np.linalg.norm(np.maximum(np.abs(cand_world) - h, 0.0), axis=1)

    cov, slack = cell.covering_radius, 1e-9 * (1.0 + r)
    sure = dist(half.min(axis=0)) + cov < r + cell.packing_radius - slack
    test = ~sure & (dist(half.max(axis=0)) - cov < r + tol + cov + slack)
    return sure, test


def exact_box_inflation(lo: np.ndarray, hi: np.ndarray, lattice: Lattice, radius: float, *,
                        rotation: np.ndarray | None = None,
                        translation: np.ndarray | None = None,
                        memory_budget: int | None = DEFAULT_BUDGET) -> OccupiedVoxelList:
    """The exact set of cells whose closed Voronoi cell is closer than ``radius`` to a box.

    Box k is the solid ``{R @ x + t : lo[k] <= x <= hi[k]}`` (R, t shared by all boxes: how
    a rotated map's boxes are represented). For ``radius`` 0 the cells overlapping a box
    with positive volume (as :func:`box_keys`, plus the cell of each box centre). For
    ``radius`` > 0 every cell at distance < ``radius`` from some box, decided by ball bounds
    (packing / covering radius) and an exact convex distance (GJK) in the thin shell between
    them; a cell within 1e-9 cell diameters of ``radius`` counts as blocked (conservative).
    Every cell left out is at distance >= ``radius`` from every box.

    Parameters
    ----------
    lo, hi : array_like, shape (K, d)
        Box corners in the box frame (m), ``lo <= hi``.
    lattice : Lattice
    radius : float
        Metres, >= 0.
    rotation : array_like, shape (d, d), optional
        Proper rotation R (default identity).
    translation : array_like, shape (d,), optional
        Translation t (m, default 0).
    memory_budget : int
        Bytes for the dense scratch grid over the result's index box (radius > 0;
        default: the memory budget of :mod:`planner.budget`).

    Returns
    -------
    OccupiedVoxelList

    Examples
    --------
    >>> lat = Lattice.named("cubic", 1.0)
    >>> lo, hi = np.full((1, 3), -0.25), np.full((1, 3), 0.25)  # a cube inside one cell
    >>> len(exact_box_inflation(lo, hi, lat, 0.0))
    1
    >>> len(exact_box_inflation(lo, hi, lat, 0.3))  # + 6 face neighbours 0.25 m away
    7
    >>> len(exact_box_inflation(lo, hi, lat, 0.3, rotation=[[0, -1, 0], [1, 0, 0], [0, 0, 1]]))
    7
    """
    lat = check_lattice(lattice)
    r = check_radius(radius)
    d = lat.dim
    centres, half, rot = _box_frame(lo, hi, rotation, translation, d)
    if r == 0 or not len(centres):
        return OccupiedVoxelList._from_keys(lat, _overlap_keys(centres, half, rot, lat))
    if d != 3:
        raise MapError(f"box inflation with a radius needs a 3D lattice, got {d}D")
    memory_budget = resolve_budget(memory_budget)
    cell = lat.voronoi
    tol = REL_TOL * cell_diameter(lat)
    centres, half = _split_boxes(centres, half, rot, max(r, 2 * cell_diameter(lat)),
                                 memory_budget)
    base = lat.quantize(centres)
    # Boxes by size class (half diagonals within a factor 2, e.g. OctoMap leaf depths), each
    # with candidates out to its own reach: a cell closer than r has its centre within
    # r + covering of the box, whose centre is within covering of the base cell's centre.
    diag = np.linalg.norm(half, axis=1)
    size_class = np.floor(np.log2(np.maximum(diag, tol) / max(float(diag.min()), tol)))
    groups = []
    for c in np.unique(size_class):
        sel = np.flatnonzero(size_class == c)
        reach = r + 2 * cell.covering_radius + float(diag[sel].max()) + tol
        groups.append((sel, offsets_within(lat, reach, memory_budget, r)))
    ext = np.max([np.abs(cand).max(axis=0) for _, cand in groups], axis=0)
    glo, ghi = base.min(axis=0) - ext, base.max(axis=0) + ext
    check_range(glo, ghi, d)
    dims = ghi - glo + 1
    cells = float(np.prod(dims.astype(float)))
    if cells > memory_budget:
        raise over_budget(r, cells, memory_budget)
    strides = grid_strides(dims)
    base_flat = (base - glo) @ strides
    grid = np.zeros(int(cells), dtype=np.uint8)
    verts = np.ascontiguousarray(cell.vertices @ rot)
    for sel, cand in groups:
        # Boxes in grid order and candidates by flat offset: neighbouring boxes then find
        # their shared cells already marked, and the grid is walked mostly forwards.
        # Candidate centres go in the box frame (R^T G w): the kernel adds the base
        # cell's box-frame position only.
        order = sel[np.argsort(base_flat[sel], kind="stable")]
        cand_flat = cand @ strides
        corder = np.argsort(cand_flat, kind="stable")
        cand_flat = cand_flat[corder]
        cand_world = np.ascontiguousarray(cand[corder] @ lat.generator.T @ rot, dtype=float)
        sure, test = _sure_and_tested(cand_world, half[sel], cell, r, tol)
        bk.within_mark(centres[order], half[order], rot,
                       np.ascontiguousarray(base_flat[order]),
                       np.ascontiguousarray(lat.to_world(base[order])),
                       np.ascontiguousarray(cand_flat[sure]), np.ascontiguousarray(
                           cand_flat[test]), np.ascontiguousarray(cand_world[test]),
                       verts, cell.packing_radius, cell.covering_radius, r, tol, grid)
    n = int(np.count_nonzero(grid))
    _check_result(r, cells, n, memory_budget)
    out = np.empty(n, dtype=np.int64)
    vk.grid_keys(grid, glo.astype(np.int64), dims.astype(np.int64), BITS[d], index_limit(d), out)
    return OccupiedVoxelList._from_keys(lat, out)
