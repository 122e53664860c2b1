"""Compiled (numba) kernels deciding which lattice cells meet boxes, dimension-generic.

A box is given by its centre ``C`` (world, metres) and half sizes ``H`` in a frame whose
axes are the columns of a rotation ``R`` shared by all boxes: ``{C + R x : |x| <= H}``.
Cell geometry travels as a :class:`planner.voxels.kernels.CellPolytope` expressed in the
boxes' frame (so a box is axis-aligned there).

* :func:`overlap_keys` / :func:`overlap_mark`: cells whose Voronoi cell overlaps a box with
  positive volume, by the separating axis theorem (the axes are the facet normals of the
  Minkowski sum box + V), as keys or marked in a dense grid.
* :func:`within_mark`: cells whose closed Voronoi cell is closer than ``r`` to a box (3D),
  by ball bounds and, in the thin shell they leave undecided, GJK on support functions.

:func:`overlap_tests` prepares the overlap kernels' inputs (:class:`OverlapTests`).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from planner._numba import njit_cached
from planner.lattice import Lattice
from planner.voxels._checks import REL_TOL, cell_diameter, offsets_within


class OverlapTests(NamedTuple):
    """What the overlap kernels (:func:`overlap_keys`, :func:`overlap_mark`) need for
    boxes of half sizes up to ``half`` on a lattice: candidate ``offsets`` (n, d) about a
    box's base cell with their world vectors ``offs_world``, separating ``axes`` (m, d),
    ``axes_box`` ``|axes @ R|``, the cell's ``support_v`` (m,), radii and tolerance."""

    offsets: np.ndarray
    offs_world: np.ndarray
    axes: np.ndarray
    axes_box: np.ndarray
    support_v: np.ndarray
    packing: float
    covering: float
    tol: float


def overlap_tests(lat: Lattice, half: np.ndarray, rot: np.ndarray) -> OverlapTests:
    """:class:`OverlapTests` for boxes of half sizes ``half`` (K, d) (m) in the frame ``rot``."""
    cell = lat.voronoi
    tol = REL_TOL * max(cell_diameter(lat), 2 * float(half.max()))
    axes = cell.separating_axes(rot)
    support_v = np.abs(cell.vertices @ axes.T).max(axis=0)
    reach = float(np.linalg.norm(half, axis=1).max()) + 2 * cell.covering_radius + tol
    offs = offsets_within(lat, reach, None, reach)
    return OverlapTests(offs, np.ascontiguousarray(offs @ lat.generator.T, dtype=float), axes,
                        np.ascontiguousarray(np.abs(axes @ rot)), support_v,
                        cell.packing_radius, cell.covering_radius, tol)


@njit_cached(_nrt=False)
def _overlap_thresholds(half_i, axes_box, support_v, packing, covering, tol, thr
                        ):  # pragma: no cover - compiled
    """Per-axis thresholds ``thr`` of one box (half sizes ``half_i``) and the radii
    ``(r_in, r_out)`` of balls about its centre inside / around box + V."""
    d = half_i.shape[0]
    hmin = np.inf
    h2 = 0.0
    for j in range(d):
        hmin = min(hmin, half_i[j])
        h2 += half_i[j] * half_i[j]
    for m in range(axes_box.shape[0]):
        s = support_v[m] - tol
        for j in range(d):
            s += axes_box[m, j] * half_i[j]
        thr[m] = s
    return hmin + packing - tol, math.sqrt(h2) + covering + tol


@njit_cached(_nrt=False)
def _overlaps(centre_i, base_i, offs_o, axes, thr, r_in, r_out, x
              ):  # pragma: no cover - compiled
    """Does the cell centred at ``base_i + offs_o`` overlap the box (see overlap_keys)?"""
    d = centre_i.shape[0]
    r2 = 0.0
    for j in range(d):
        x[j] = base_i[j] + offs_o[j] - centre_i[j]
        r2 += x[j] * x[j]
    if r2 > r_out * r_out:
        return False
    if r2 >= r_in * r_in:
        for m in range(axes.shape[0]):
            s = 0.0
            for j in range(d):
                s += axes[m, j] * x[j]
            if abs(s) >= thr[m]:
                return False
    return True


