"""Compiled kernels of scan matching: membership in the occupancy layer's key sets, the fused
transform-quantize-lookup score of many poses, and ray casting through a voxel grid.

The score rounds each transformed point with the lattice's coset quantizer
(:mod:`planner.lattice.cosets`: the nearest of one or two roundings on a box sublattice,
the box's frame folded into the pose so that it costs nothing per point), fused with the
rigid transform and the lookup so that no (N, 3) temporary is made per pose; one code
path serves every named lattice, so their match times compare on equal terms. A lattice
without a box sublattice of small index uses the project's exact generic quantizer (the
tables of :meth:`planner.Lattice.quantizer` and
:func:`planner.lattice.quantize.closest_point3`) in :func:`score_poses`.
"""

from __future__ import annotations

import numpy as np

from planner._numba import njit_cached
from planner.lattice.quantize import candidate_norms3, closest_point3
from planner.occupancy.keys import in_key_set, in_key_set3


@njit_cached(nogil=True)
def contains_keys(table, bits, keys):  # pragma: no cover - compiled
    """(N,) bool: which of ``keys`` are in ``table`` (a key set of 2**bits slots)."""
    out = np.zeros(len(keys), dtype=np.bool_)
    mask = (1 << bits) - 1
    for i in range(len(keys)):
        out[i] = in_key_set(table, mask, keys[i])
    return out


@njit_cached(nogil=True)
def score_poses(pts, wts, rots, trans, b, binv, cand, cand_z, counts, t, table, bits,
                out):  # pragma: no cover - compiled
    """out[p] = sum of wts[i] over points i whose cell, after pose p, is in ``table``.

    pts (N, 3), wts (N,), rots (M, 3, 3), trans (M, 3), out (M,); the quantizer tables as
    in :class:`planner.lattice.Quantizer`.
    """
    cn = candidate_norms3(cand)
    mask = (1 << bits) - 1
    for p in range(rots.shape[0]):
        r = rots[p]
        tx, ty, tz = trans[p, 0], trans[p, 1], trans[p, 2]
        s = 0.0
        for i in range(pts.shape[0]):
            a0, a1, a2 = pts[i, 0], pts[i, 1], pts[i, 2]
            x0 = r[0, 0] * a0 + r[0, 1] * a1 + r[0, 2] * a2 + tx
            x1 = r[1, 0] * a0 + r[1, 1] * a1 + r[1, 2] * a2 + ty
            x2 = r[2, 0] * a0 + r[2, 1] * a1 + r[2, 2] * a2 + tz
            w0, w1, w2 = closest_point3(x0, x1, x2, b, binv, cand, cand_z, counts, t, cn)
            if in_key_set3(table, mask, w0, w1, w2):
                s += wts[i]
        out[p] = s


@njit_cached(nogil=True)
def score_poses_cosets(pts, wts, rots, trans, inv_sides, sides, shifts, mb, mo, table, bits,
                       out):  # pragma: no cover - compiled
    """:func:`score_poses` with the coset quantizer: ``rots`` (M, 3, 3) and ``trans`` (M, 3)
    take the points into the box frame (the pose premultiplied by the frame), the other
    tables are :class:`planner.lattice.cosets.CosetQuantizer`'s.

    The rounding is :func:`planner.lattice.cosets.closest_coset3`'s, written out here: as a
    call it cost 7 ns of a 30 ns lookup (numba does not inline it). With two cosets (every
    named lattice but cubic) the second rounding needs no second ``rint``: a sublattice of
    index 2 holds twice the shift ``h`` between the cosets, so in box units ``h = q + c/2``
    (``q`` integer, ``c`` 0 or 1 per axis); along an axis with ``c = 1`` the second coset's
    nearest coordinate lies ``1/2 - |e|`` away where the first's lies ``|e|`` (``e`` the
    rounding residual), so the second coset is nearer when
    ``sum_c side^2 (1/4 - |e|) < 0`` (squared distances, ``|e| <= 1/2``), and its point
    is ``n - q`` less one where ``c = 1`` and ``e < 0``."""
    mask = (1 << bits) - 1
    k = shifts.shape[0]
    s0, s1, s2 = sides[0], sides[1], sides[2]
    i0_, i1_, i2_ = inv_sides[0], inv_sides[1], inv_sides[2]
    # Index 2: the second coset's shift h (box units) is q + c/2, q integer, c 0 or 1 per
    # axis; g = c * side^2 weighs the axes where the two roundings differ.
    q0 = q1 = q2 = c0 = c1 = c2 = 0.0
    if k == 2:
        h0, h1, h2 = shifts[1, 0] * i0_, shifts[1, 1] * i1_, shifts[1, 2] * i2_
        q0, q1, q2 = np.floor(h0 + 1e-9), np.floor(h1 + 1e-9), np.floor(h2 + 1e-9)
        c0 = 1.0 if h0 - q0 > 0.25 else 0.0
        c1 = 1.0 if h1 - q1 > 0.25 else 0.0
        c2 = 1.0 if h2 - q2 > 0.25 else 0.0
    g0, g1, g2 = c0 * s0 * s0, c1 * s1 * s1, c2 * s2 * s2
    for p in range(rots.shape[0]):
        r = rots[p]
        tx, ty, tz = trans[p, 0], trans[p, 1], trans[p, 2]
        s = 0.0
        for i in range(pts.shape[0]):
            a0, a1, a2 = pts[i, 0], pts[i, 1], pts[i, 2]
            u0 = (r[0, 0] * a0 + r[0, 1] * a1 + r[0, 2] * a2 + tx) * i0_
            u1 = (r[1, 0] * a0 + r[1, 1] * a1 + r[1, 2] * a2 + ty) * i1_
            u2 = (r[2, 0] * a0 + r[2, 1] * a1 + r[2, 2] * a2 + tz) * i2_
            n0, n1, n2 = np.rint(u0), np.rint(u1), np.rint(u2)
            bc = 0
            if k == 2:  # every named lattice but cubic: see the docstring
                e0, e1, e2 = u0 - n0, u1 - n1, u2 - n2
                gain = (g0 * (0.25 - abs(e0)) + g1 * (0.25 - abs(e1))
                        + g2 * (0.25 - abs(e2)))
                if gain < 0.0:
                    n0 = n0 - q0 - (c0 if e0 < 0 else 0.0)
                    n1 = n1 - q1 - (c1 if e1 < 0 else 0.0)
                    n2 = n2 - q2 - (c2 if e2 < 0 else 0.0)
                    bc = 1
            elif k > 2:
                e0, e1, e2 = (u0 - n0) * s0, (u1 - n1) * s1, (u2 - n2) * s2
                best_d = e0 * e0 + e1 * e1 + e2 * e2
                for c in range(1, k):
                    v0 = u0 - shifts[c, 0] * i0_
                    v1 = u1 - shifts[c, 1] * i1_
                    v2 = u2 - shifts[c, 2] * i2_
                    m0, m1, m2 = np.rint(v0), np.rint(v1), np.rint(v2)
                    e0, e1, e2 = (v0 - m0) * s0, (v1 - m1) * s1, (v2 - m2) * s2
                    d = e0 * e0 + e1 * e1 + e2 * e2
                    if d < best_d:
                        best_d, n0, n1, n2, bc = d, m0, m1, m2, c
            j0, j1, j2 = np.int64(n0), np.int64(n1), np.int64(n2)
            w0 = mb[0, 0] * j0 + mb[0, 1] * j1 + mb[0, 2] * j2 + mo[bc, 0]
            w1 = mb[1, 0] * j0 + mb[1, 1] * j1 + mb[1, 2] * j2 + mo[bc, 1]
            w2 = mb[2, 0] * j0 + mb[2, 1] * j1 + mb[2, 2] * j2 + mo[bc, 2]
            if in_key_set3(table, mask, w0, w1, w2):
                s += wts[i]
        out[p] = s


