"""Compiled (numba) kernels of :mod:`planner.voxels`, dimension-generic (2D and 3D).

Cells are addressed either by packed keys (:mod:`planner.occupancy.keys`) or, inside a dense scratch
grid over an index box, by flat C-order positions ``sum((w - lo) * strides)``. A lattice
offset ``delta`` is then a constant flat offset, so dilation is a 1D loop.

The Voronoi cell V of the origin travels as one :class:`CellPolytope` struct. Box kernels
(overlap and exact distance) are in :mod:`planner.voxels._box_kernels`.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from planner._numba import njit_cached


class CellPolytope(NamedTuple):
    """The Voronoi cell V of the origin for the kernels (metres).

    ``normals`` (k, d) unit facet normals and ``offsets`` (k,): V = {y : normals y <= offsets};
    ``e0``, ``e1`` (m, d) edge end points (in 2D the edges are the facets); ``vertices``
    (n, d); ``packing`` / ``covering``: radii of balls about 0 inside / around V.
    """

    normals: np.ndarray
    offsets: np.ndarray
    e0: np.ndarray
    e1: np.ndarray
    vertices: np.ndarray
    packing: float
    covering: float


def cell_polytope(voronoi, rotation: np.ndarray | None = None) -> CellPolytope:
    """:class:`CellPolytope` of a :class:`planner.lattice.VoronoiCell`, optionally expressed
    in a rotated frame (coordinates ``R^T y``: the frame whose axes are R's columns)."""
    def c(a: np.ndarray) -> np.ndarray:
        a = np.asarray(a, dtype=float)
        return np.ascontiguousarray(a if rotation is None else a @ rotation)

    e0, e1 = voronoi.edges
    return CellPolytope(c(voronoi.normals), np.array(voronoi.offsets, dtype=float), c(e0), c(e1),
                        c(voronoi.vertices), float(voronoi.packing_radius),
                        float(voronoi.covering_radius))


@njit_cached(_nrt=False)
def _in_cell(a, b, y, tol):  # pragma: no cover - compiled
    """Is ``y`` in {x : a x <= b + tol}?"""
    for i in range(a.shape[0]):
        s = 0.0
        for j in range(a.shape[1]):
            s += a[i, j] * y[j]
        if s > b[i] + tol:
            return False
    return True


@njit_cached
def cell_distance(y, cell, tol):  # pragma: no cover - compiled
    """Exact Euclidean distance from point ``y`` (d,) to the Voronoi cell V.

    The nearest point of V lies in the relative interior of a facet, on an edge or at a
    vertex. Facet candidates are the orthogonal projections that land inside V (within
    ``tol``): V lies on one side of the facet plane, so such a projection is the nearest
    point. Edge candidates are the clamped projections onto the edge segments (always in V,
    vertices included). The minimum over the candidates is the distance; ``tol`` can only
    make it smaller (conservative for "closer than r" tests).
    """
    a, b, e0, e1 = cell.normals, cell.offsets, cell.e0, cell.e1
    k, d = a.shape
    if _in_cell(a, b, y, tol):
        return 0.0
    best = np.inf
    proj = np.empty(d)
    for i in range(k):
        s = -b[i]
        for j in range(d):
            s += a[i, j] * y[j]
        if s <= 0.0 or s >= best:  # not beyond this facet, or cannot improve
            continue
        for j in range(d):
            proj[j] = y[j] - s * a[i, j]
        if _in_cell(a, b, proj, tol):
            best = s
    for m in range(e0.shape[0]):
        uu = 0.0
        uy = 0.0
        for j in range(d):
            u = e1[m, j] - e0[m, j]
            uu += u * u
            uy += u * (y[j] - e0[m, j])
        t = min(max(uy / uu, 0.0), 1.0)
        s = 0.0
        for j in range(d):
            r = y[j] - e0[m, j] - t * (e1[m, j] - e0[m, j])
            s += r * r
        s = math.sqrt(s)
        if s < best:
            best = s
    return best


@njit_cached
def cell_distances(ys, cell, tol, out):  # pragma: no cover - compiled
    """:func:`cell_distance` for every row of ``ys`` (n, d) into ``out`` (n,)."""
    for i in range(ys.shape[0]):
        out[i] = cell_distance(ys[i], cell, tol)


@njit_cached
def mark_boundary(grid, occ_flat, full_flat):  # pragma: no cover - compiled
    """Mark ``occ_flat`` with bit 1 and return the positions of the occupied cells that have
    a free full neighbour (the only ones a dilation needs).

    Skipping interior cells is exact: if ``x`` in V(c) and ``y`` in V(c + delta) are closer
    than r, walk the segment from ``y`` to ``x``; the first point on an occupied closed cell
    V(m) also lies in a free closed cell (the ones before it), so ``m`` is a boundary cell
    and V(m) is still within r of V(c + delta). The grid must be padded by the stencil
    and full-neighbour extents (no bounds checks here).
    """
    for i in range(occ_flat.shape[0]):
        grid[occ_flat[i]] = 1
    out = np.empty(occ_flat.shape[0], dtype=np.int64)
    n = 0
    for i in range(occ_flat.shape[0]):
        p = occ_flat[i]
        for j in range(full_flat.shape[0]):
            if (grid[p + full_flat[j]] & 1) == 0:
                out[n] = p
                n += 1
                break
    return out[:n]


@njit_cached
def dilate(grid, occ_flat, stencil_flat, full_flat):  # pragma: no cover - compiled
    """Mark ``occ_flat`` with bit 1, then OR bit 2 into ``occ + stencil`` for every
    boundary cell (:func:`mark_boundary`)."""
    edge = mark_boundary(grid, occ_flat, full_flat)
    for i in range(edge.shape[0]):
        p = edge[i]
        for j in range(stencil_flat.shape[0]):
            grid[p + stencil_flat[j]] |= 2


@njit_cached
def dilate_rows(grid, occ_flat, full_flat, row_start, row_len, diff
                ):  # pragma: no cover - compiled
    """:func:`dilate` with the stencil as runs along the last (stride 1) axis: each
    boundary cell adds +1 at a run's start and -1 after its end in ``diff`` (int32, one
    longer than ``grid``), and one prefix sum marks the union. Two writes per run instead
    of one per offset (a 3 m ball of 0.08 m cells: ~4,000 runs for ~200,000 offsets)."""
    edge = mark_boundary(grid, occ_flat, full_flat)
    for i in range(edge.shape[0]):
        p = edge[i]
        for j in range(row_start.shape[0]):
            a = p + row_start[j]
            diff[a] += 1
            diff[a + row_len[j]] -= 1
    run = 0
    for f in range(grid.shape[0]):
        run += diff[f]
        if run > 0:
            grid[f] |= 2


@njit_cached
def _line_runs(grid, dims, fill, ry, rs, re, ptr):  # pragma: no cover - compiled
    """The runs of cells with bit 1 set along the last axis of ``grid`` (C order over
    ``dims`` (3,)): their count, and with ``fill`` each run's line ``ry`` (middle index),
    start ``rs`` and end ``re`` (last index + 1), grouped by plane (first index) with
    ``ptr`` (dims[0] + 1,) the start of each plane's runs."""
    n1, n2 = dims[1], dims[2]
    n = 0
    for a in range(dims[0]):
        if fill:
            ptr[a] = n
        for b in range(n1):
            row = (a * n1 + b) * n2
            c = 0
            while c < n2:
                if grid[row + c] & 1 == 0:
                    c += 1
                    continue
                c0 = c
                while c < n2 and grid[row + c] & 1:
                    c += 1
                if fill:
                    ry[n] = b
                    rs[n] = c0
                    re[n] = c
                n += 1
    if fill:
        ptr[dims[0]] = n
    return n


@njit_cached
def dilate_runs(grid, dims, sx, sy, sz, slen, sptr, diff):  # pragma: no cover - compiled
    """OR bit 2 into every cell of ``grid`` (uint8, C order over ``dims`` (3,)) that some
    cell with bit 1 reaches by an offset of a stencil given as runs along the last axis:
    run ``r`` holds the offsets ``(sx[r], sy[r], sz[r] + [0, slen[r]))``, the runs sorted
    by ``sx`` with ``sptr`` the start of each distinct ``sx`` (one past the last at the
    end). The grid must hold every offset of every marked cell (no bounds checks).

    The marked cells are taken as runs along the last axis too: a source run and a stencil
    run cover one interval of one target line, written as +1 at its start and -1 after its
    end into ``diff`` (int32, one plane of the grid + 1), one target plane at a time, and a
    prefix sum over the plane marks their union. Work: source runs x stencil runs, on a
    plane-sized scratch."""
    n0, n1, n2 = dims[0], dims[1], dims[2]
    none32 = np.empty(0, dtype=np.int32)
    count = _line_runs(grid, dims, False, none32, none32, none32, np.empty(0, np.int64))
    ry = np.empty(count, dtype=np.int32)
    rs = np.empty(count, dtype=np.int32)
    re = np.empty(count, dtype=np.int32)
    ptr = np.empty(n0 + 1, dtype=np.int64)
    _line_runs(grid, dims, True, ry, rs, re, ptr)
    plane = n1 * n2
    ngroups = sptr.shape[0] - 1
    for xt in range(n0):
        touched = False
        for gi in range(ngroups):
            xs = xt - sx[sptr[gi]]
            if xs < 0 or xs >= n0 or ptr[xs] == ptr[xs + 1]:
                continue
            if not touched:
                diff[:plane + 1] = 0
                touched = True
            for q in range(ptr[xs], ptr[xs + 1]):
                yb = ry[q]
                s = rs[q]
                e = re[q]
                for r in range(sptr[gi], sptr[gi + 1]):
                    f = (yb + sy[r]) * n2 + sz[r]
                    diff[f + s] += 1
                    diff[f + e + slen[r] - 1] -= 1
        if not touched:
            continue
        run = 0
        off = xt * plane
        for f in range(plane):
            run += diff[f]
            if run > 0:
                grid[off + f] |= 2


@njit_cached
def flat_positions(keys, lo, strides, bits, limit, out):  # pragma: no cover - compiled
    """Flat grid positions ``sum((w - lo) * strides)`` of packed ``keys`` into ``out``."""
    d = lo.shape[0]
    mask = (np.int64(1) << bits) - 1
    for i in range(keys.shape[0]):
        k = keys[i]
        f = np.int64(0)
        for j in range(d - 1, -1, -1):
            w = (k & mask) - limit
            k >>= bits
            f += (w - lo[j]) * strides[j]
        out[i] = f


@njit_cached
def grid_keys(grid, lo, dims, bits, limit, out):  # pragma: no cover - compiled
    """Packed keys of the nonzero cells of ``grid`` in C order (ascending keys) into ``out``.
    Returns the number written."""
    d = dims.shape[0]
    w = np.zeros(d, dtype=np.int64)  # the index of p, counted up (no divisions)
    n = 0
    for p in range(grid.shape[0]):
        if grid[p] != 0:
            key = np.int64(0)
            for j in range(d):
                key = (key << bits) | (w[j] + lo[j] + limit)
            out[n] = key
            n += 1
        j = d - 1
        w[j] += 1
        while j > 0 and w[j] == dims[j]:
            w[j] = 0
            j -= 1
            w[j] += 1
    return n


@njit_cached
def exact_mark(points, centres, base_flat, grid, cand_flat, cand_world, cell, tol, radius
               ):  # pragma: no cover - compiled
    """Mark (set to 1) every grid cell whose Voronoi cell is at distance < ``radius`` from a
    point. ``centres[i]`` is the centre of the cell containing ``points[i]`` (flat position
    ``base_flat[i]``); candidate cells are ``base + cand``. The cell's packing and covering
    radii bound the distance as ``|y| - covering <= dist <= |y| - packing``.
    Returns the number of exact point-to-cell distance evaluations."""
    d = points.shape[1]
    rho, big_r = cell.packing, cell.covering
    y = np.empty(d)
    evals = 0
    for i in range(points.shape[0]):
        for o in range(cand_flat.shape[0]):
            f = base_flat[i] + cand_flat[o]
            if grid[f] != 0:
                continue
            s = 0.0
            for j in range(d):
                y[j] = points[i, j] - centres[i, j] - cand_world[o, j]
                s += y[j] * y[j]
            s = math.sqrt(s)
            if s - big_r >= radius:
                continue
            if s - rho < radius:
                grid[f] = 1
                continue
            evals += 1
            if cell_distance(y, cell, tol) < radius:
                grid[f] = 1
    return evals