@njit_cached
def overlap_keys(centres, half, base_keys, base_world, offs_world, offs_key, axes, axes_box,
                 support_v, packing, covering, tol, out):  # pragma: no cover - compiled
    """Keys of the cells whose Voronoi cell overlaps box i with positive volume.

    For box ``i`` the candidates are ``base_keys[i] + offs_key[o]`` with centres
    ``base_world[i] + offs_world[o]``. ``axes`` (m, d): separating axes (world); ``axes_box``
    (m, d): ``|axes @ R|``, so a box's support along axis m is ``axes_box[m] . H``;
    ``support_v`` (m,): the cell's support along each axis; ``packing`` / ``covering``: the
    cell's radii. Overlap iff ``|a . x| < support
    - tol`` on every axis (``x`` cell centre minus box centre): mere touching does not count.
    Balls about the box centre inside / around box + V accept / reject most candidates
    first. Returns the number of keys written to ``out``.
    """
    n = 0
    x = np.empty(centres.shape[1])
    thr = np.empty(axes.shape[0])
    for i in range(centres.shape[0]):
        r_in, r_out = _overlap_thresholds(half[i], axes_box, support_v, packing, covering,
                                          tol, thr)
        for o in range(offs_world.shape[0]):
            if _overlaps(centres[i], base_world[i], offs_world[o], axes, thr, r_in, r_out, x):
                out[n] = base_keys[i] + offs_key[o]
                n += 1
    return n


@njit_cached
def overlap_mark(centres, half, base_flat, base_world, offs_world, offs_flat, axes, axes_box,
                 support_v, packing, covering, tol, grid):  # pragma: no cover - compiled
    """:func:`overlap_keys` into a dense grid: OR 1 into ``grid[base_flat[i] +
    offs_flat[o]]`` for every overlapping candidate and for each box's base cell; cells
    already marked are not tested again. The grid must hold every candidate."""
    x = np.empty(centres.shape[1])
    thr = np.empty(axes.shape[0])
    for i in range(centres.shape[0]):
        grid[base_flat[i]] |= 1
        r_in, r_out = _overlap_thresholds(half[i], axes_box, support_v, packing, covering,
                                          tol, thr)
        for o in range(offs_world.shape[0]):
            f = base_flat[i] + offs_flat[o]
            if grid[f] & 1:
                continue
            if _overlaps(centres[i], base_world[i], offs_world[o], axes, thr, r_in, r_out, x):
                grid[f] |= 1


@njit_cached
def _closest_on_simplex(w, n, lam, scratch):  # pragma: no cover - compiled
    """Closest point to the origin of the convex hull of ``w[:n]`` (n <= d + 1 points).

    Every subset whose affine projection of the origin has non-negative barycentric
    coordinates gives a point of the hull; the nearest such point is the answer (the
    closest point lies in the relative interior of one face). Returns the squared distance
    and the mask of the chosen subset; ``lam`` receives its barycentric coordinates.
    """
    d = w.shape[1]
    best = np.inf
    best_mask = 0
    idx = np.empty(d + 1, dtype=np.int64)
    a = scratch  # (d + 1, d + 2) augmented Gram system
    for mask in range(1, 1 << n):
        m = 0
        for i in range(n):
            if mask & (1 << i):
                idx[m] = i
                m += 1
        p0 = idx[0]
        k = m - 1
        # Gram system for mu: sum_j (D_i . D_j) mu_j = -D_i . w[p0], D_i = w[idx[i]] - w[p0].
        for i in range(k):
            for jj in range(k):
                s = 0.0
                for c in range(d):
                    s += (w[idx[i + 1], c] - w[p0, c]) * (w[idx[jj + 1], c] - w[p0, c])
                a[i, jj] = s
            s = 0.0
            for c in range(d):
                s -= (w[idx[i + 1], c] - w[p0, c]) * w[p0, c]
            a[i, k] = s
        ok = True
        scale = 0.0
        for i in range(k):
            scale = max(scale, a[i, i])
        for col in range(k):  # Gaussian elimination with partial pivoting
            piv = col
            for r in range(col + 1, k):
                if abs(a[r, col]) > abs(a[piv, col]):
                    piv = r
            if abs(a[piv, col]) <= 1e-12 * scale:
                ok = False
                break
            if piv != col:
                for c in range(k + 1):
                    a[col, c], a[piv, c] = a[piv, c], a[col, c]
            for r in range(col + 1, k):
                f = a[r, col] / a[col, col]
                for c in range(col, k + 1):
                    a[r, c] -= f * a[col, c]
        if not ok:
            continue
        mu_sum = 0.0
        for i in range(k - 1, -1, -1):
            s = a[i, k]
            for c in range(i + 1, k):
                s -= a[i, c] * a[c, k + 1]
            a[i, k + 1] = s / a[i, i]
            mu_sum += a[i, k + 1]
            if a[i, k + 1] < 0.0:
                ok = False
        if not ok or mu_sum > 1.0:
            continue
        dist2 = 0.0
        for c in range(d):
            v = w[p0, c]
            for i in range(k):
                v += a[i, k + 1] * (w[idx[i + 1], c] - w[p0, c])
            dist2 += v * v
        if dist2 < best:
            best = dist2
            best_mask = mask
            lam[:] = 0.0
            lam[p0] = 1.0 - mu_sum
            for i in range(k):
                lam[idx[i + 1]] = a[i, k + 1]
    return best, best_mask


