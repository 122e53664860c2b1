"""Known and unknown space on a lattice: what a tri-state map says about each cell.

A map's space is occupied, observed free, or unknown (:class:`planner.io.Obstacles`). This
module turns the free-space information into lattice cells:

* :func:`ray_free_keys`: cells a sensor ray crosses before its end cell (posed scans, bags),
  by the exact segment walk of the world (every cell whose closed Voronoi cell the ray
  touches);
* :func:`unknown_box_keys`: for maps whose free space is a set of boxes on a voxel grid
  (OctoMap free leaves, ROS map free cells), the cells whose Voronoi cell meets unknown space
  (voxels covered by neither an occupied nor a free box), in a box padded around the bounds;
* :func:`unknown_cell_keys`: the same for cell-level free space (rays): every cell in the
  padded box that is neither observed free nor occupied;
* :func:`unknown_inflation`: the cells a robot of radius r must not enter when unknown space
  counts as an obstacle.

The guarantee: unknown space U lies inside the union of the closed Voronoi cells of the keys
returned (every point of U is in some closed cell meeting U with positive volume, up to
1e-9 cell diameters), so blocking every cell whose closed Voronoi cell comes closer than r
to one of those cells (:func:`planner.voxels.inflation_stencil`, exact for cell pairs)
keeps every point of every usable cell at distance >= r from U.
"""

from __future__ import annotations

import numpy as np

from planner._numba import njit_cached
from planner.errors import MapError
from planner.lattice import Lattice
from planner.occupancy import grid as wk
from planner.occupancy.keys import check_range, pack, unique_keys
from planner.occupancy.walk import c_array, segment_walk, walk_of
from planner.voxels import _box_kernels as bk
from planner.voxels import _unknown_kernels as uk
from planner.voxels import kernels as vk
from planner.voxels._checks import (
    DEFAULT_BUDGET,
    grid_strides,
    resolve_budget,
)
from planner.voxels.inflate import box_keys, stencil_inflation
from planner.voxels.stencil import _stencil_runs, inflation_stencil

# Margins within which another summation order of G w could decide a voxel face (voxels)
# or a bounds face (m, relative to the bounds' size) the other way: numpy decides those.
_EPS_VOXEL = 1e-6
_EPS_METRES = 1e-9

__all__ = ["cells_in_box", "ray_free_keys", "unknown_box_keys", "unknown_box_space",
           "unknown_cell_keys", "unknown_inflation"]


@njit_cached
def _box_cells(g, ilo, idims, lo, hi, out, fill):  # pragma: no cover - compiled
    """Cells of the index box ``ilo + [0, idims)`` whose centre lies in ``[lo, hi]``: the
    count, and with ``fill`` their indices in ``out``."""
    n = 0
    for a in range(idims[0]):
        i = ilo[0] + a
        for b in range(idims[1]):
            j = ilo[1] + b
            x0 = g[0, 0] * i + g[0, 1] * j
            x1 = g[1, 0] * i + g[1, 1] * j
            x2 = g[2, 0] * i + g[2, 1] * j
            for c in range(idims[2]):
                k = ilo[2] + c
                y0 = x0 + g[0, 2] * k
                y1 = x1 + g[1, 2] * k
                y2 = x2 + g[2, 2] * k
                if (lo[0] <= y0 <= hi[0] and lo[1] <= y1 <= hi[1] and lo[2] <= y2 <= hi[2]):
                    if fill:
                        out[n, 0] = i
                        out[n, 1] = j
                        out[n, 2] = k
                    n += 1
    return n