@njit_cached(nogil=True)
def score_poses_cubic(pts, wts, rots, trans, inv_side, table, bits,
                      out):  # pragma: no cover - compiled
    """:func:`score_poses` on an axis-aligned cubic lattice of side ``1 / inv_side`` with
    the rounding written for it (``rint(x / side)`` per axis, no quantizer tables): the
    floor the other roundings are measured against (``benchmarks/match_speed.py``)."""
    mask = (1 << bits) - 1
    for p in range(rots.shape[0]):
        r = rots[p]
        tx, ty, tz = trans[p, 0], trans[p, 1], trans[p, 2]
        s = 0.0
        for i in range(pts.shape[0]):
            a0, a1, a2 = pts[i, 0], pts[i, 1], pts[i, 2]
            w0 = np.int64(np.rint((r[0, 0] * a0 + r[0, 1] * a1 + r[0, 2] * a2 + tx) * inv_side))
            w1 = np.int64(np.rint((r[1, 0] * a0 + r[1, 1] * a1 + r[1, 2] * a2 + ty) * inv_side))
            w2 = np.int64(np.rint((r[2, 0] * a0 + r[2, 1] * a1 + r[2, 2] * a2 + tz) * inv_side))
            if in_key_set3(table, mask, w0, w1, w2):
                s += wts[i]
        out[p] = s


@njit_cached(nogil=True)
def cast_rays(origin, dirs, grid, lo, h, max_range, out):  # pragma: no cover - compiled
    """Distance along each unit ray to the first occupied voxel of ``grid`` (inf: none
    within ``max_range`` or the grid).

    Exact ray-box intersection by a voxel walk (Amanatides and Woo): ``grid`` (nx, ny, nz)
    bool is the map's occupied boxes on their own axis-aligned grid of spacing ``h`` (m)
    with corner ``lo`` (3,); the distance returned is the ray's entry into the first
    occupied voxel, i.e. into the box that contains it.
    """
    nx, ny, nz = grid.shape
    for r in range(dirs.shape[0]):
        out[r] = np.inf
        cell = np.empty(3, dtype=np.int64)
        step = np.empty(3, dtype=np.int64)
        tmax = np.empty(3)
        tdel = np.empty(3)
        inside = True
        for a in range(3):
            f = (origin[a] - lo[a]) / h
            cell[a] = np.int64(np.floor(f))
            d = dirs[r, a]
            if d > 0:
                step[a] = 1
                tmax[a] = (lo[a] + (cell[a] + 1) * h - origin[a]) / d
                tdel[a] = h / d
            elif d < 0:
                step[a] = -1
                tmax[a] = (lo[a] + cell[a] * h - origin[a]) / d
                tdel[a] = -h / d
            else:
                step[a] = 0
                tmax[a] = np.inf
                tdel[a] = np.inf
        if not (0 <= cell[0] < nx and 0 <= cell[1] < ny and 0 <= cell[2] < nz):
            inside = False
        if inside and grid[cell[0], cell[1], cell[2]]:
            out[r] = 0.0
            continue
        while inside:
            a = 0
            if tmax[1] < tmax[a]:
                a = 1
            if tmax[2] < tmax[a]:
                a = 2
            tt = tmax[a]
            if tt > max_range:
                break
            cell[a] += step[a]
            tmax[a] += tdel[a]
            if cell[a] < 0 or cell[a] >= grid.shape[a]:
                break
            if grid[cell[0], cell[1], cell[2]]:
                out[r] = tt
                break
