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
from planner.checks import check_radius
from planner.errors import MapError
from planner.lattice import Lattice
from planner.occupancy.keys import BITS, check_range, index_limit, pack, unique_keys
from planner.voxels import _box_kernels as bk
from planner.voxels import kernels as vk
from planner.voxels._checks import (
    DEFAULT_BUDGET,
    REL_TOL,
    as_points,
    cell_diameter,
    check_lattice,
    grid_strides,
    offsets_within,
    over_budget,
    resolve_budget,
)
from planner.voxels.boxes import box_frame, box_keys, overlap_keys
from planner.voxels.stencil import inflation_stencil, stencil_inflation
from planner.voxels.voxel_list import OccupiedVoxelList

__all__ = ["box_inflation_grid", "box_keys", "exact_box_inflation", "exact_inflation",
           "inflation_stencil", "point_inflation_grid", "stencil_inflation"]



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
    if r == 0:
        return OccupiedVoxelList._from_keys(lat, unique_keys(pack(lat.quantize(x))))
    grid, lo, dims = point_inflation_grid(x, lat, r, memory_budget, lists=True)
    n = int(np.count_nonzero(grid))
    _check_result(r, float(grid.size), n, resolve_budget(memory_budget))
    out = np.empty(n, dtype=np.int64)
    vk.grid_keys(grid, lo, dims, BITS[lat.dim], index_limit(lat.dim), out)
    return OccupiedVoxelList._from_keys(lat, out)


def point_inflation_grid(points: np.ndarray, lattice: Lattice, radius: float,
                         memory_budget: int | None = DEFAULT_BUDGET, lists: bool = False
                         ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The cells of :func:`exact_inflation` (``radius`` > 0) marked in a byte grid.

    Parameters
    ----------
    points : array_like, shape (N, d)
        Obstacle points (m), at least one.
    lattice, radius, memory_budget
        As for :func:`exact_inflation` (``radius`` > 0).
    lists : bool
        The caller will list the cells (the budget then counts ~40 bytes a cell).

    Returns
    -------
    grid : ndarray, shape (prod(dims),), uint8
        Nonzero for a marked cell, C order over the index box ``lo + [0, dims)``.
    lo, dims : ndarray, shape (d,), int64
    """
    lat = check_lattice(lattice)
    r = check_radius(radius)
    x = as_points(points, lat.dim)
    base = lat.quantize(x)
    memory_budget = resolve_budget(memory_budget)
    # Each point blocks every cell whose centre is within rho = r - covering of it: about
    # that ball's volume in cells (halved for the lattice-point-count error), times the
    # points whose balls are disjoint, known before any enumeration.
    rho = r - lat.covering_radius
    if rho > 0 and lists:
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
    return grid, lo.astype(np.int64), dims.astype(np.int64)


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
    centres, half, rot = box_frame(lo, hi, rotation, translation, d)
    if r == 0 or not len(centres):
        return OccupiedVoxelList._from_keys(lat, overlap_keys(centres, half, rot, lat))
    grid, glo, dims = box_inflation_grid(lo, hi, lat, r, rotation=rotation,
                                         translation=translation, memory_budget=memory_budget)
    n = int(np.count_nonzero(grid))
    _check_result(r, float(grid.size), n, resolve_budget(memory_budget))
    out = np.empty(n, dtype=np.int64)
    vk.grid_keys(grid, glo, dims, BITS[d], index_limit(d), out)
    return OccupiedVoxelList._from_keys(lat, out)


def box_inflation_grid(lo: np.ndarray, hi: np.ndarray, lattice: Lattice, radius: float, *,
                       rotation: np.ndarray | None = None,
                       translation: np.ndarray | None = None,
                       memory_budget: int | None = DEFAULT_BUDGET,
                       ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The cells of :func:`exact_box_inflation` (``radius`` > 0, at least one box, 3D)
    marked in a byte grid.

    Parameters
    ----------
    lo, hi, lattice, radius, rotation, translation, memory_budget
        As for :func:`exact_box_inflation`.

    Returns
    -------
    grid : ndarray, shape (prod(dims),), uint8
        Nonzero for a marked cell, C order over the index box ``glo + [0, dims)``.
    glo, dims : ndarray, shape (3,), int64
    """
    lat = check_lattice(lattice)
    r = check_radius(radius)
    d = lat.dim
    centres, half, rot = box_frame(lo, hi, rotation, translation, d)
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
    return grid, glo.astype(np.int64), dims.astype(np.int64)
