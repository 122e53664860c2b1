"""Compiled (numba) kernels classifying unknown space on a dense grid (3D).

Two grids travel together: ``known`` (uint8, C order over a voxel index box ``vdims``) says
which voxels of a map's grid some occupied or free box covers, and ``grid`` (uint8, C order
over a lattice index box starting at ``glo`` with ``strides``) collects cells (bit 1:
meets unknown space). Cell centres are computed as ``G w`` in the order
:func:`planner.voxels.unknown.cells_in_box` uses; where another summation order (numpy's
``w @ G.T``) could round to the other side of a voxel face or a bounds face, the kernels
hand the cell back to the caller (``border``) instead of deciding it.
"""

from __future__ import annotations

import math

import numpy as np

from planner._numba import njit_cached
from planner.occupancy.bits import line_range


@njit_cached
def fill_known(known, vdims, first, n):  # pragma: no cover - compiled
    """Set to 1 in ``known`` ((vdims) flat) every voxel of the cubes ``first[i] + [0, n[i])^3``
    (clipped to the grid)."""
    s0 = vdims[1] * vdims[2]
    s1 = vdims[2]
    for i in range(first.shape[0]):
        a0, a1 = max(first[i, 0], 0), min(first[i, 0] + n[i], vdims[0])
        b0, b1 = max(first[i, 1], 0), min(first[i, 1] + n[i], vdims[1])
        c0, c1 = max(first[i, 2], 0), min(first[i, 2] + n[i], vdims[2])
        for a in range(a0, a1):
            for b in range(b0, b1):
                row = a * s0 + b * s1
                for c in range(c0, c1):
                    known[row + c] = 1


@njit_cached
def edge_voxels(known, vdims):  # pragma: no cover - compiled
    """(E, 3) indices of the unknown voxels with a known voxel among their 26 neighbours
    (outside the grid counts as not known), in C order. The 3x3x3 neighbourhood is taken
    one axis at a time (three sequential passes instead of 27 lookups a voxel)."""
    n0, n1, n2 = vdims[0], vdims[1], vdims[2]
    s0 = n1 * n2
    near = np.zeros(known.shape[0], dtype=np.uint8)
    tmp = np.zeros(known.shape[0], dtype=np.uint8)
    for r in range(n0 * n1):  # along the last axis
        row = r * n2
        for c in range(n2):
            v = known[row + c]
            if c > 0:
                v |= known[row + c - 1]
            if c + 1 < n2:
                v |= known[row + c + 1]
            near[row + c] = v
    for a in range(n0):  # along the middle axis
        for b in range(n1):
            row = a * s0 + b * n2
            for c in range(n2):
                v = near[row + c]
                if b > 0:
                    v |= near[row - n2 + c]
                if b + 1 < n1:
                    v |= near[row + n2 + c]
                tmp[row + c] = v
    n = 0
    for p in range(known.shape[0]):  # along the first axis, counting the edge voxels
        a = p // s0
        v = tmp[p]
        if a > 0:
            v |= tmp[p - s0]
        if a + 1 < n0:
            v |= tmp[p + s0]
        v = v & (1 - known[p])
        near[p] = v
        n += v
    out = np.empty((n, 3), dtype=np.int64)
    n = 0
    p = 0
    for a in range(n0):
        for b in range(n1):
            for c in range(n2):
                if near[p]:
                    out[n, 0] = a
                    out[n, 1] = b
                    out[n, 2] = c
                    n += 1
                p += 1
    return out


@njit_cached(_nrt=False)
def _near_face(t, eps):  # pragma: no cover - compiled
    """Is ``t`` within ``eps`` of an integer (a voxel face in voxel units)?"""
    return math.floor(t - eps) != math.floor(t + eps)


@njit_cached(_nrt=False)
def _voxel(x, gk, k, phase, res, g0, n, single, eps):  # pragma: no cover - compiled
    """Voxel index (clipped to ``[0, n)``) along one axis of the cell centre ``x + gk * k``,
    and whether it lies within ``eps`` voxels of a face along an axis that sums several
    terms (``single`` False)."""
    t = (x + gk * k - phase) / res
    return (min(max(np.int64(math.floor(t)) - g0, 0), n - 1),
            (not single) and _near_face(t, eps))