@njit_cached
def gjk_within(p, half, verts, radius, tol, w, lam, scratch):  # pragma: no cover - compiled
    """Is the cell ``p + V`` (vertices ``verts`` (n, d), box frame) closer than ``radius``
    to the box ``[-half, half]``? GJK on K = (p + V) - box, distance from the origin.

    Each step gives an upper bound ``|v|`` (v a point of K) and a lower bound ``v.w / |v|``
    (w the support point of K along -v); the answer is returned as soon as one bound
    decides it. A distance within ``tol`` of ``radius`` counts as closer (a tie is blocked,
    whichever bound sees it: conservative for the clearance guarantee).
    ``w`` (d + 1, d), ``lam`` (d + 1,), ``scratch`` (d + 1, d + 2): work arrays.
    """
    d = p.shape[0]
    r2 = radius * radius
    out2 = (radius + tol) ** 2  # "not closer" needs a margin of tol: ties count as blocked
    v = np.empty(d)
    s = np.empty(d)
    # Start at p - clamp(p): the cell centre minus the nearest box point, a point of K.
    # It starts the simplex, so every later closest point is at least as near.
    for j in range(d):
        v[j] = p[j] - min(max(p[j], -half[j]), half[j])
        w[0, j] = v[j]
    n = 1
    for _ in range(64):
        vv = 0.0
        for j in range(d):
            vv += v[j] * v[j]
        if vv < r2:
            return True
        # Support of K along -v: argmin over V of v . y, plus the box corner against v.
        best = np.inf
        bi = 0
        for i in range(verts.shape[0]):
            t = 0.0
            for j in range(d):
                t += v[j] * verts[i, j]
            if t < best:
                best = t
                bi = i
        vw = 0.0
        for j in range(d):
            s[j] = p[j] + verts[bi, j] + (-half[j] if v[j] > 0.0 else half[j])
            vw += v[j] * s[j]
        if vw > 0.0 and vw * vw >= out2 * vv:
            return False
        if vv - vw <= tol * math.sqrt(vv):
            return True  # converged within tol of radius
        for j in range(d):
            w[n, j] = s[j]
        n += 1
        dist2, mask = _closest_on_simplex(w, n, lam, scratch)
        if dist2 >= vv:  # no progress: numerically converged
            return True
        m = 0
        for j in range(d):
            v[j] = 0.0
        for i in range(n):
            if mask & (1 << i):
                for j in range(d):
                    v[j] += lam[i] * w[i, j]
                    w[m, j] = w[i, j]
                m += 1
        n = m
        if n == d + 1:
            return True  # the origin is inside the simplex: the cell meets the box
    return True