def _index_box(g: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(ilo, idims)``: an index box holding every cell whose centre lies in ``[lo, hi]``."""
    corners = np.array([[(lo, hi)[c][a] for a, c in enumerate(bits)]
                        for bits in np.ndindex(2, 2, 2)])
    w = corners @ np.linalg.inv(g).T
    ilo = np.floor(w.min(axis=0)).astype(np.int64) - 1
    return ilo, np.ceil(w.max(axis=0)).astype(np.int64) + 1 - ilo + 1


def cells_in_box(lattice: Lattice, lo: np.ndarray, hi: np.ndarray,
                 budget: float | None = DEFAULT_BUDGET) -> np.ndarray:
    """Every cell of a 3D lattice whose centre lies in the closed box ``[lo, hi]`` (m,
    shape (3,) each).

    Returns
    -------
    ndarray, shape (N, 3), int64
    """
    lo = np.ascontiguousarray(lo, dtype=float)
    hi = np.ascontiguousarray(hi, dtype=float)
    g = np.ascontiguousarray(lattice.generator, dtype=float)
    ilo, idims = _index_box(g, lo, hi)
    out = np.zeros((0, 3), dtype=np.int64)
    n = _box_cells(g, ilo, idims, lo, hi, out, False)
    budget = resolve_budget(budget)
    if n * 24 > budget:
        raise MapError(f"the box {lo.tolist()} .. {hi.tolist()} holds {n:,} cells, too many "
                       f"to enumerate within {budget / 2**30:.1f} GB; use larger cells")
    out = np.empty((n, 3), dtype=np.int64)
    _box_cells(g, ilo, idims, lo, hi, out, True)
    return out


# -- boxes on a voxel grid ---------------------------------------------------------------------
def _voxel_frame(boxes: np.ndarray, box_sizes: np.ndarray, free_boxes: np.ndarray,
                 free_sizes: np.ndarray, res: float, lo: np.ndarray, hi: np.ndarray, d: int
                 ) -> tuple[np.ndarray, ...]:
    """The voxel grid of the known boxes over ``[lo, hi]``: ``(phase (d,), g0 (d,), dims
    (d,), first (K, d), n (K,))``: voxel v spans ``phase + res * [v, v + 1)``, the grid holds
    voxels ``g0 + [0, dims)``, known box k covers grid voxels ``first[k] + [0, n[k])^d``."""
    known_c = np.concatenate([boxes, free_boxes]).reshape(-1, d)
    known_s = np.concatenate([box_sizes, free_sizes])
    # Grid aligned to the boxes.
    ref = known_c[0] - known_s[0] / 2 if len(known_c) else np.zeros(d)
    phase = ref - res * np.floor(ref / res)
    g0 = np.floor((np.asarray(lo) - phase) / res).astype(np.int64)
    g1 = np.ceil((np.asarray(hi) - phase) / res).astype(np.int64)
    n = np.maximum(np.rint(known_s / res).astype(np.int64), 1)
    first = np.rint((known_c - n[:, None] * res / 2 - phase) / res).astype(np.int64) - g0
    return phase, g0, g1 - g0, first, n


def unknown_box_keys(boxes: np.ndarray, box_sizes: np.ndarray, free_boxes: np.ndarray,
                     free_sizes: np.ndarray, resolution: float, lattice: Lattice,
                     lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """Keys of the cells whose closed Voronoi cell meets unknown space, for boxes on a grid.

    Known space is the union of the occupied and free boxes (each an axis-aligned cube of
    edge a multiple of ``resolution``, aligned to one voxel grid, as OctoMap leaves and ROS
    map cells are); unknown space is every voxel of that grid in ``[lo, hi]`` (rounded out
    to whole voxels) that no box covers, and everything outside that region.

    Parameters
    ----------
    boxes, free_boxes : ndarray, shape (M, d), (K, d)
        Occupied and free box centres (m).
    box_sizes, free_sizes : ndarray, shape (M,), (K,)
        Box edges (m).
    resolution : float
        Voxel edge (m).
    lattice : Lattice
    lo, hi : ndarray, shape (d,)
        The region to classify (m): the world bounds padded by the robot's reach.

    Returns
    -------
    ndarray, shape (U,), int64
        Sorted unique keys.
    """
    d = lattice.dim
    res = float(resolution)
    phase, g0, dims, first, n = _voxel_frame(boxes, box_sizes, free_boxes, free_sizes, res, lo,
                                             hi, d)
    known = np.zeros(tuple(int(x) for x in dims), dtype=bool)
    if len(first):
        for m in np.unique(n):
            sel = first[n == m]
            steps = np.stack(np.meshgrid(*[np.arange(m)] * d, indexing="ij"), -1).reshape(-1, d)
            for s in steps:
                v = sel + s
                ok = np.all((v >= 0) & (v < dims), axis=1)
                known[tuple(v[ok].T)] = True
    unknown = ~known
    # Boundary unknown voxels (a known voxel among their 3^d neighbours): every point of U
    # not deep inside it lies in one, so the cells overlapping them plus the cells whose
    # centre lies in U cover U.
    pad = np.pad(known, 1, constant_values=False)
    near_known = np.zeros_like(known)
    for off in np.ndindex(*(3,) * d):
        near_known |= pad[tuple(slice(o, o + dims[a]) for a, o in enumerate(off))]
    edge = np.argwhere(unknown & near_known)
    parts = []
    if len(edge):
        centres = phase + (edge + g0 + 0.5) * res
        parts.append(box_keys(centres, res, lattice))
    cells = cells_in_box(lattice, lo, hi)
    if len(cells):
        v = np.floor((cells @ lattice.generator.T - phase) / res).astype(np.int64) - g0
        v = np.clip(v, 0, dims - 1)
        parts.append(pack(cells[unknown[tuple(v.T)]]))
    if not parts:
        return np.zeros(0, dtype=np.int64)
    return unique_keys(np.concatenate(parts))


def unknown_box_grid(boxes: np.ndarray, box_sizes: np.ndarray, free_boxes: np.ndarray,
                     free_sizes: np.ndarray, resolution: float, lattice: Lattice,
                     lo: np.ndarray, hi: np.ndarray, radius: float | None = None,
                     budget: float | None = DEFAULT_BUDGET,
                     ) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """The cells of :func:`unknown_box_keys` and, with ``radius``, those of
    :func:`unknown_inflation` of its keys, marked in one byte grid over a lattice index box
    (what :func:`unknown_box_space` lists, and :func:`planner.build_world` reads directly).

    Parameters
    ----------
    boxes, free_boxes, box_sizes, free_sizes, resolution, lattice, lo, hi, radius, budget
        As for :func:`unknown_box_space`.

    Returns
    -------
    (grid, glo, dims) or None
        ``grid`` (prod(dims),) uint8 over the index box ``glo`` (3,) + ``[0, dims)`` in C
        order: bit 1 for a cell meeting unknown space, bit 2 for one within ``radius`` of
        it (with ``radius``). None when the grids do not fit ``budget``.
    """
    lat = lattice
    g = np.ascontiguousarray(lat.generator, dtype=float)
    res = float(resolution)
    lo = np.ascontiguousarray(lo, dtype=float)
    hi = np.ascontiguousarray(hi, dtype=float)
    phase, g0, vdims, first, n = _voxel_frame(boxes, box_sizes, free_boxes, free_sizes, res, lo,
                                              hi, 3)
    budget = resolve_budget(budget)
    if float(np.prod(vdims.astype(float))) > budget:
        return None
    known = np.zeros(int(np.prod(vdims)), dtype=np.uint8)
    uk.fill_known(known, vdims, np.ascontiguousarray(first), np.ascontiguousarray(n))
    # Boundary unknown voxels as boxes (as unknown_box_keys): their cells by overlap tests.
    edge = uk.edge_voxels(known, vdims)
    centres = np.ascontiguousarray(phase + (edge + g0 + 0.5) * res)
    half = np.full(centres.shape, res / 2)
    tests = bk.overlap_tests(lat, np.full((1, 3), res / 2), np.eye(3))  # all voxels alike
    base = lat.quantize(centres) if len(centres) else np.zeros((0, 3), dtype=np.int64)
    stencil = np.zeros((1, 3), dtype=np.int64) if not radius else inflation_stencil(
        lat, radius, budget)
    full = lat.neighbors("full")
    # The grid holds every candidate of the overlap tests and the dilation's reach past
    # every cell marked (no bounds checks in the kernels).
    e_dil = np.maximum(np.abs(stencil).max(axis=0), np.abs(full).max(axis=0)) + 1
    e_box = np.abs(tests.offsets).max(axis=0) + e_dil
    ilo, idims = _index_box(g, lo, hi)
    glo, ghi = ilo - e_dil, ilo + idims - 1 + e_dil
    if len(base):
        glo = np.minimum(glo, base.min(axis=0) - e_box)
        ghi = np.maximum(ghi, base.max(axis=0) + e_box)
    check_range(glo, ghi, 3)
    dims = ghi - glo + 1
    cells = float(np.prod(dims.astype(float)))
    if known.nbytes + cells > budget:  # one byte a cell; the dilation scratch is a plane
        return None
    strides = grid_strides(dims)
    grid = np.zeros(int(cells), dtype=np.uint8)
    # Cells whose centre lies in an unknown voxel of [lo, hi].
    single = np.count_nonzero(g, axis=1) <= 1  # G w then rounds the same in any order
    border = np.empty((1 << 16, 3), dtype=np.int64)
    while True:
        nb = uk.mark_unknown_centres(g, ilo, idims, lo, hi, phase, res, g0, known, vdims,
                                     single, _EPS_VOXEL, grid, glo, strides, border)
        if nb <= len(border):
            break
        border = np.empty((nb, 3), dtype=np.int64)
    if nb:  # decided as unknown_box_keys does
        w = border[:nb]
        v = np.floor((w @ g.T - phase) / res).astype(np.int64) - g0
        v = np.clip(v, 0, vdims - 1)
        w = w[known[v @ grid_strides(vdims)] == 0]
        grid[(w - glo) @ strides] |= 1
    # Then the cells overlapping boundary voxels (those already marked are not tested).
    bk.overlap_mark(centres, half, np.ascontiguousarray((base - glo) @ strides),
                    np.ascontiguousarray(lat.to_world(base)), tests.offs_world,
                    np.ascontiguousarray(tests.offsets @ strides), tests.axes, tests.axes_box,
                    tests.support_v, tests.packing, tests.covering, tests.tol, grid)
    del known
    if radius is not None and radius > 0 and np.any(grid):
        runs = _stencil_runs(stencil)
        if runs is not None:  # runs of cells times runs of the stencil, a plane at a time
            starts, lengths = runs
            order = np.lexsort((starts[:, 2], starts[:, 1], starts[:, 0]))
            starts, lengths = starts[order], lengths[order]
            sptr = np.flatnonzero(np.r_[True, starts[1:, 0] != starts[:-1, 0], True])
            vk.dilate_runs(grid, dims, *(np.ascontiguousarray(starts[:, m]) for m in range(3)),
                           np.ascontiguousarray(lengths), sptr.astype(np.int64),
                           np.empty(int(dims[1] * dims[2]) + 1, dtype=np.int32))
        else:
            vk.dilate(grid, np.flatnonzero(grid), stencil @ strides, full @ strides)
    return grid, glo, dims


def unknown_box_space(boxes: np.ndarray, box_sizes: np.ndarray, free_boxes: np.ndarray,
                      free_sizes: np.ndarray, resolution: float, lattice: Lattice,
                      lo: np.ndarray, hi: np.ndarray, radius: float | None = None,
                      near: np.ndarray | None = None, exclude: np.ndarray | None = None,
                      budget: float | None = DEFAULT_BUDGET,
                      ) -> tuple[np.ndarray, np.ndarray | None] | None:
    """The cells of :func:`unknown_box_keys` and, with ``radius``, those of
    :func:`unknown_inflation` of its keys whose centre lies in the box ``near``: the same
    sets, computed on dense grids (voxels of the map's grid, cells of the lattice's index
    box) instead of sorted key lists. 3D lattices.

    Parameters
    ----------
    boxes, free_boxes, box_sizes, free_sizes, resolution, lattice, lo, hi
        As for :func:`unknown_box_keys`.
    radius : float, optional
        Robot radius (m, >= 0): also return the blocked cells.
    near : ndarray, shape (2, 3), optional
        ``[min, max]`` (m) of the blocked cells' centres returned (default: all).
    exclude : ndarray, shape (E, 3), int, optional
        Cells left out of the blocked cells returned (those already blocked otherwise).
    budget : float, optional
        Bytes the dense grids may use (default: the memory budget).

    Returns
    -------
    (unknown, blocked) or None
        ``unknown`` (U, 3) int64: the cells meeting unknown space; ``blocked`` (B, 3) int64,
        or None without ``radius``; both distinct, in ascending key order. None when the
        grids do not fit ``budget``.
    """
    got = unknown_box_grid(boxes, box_sizes, free_boxes, free_sizes, resolution, lattice, lo,
                           hi, radius, budget)
    if got is None:
        return None
    grid, glo, dims = got
    lat = lattice
    g = np.ascontiguousarray(lat.generator, dtype=float)
    single = np.count_nonzero(g, axis=1) <= 1  # G w then rounds the same in any order
    unknown = np.empty((int(np.count_nonzero(grid & 1)), 3), dtype=np.int64)
    uk.grid_cells(grid, glo, dims, 1, unknown)
    if radius is None:
        return unknown, None
    ghi = glo + dims - 1
    strides = grid_strides(dims)
    if exclude is not None and len(exclude):  # bit 4: left out of the blocked cells
        inside = np.all((exclude >= glo) & (exclude <= ghi), axis=1)
        grid[(exclude[inside] - glo) @ strides] |= 4
    box = np.array([[-np.inf] * 3, [np.inf] * 3]) if near is None else np.asarray(near, float)
    eps = _EPS_METRES * (1.0 + float(np.abs(box[np.isfinite(box)]).max(initial=0.0)))
    out = np.empty((int(np.count_nonzero(grid)), 3), dtype=np.int64)
    unsure = np.empty(len(out), dtype=bool)
    m = uk.cells_near(grid, glo, dims, g, box[0], box[1], single, eps, out, unsure)
    out, unsure = out[:m], unsure[:m]
    if unsure.any():  # decided as planner.planning does, on lat.to_world
        c = lat.to_world(out[unsure])
        keep = np.ones(m, dtype=bool)
        keep[unsure] = np.all((c >= box[0]) & (c <= box[1]), axis=1)
        out = out[keep]
    return unknown, out


# -- rays --------------------------------------------------------------------------------------
@njit_cached
def _mark_rays(occ, walk, a, b, s, grid, lo, dims):  # pragma: no cover - compiled
    """Set to 0 in ``grid`` (flat uint8 over the index box ``lo``, ``dims``) every cell the
    segment a[i] -> b[i] touches, walking from cell s[i]."""
    for i in range(a.shape[0]):
        cells, _, _ = segment_walk(occ, walk, a[i], b[i], s[i], False)
        wk.clear_cells(grid, lo, dims, cells)


def ray_free_keys(points: np.ndarray, origins: np.ndarray, point_origin: np.ndarray,
                  lattice: Lattice) -> np.ndarray:
    """Cells observed free by sensor rays: every cell whose closed Voronoi cell the segment
    from a point's sensor origin to the point touches, except the cell containing the point
    and every cell containing some point (occupied wins).

    Parameters
    ----------
    points : ndarray, shape (N, 3)
        Obstacle points (m).
    origins : ndarray, shape (S, 3)
        Sensor origins (m).
    point_origin : ndarray, shape (N,), int
        Index into ``origins`` of each point.
    lattice : Lattice
        A 3D lattice.

    Returns
    -------
    ndarray, shape (F,), int64
        Sorted unique keys.
    """
    if lattice.dim != 3:
        raise MapError(f"ray casting needs a 3D lattice, got {lattice.dim}D")
    b = np.ascontiguousarray(points, dtype=float)
    a = np.ascontiguousarray(np.asarray(origins, dtype=float)[point_origin])
    if not len(b):
        return np.zeros(0, dtype=np.int64)
    s = np.ascontiguousarray(lattice.quantize(a))
    ends = lattice.quantize(b)
    both = np.concatenate([s, ends])
    lo = both.min(axis=0) - 2
    dims = both.max(axis=0) + 2 - lo + 1
    grid = np.ones(int(np.prod(dims)), dtype=np.uint8)  # 0: crossed by a ray
    g = c_array(lattice.generator, float)
    dummy = wk.Occupancy(mode=0, grid=np.ones(1, np.uint8), lo=np.zeros(3, np.int64),
                         dims=np.ones(3, np.int64), table=np.full(1, -1, np.int64), tmask=0,
                         gmat=g, blo=np.zeros(3), bhi=np.zeros(3))
    _mark_rays(dummy, walk_of(lattice), a, b, s, grid, lo.astype(np.int64),
               dims.astype(np.int64))
    grid[(ends - lo) @ grid_strides(dims)] = 1  # a point's own cell is occupied, not free
    flat = np.flatnonzero(grid == 0)
    idx = np.stack(np.unravel_index(flat, tuple(int(x) for x in dims)), axis=1) + lo
    return unique_keys(pack(idx))


def unknown_cell_keys(free_keys: np.ndarray, occupied_keys: np.ndarray, lattice: Lattice,
                      lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """Keys of the cells with centre in ``[lo, hi]`` (m) that are neither observed free
    (``free_keys``) nor occupied (``occupied_keys``): unknown at cell level.

    Returns
    -------
    ndarray, shape (U,), int64
        Sorted unique keys.
    """
    keys = unique_keys(pack(cells_in_box(lattice, lo, hi)))
    known = unique_keys(np.concatenate([free_keys, occupied_keys]))
    return keys[~np.isin(keys, known, assume_unique=True)]


def unknown_inflation(unknown_keys: np.ndarray, lattice: Lattice, radius: float,
                      budget: float | None = DEFAULT_BUDGET) -> np.ndarray:
    """Keys of the cells whose closed Voronoi cell comes closer than ``radius`` (m) to the
    closed Voronoi cell of an unknown cell (the unknown cells themselves included): where a
    robot centre may not go when unknown space counts as an obstacle (module docstring).

    Returns
    -------
    ndarray, shape (B,), int64
    """
    keys = unique_keys(np.asarray(unknown_keys, dtype=np.int64))
    if radius == 0 or not len(keys):
        return keys
    return stencil_inflation(keys, lattice, float(radius), budget)