@njit_cached
def mark_unknown_centres(g, ilo, idims, lo, hi, phase, res, g0, known, vdims, single, eps,
                         grid, glo, strides, border):  # pragma: no cover - compiled
    """OR 1 into ``grid`` for every cell of the index box ``ilo + [0, idims)`` whose centre
    lies in ``[lo, hi]`` and in an unknown voxel (voxel ``floor((x - phase) / res) - g0``,
    clipped to the grid). A cell whose centre lies within ``eps`` voxels of a voxel face
    along an axis whose coordinate sums several terms (``single[a]`` False) is written to
    ``border`` instead (while it has room). Returns the number of border cells.

    Along a line of the last index the centre moves by ``G[:, 2]``: the cells in the
    bounds are an interval of it (found by bisection), and an axis the line does not move
    along is classified once per line; each cell is decided by the same float expressions
    either way."""
    s0 = vdims[1] * vdims[2]
    s1 = vdims[2]
    m0, m1, m2 = g[0, 2] != 0.0, g[1, 2] != 0.0, g[2, 2] != 0.0
    nb = 0
    k0, k1 = ilo[2], ilo[2] + idims[2]
    for a in range(idims[0]):
        i = ilo[0] + a
        for b in range(idims[1]):
            j = ilo[1] + b
            x0 = g[0, 0] * i + g[0, 1] * j
            x1 = g[1, 0] * i + g[1, 1] * j
            x2 = g[2, 0] * i + g[2, 1] * j
            ka, kb = line_range(x0, g[0, 2], lo[0], hi[0], k0, k1)
            ra, rb = line_range(x1, g[1, 2], lo[1], hi[1], ka, kb)
            ka, kb = max(ka, ra), min(kb, rb)
            ra, rb = line_range(x2, g[2, 2], lo[2], hi[2], ka, kb)
            ka, kb = max(ka, ra), min(kb, rb)
            if ka >= kb:
                continue
            base = (i - glo[0]) * strides[0] + (j - glo[1]) * strides[1] - glo[2] * strides[2]
            # The axes the line does not move along, once (at any k: the same values).
            v0, q0 = _voxel(x0, g[0, 2], ka, phase[0], res, g0[0], vdims[0], single[0], eps)
            v1, q1 = _voxel(x1, g[1, 2], ka, phase[1], res, g0[1], vdims[1], single[1], eps)
            v2, q2 = _voxel(x2, g[2, 2], ka, phase[2], res, g0[2], vdims[2], single[2], eps)
            for k in range(ka, kb):
                if m0:
                    v0, q0 = _voxel(x0, g[0, 2], k, phase[0], res, g0[0], vdims[0], single[0],
                                    eps)
                if m1:
                    v1, q1 = _voxel(x1, g[1, 2], k, phase[1], res, g0[1], vdims[1], single[1],
                                    eps)
                if m2:
                    v2, q2 = _voxel(x2, g[2, 2], k, phase[2], res, g0[2], vdims[2], single[2],
                                    eps)
                if q0 or q1 or q2:
                    if nb < border.shape[0]:
                        border[nb, 0] = i
                        border[nb, 1] = j
                        border[nb, 2] = k
                    nb += 1
                elif known[v0 * s0 + v1 * s1 + v2] == 0:
                    grid[base + k * strides[2]] |= 1
    return nb


@njit_cached
def grid_cells(grid, glo, dims, bit, out):  # pragma: no cover - compiled
    """Indices of the cells of ``grid`` with ``bit`` set, in C order (ascending keys), into
    ``out``. Returns the number written."""
    n = 0
    p = 0
    for a in range(dims[0]):
        for b in range(dims[1]):
            for c in range(dims[2]):
                if grid[p] & bit:
                    out[n, 0] = glo[0] + a
                    out[n, 1] = glo[1] + b
                    out[n, 2] = glo[2] + c
                    n += 1
                p += 1
    return n


@njit_cached
def cells_near(grid, glo, dims, g, lo, hi, single, eps, out, border
               ):  # pragma: no cover - compiled
    """Indices of the marked cells of ``grid`` (nonzero, bit 4 clear) whose centre ``G w``
    lies in ``[lo, hi]``, in C order (ascending keys) into ``out``; ``border[n]`` is True for a
    cell whose centre lies within ``eps`` metres of a face of the box along an axis whose
    coordinate sums several terms (``single`` False): the caller decides those. Returns
    the number written."""
    n = 0
    p = 0
    w = np.empty(3, dtype=np.int64)
    for a in range(dims[0]):
        w[0] = glo[0] + a
        for b in range(dims[1]):
            w[1] = glo[1] + b
            for c in range(dims[2]):
                p += 1
                if grid[p - 1] == 0 or grid[p - 1] & 4:
                    continue
                w[2] = glo[2] + c
                unsure = False
                ok = True
                for m in range(3):
                    y = g[m, 0] * w[0] + g[m, 1] * w[1] + g[m, 2] * w[2]
                    if not single[m] and (abs(y - lo[m]) <= eps or abs(y - hi[m]) <= eps):
                        unsure = True
                    elif y < lo[m] or y > hi[m]:
                        ok = False
                if ok:
                    out[n, 0] = w[0]
                    out[n, 1] = w[1]
                    out[n, 2] = w[2]
                    border[n] = unsure
                    n += 1
    return n