@njit_cached
def within_mark(centres, half, rot, base_flat, base_world, sure_flat, cand_flat, cand_world,
                verts, packing, covering, radius, tol, grid):  # pragma: no cover - compiled
    """Mark (set to 1) every grid cell whose closed Voronoi cell is closer than ``radius``
    to some box (3D). Cells ``base_flat[i] + sure_flat`` are marked untested (the caller
    knows every one passes the first bound below). Candidates of box i: flat
    ``base_flat[i] + cand_flat[o]``, centre ``base_world[i] + cand_world[o]``. With ``d0``
    the distance of the cell centre to the box, ``d0 - covering <= dist <= max(d0 -
    packing, 0)`` decides most candidates, a separating plane and the nearest cell vertex
    most others; GJK (:func:`gjk_within`, cell vertices ``verts`` in the box frame) the
    rest. Returns the number of GJK calls."""
    p = np.empty(3)
    hb = np.empty(3)
    w = np.empty((4, 3))
    lam = np.empty(4)
    scratch = np.empty((4, 5))
    # Ties (distance within tol of radius) count as closer on every path, so the result
    # does not depend on which bound decides a cell (aligned grids have many exact ties).
    far2 = (radius + tol + covering) ** 2
    near2 = (radius + packing) ** 2
    r2 = radius * radius
    calls = 0
    for i in range(centres.shape[0]):
        for o in range(sure_flat.shape[0]):
            grid[base_flat[i] + sure_flat[o]] = 1
        h0, h1, h2 = half[i, 0], half[i, 1], half[i, 2]
        # The base cell centre relative to the box centre, in the box frame.
        c0 = base_world[i, 0] - centres[i, 0]
        c1 = base_world[i, 1] - centres[i, 1]
        c2 = base_world[i, 2] - centres[i, 2]
        b0 = rot[0, 0] * c0 + rot[1, 0] * c1 + rot[2, 0] * c2
        b1 = rot[0, 1] * c0 + rot[1, 1] * c1 + rot[2, 1] * c2
        b2 = rot[0, 2] * c0 + rot[1, 2] * c1 + rot[2, 2] * c2
        for o in range(cand_flat.shape[0]):
            f = base_flat[i] + cand_flat[o]
            if grid[f] != 0:
                continue
            # cand_world is already in the box frame (see exact_box_inflation).
            p0 = b0 + cand_world[o, 0]
            p1 = b1 + cand_world[o, 1]
            p2 = b2 + cand_world[o, 2]
            q0 = min(max(p0, -h0), h0)
            q1 = min(max(p1, -h1), h1)
            q2 = min(max(p2, -h2), h2)
            u0, u1, u2 = p0 - q0, p1 - q1, p2 - q2
            d2 = u0 * u0 + u1 * u1 + u2 * u2
            if d2 >= far2:
                continue
            if d2 < near2:
                grid[f] = 1
                continue
            # The plane through the nearest box point q, normal u = (p - q) / d0, separates
            # the box: dist >= d0 - h_V(u). The cell vertex v* furthest along -u gives
            # dist <= dist(p + v*, box). One pass over the vertices decides most of the rest.
            best = np.inf
            bi = 0
            for m in range(verts.shape[0]):
                t = verts[m, 0] * u0 + verts[m, 1] * u1 + verts[m, 2] * u2
                if t < best:
                    best = t
                    bi = m
            d0 = math.sqrt(d2)
            if d0 + best / d0 >= radius + tol:
                continue
            e0 = max(abs(p0 + verts[bi, 0]) - h0, 0.0)
            e1 = max(abs(p1 + verts[bi, 1]) - h1, 0.0)
            e2 = max(abs(p2 + verts[bi, 2]) - h2, 0.0)
            if e0 * e0 + e1 * e1 + e2 * e2 < r2:
                grid[f] = 1
                continue
            calls += 1
            p[0], p[1], p[2] = p0, p1, p2
            hb[0], hb[1], hb[2] = h0, h1, h2
            if gjk_within(p, hb, verts, radius, tol, w, lam, scratch):
                grid[f] = 1
    return calls
