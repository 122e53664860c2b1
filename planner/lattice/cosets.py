"""Closest lattice point as the nearest of a few roundings: a lattice as a union of cosets of
a rectangular sublattice.

If a lattice ``L`` holds three mutually orthogonal vectors ``u_1, u_2, u_3``, they span a
rectangular (box) sublattice ``S`` of index ``k = [L : S]``, and ``L`` is the union of the
``k`` cosets ``S + v_c``. In the frame of the unit vectors ``Q = (u_j / |u_j|)`` the
closest point of a coset is found by rounding each coordinate on its side ``|u_j|``, so
the closest point of ``L`` is the nearest of ``k`` roundings (Conway and Sloane's
construction of BCC and A2 as unions of two rectangular lattices, in general). The named
lattices need one rounding (cubic) or two (BCC: the cube of side ``a``; FCC = D3: the box
``(1,1,0), (1,-1,0), (0,0,2)``; hexagonal prism: ``a x a sqrt(3) x h``; MCC: a box of
index 2 too), against the generic kernel's rounding in a reduced basis plus a scan of up to
a dozen candidates (:func:`planner.lattice.quantize.closest_point3`). Ties (points
equidistant from two lattice points, a set of measure zero) may resolve differently.

:func:`coset_quantizer` finds the sublattice of smallest index among the integer
combinations of the reduced basis with coefficients in ``[-3, 3]``; it returns None when
there is none of index at most :data:`MAX_COSETS` (a general lattice has no orthogonal
vectors at all), and callers then use the generic kernel.
"""

from __future__ import annotations

import functools
import itertools
from typing import NamedTuple

import numpy as np

from planner._numba import njit_cached

__all__ = ["CosetQuantizer", "MAX_COSETS", "closest_coset3", "coset_quantizer", "quantize",
           "quantize_cosets3", "quantize_with"]

MAX_COSETS = 4
_RANGE = 3  # coefficients searched per reduced basis vector


class CosetQuantizer(NamedTuple):
    """Tables of :func:`closest_coset3`.

    Attributes
    ----------
    frame : ndarray, shape (3, 3)
        Rows: the unit axes of the box sublattice (world -> box frame: ``y = frame @ x``).
    inv_sides : ndarray, shape (3,)
        1 / the box's sides (1/m).
    sides : ndarray, shape (3,)
        The box's sides (m).
    shifts : ndarray, shape (k, 3)
        Coset offsets in the box frame (m).
    index_basis : ndarray, shape (3, 3), int64
        Lattice indices (in the user's generator) of the box's generators, as columns.
    index_offsets : ndarray, shape (k, 3), int64
        Lattice indices of each coset's offset.
    """

    frame: np.ndarray
    inv_sides: np.ndarray
    sides: np.ndarray
    shifts: np.ndarray
    index_basis: np.ndarray
    index_offsets: np.ndarray

    @property
    def cosets(self) -> int:
        """Roundings per point."""
        return len(self.shifts)


def _orthogonal_box(basis: np.ndarray) -> np.ndarray | None:
    """Integer coefficients (3, 3), columns, in ``basis`` of three mutually orthogonal
    lattice vectors spanning a sublattice of the smallest index (at most
    :data:`MAX_COSETS`); among equal indices the most cube-like box. None if none."""
    r = range(-_RANGE, _RANGE + 1)
    coef = np.array([c for c in itertools.product(r, r, r) if any(c)], dtype=np.int64)
    # One of each +-pair: the first nonzero coefficient positive.
    first = coef[np.arange(len(coef)), (coef != 0).argmax(axis=1)]
    coef = coef[first > 0]
    vec = coef @ basis.T
    norm = np.linalg.norm(vec, axis=1)
    gram = vec @ vec.T
    orth = np.abs(gram) <= 1e-9 * np.outer(norm, norm)
    pairs = np.argwhere(np.triu(orth, 1))
    if not len(pairs):
        return None
    third = orth[pairs[:, 0]] & orth[pairs[:, 1]]
    third &= np.arange(len(coef))[None, :] > pairs[:, 1:2]
    p, m = np.nonzero(third)
    if not len(p):
        return None
    trip = np.stack([pairs[p, 0], pairs[p, 1], m], axis=1)
    c = np.transpose(coef[trip], (0, 2, 1))  # (T, 3, 3), columns the coefficients
    idx = np.abs(np.rint(np.linalg.det(c.astype(float)))).astype(np.int64)
    lengths = norm[trip]
    ok = (idx > 0) & (idx <= MAX_COSETS)
    if not ok.any():
        return None
    ratio = lengths.max(axis=1) / lengths.min(axis=1)
    order = np.lexsort((lengths.sum(axis=1), ratio, idx))
    best = order[ok[order]][0]
    return c[best]


def _representatives(c: np.ndarray) -> np.ndarray:
    """One integer vector (rows, in the reduced basis) per coset of the sublattice with
    coefficient columns ``c``: the shortest of each class found in a small box."""
    k = abs(round(float(np.linalg.det(c))))
    cinv = np.linalg.inv(c)
    seen: dict[tuple, np.ndarray] = {}
    r = range(-k, k + 1)
    for z in sorted(itertools.product(r, r, r), key=lambda v: sum(x * x for x in v)):
        frac = cinv @ np.array(z, dtype=float)
        key = tuple(np.round((frac - np.floor(frac + 1e-9)) * k).astype(int) % k)
        if key not in seen:
            seen[key] = np.array(z, dtype=np.int64)
        if len(seen) == k:
            break
    return np.array(list(seen.values()), dtype=np.int64)


@functools.lru_cache(maxsize=64)
def _box(basis_bytes: bytes) -> tuple[np.ndarray, np.ndarray] | None:
    """Box coefficients and coset representatives of a (scale-normalised) basis."""
    c = _orthogonal_box(np.frombuffer(basis_bytes).reshape(3, 3))
    return None if c is None else (c, _representatives(c))


def _tables(basis: np.ndarray, t: np.ndarray) -> CosetQuantizer | None:
    scale = abs(float(np.linalg.det(basis))) ** (1 / 3)
    # Rounded so that the levels of one lattice (generator times 2**k) share one search.
    found = _box(np.round(basis / scale, 12).tobytes())
    if found is None:
        return None
    c, reps = found
    u = basis @ c  # box generators, columns (m)
    sides = np.linalg.norm(u, axis=0)
    frame = (u / sides).T
    shifts = (reps @ basis.T) @ frame.T
    ti = np.rint(t).astype(np.int64)
    return CosetQuantizer(np.ascontiguousarray(frame), 1.0 / sides, sides,
                          np.ascontiguousarray(shifts), np.ascontiguousarray(ti @ c),
                          np.ascontiguousarray(reps @ ti.T))


def coset_quantizer(lattice) -> CosetQuantizer | None:
    """The :class:`CosetQuantizer` of a 3D :class:`planner.lattice.Lattice`, or None when it
    has no box sublattice of index at most :data:`MAX_COSETS` (see the module)."""
    if lattice.dim != 3:
        return None
    q = lattice.quantizer()
    return _tables(np.asarray(q.basis, dtype=float), np.asarray(q.reduction, dtype=float))


@njit_cached(_nrt=False)
def closest_coset3(y0, y1, y2, inv_sides, sides, shifts, mb, mo):  # pragma: no cover
    """Indices (three int64, in the user's generator) of the lattice point closest to the
    point whose box-frame coordinates are ``(y0, y1, y2)`` (m, i.e. ``frame @ x``): the
    nearest of one rounding per coset. The tables are :class:`CosetQuantizer`'s."""
    u0, u1, u2 = y0 * inv_sides[0], y1 * inv_sides[1], y2 * inv_sides[2]
    n0, n1, n2 = np.rint(u0), np.rint(u1), np.rint(u2)
    bc = 0
    if shifts.shape[0] > 1:
        # Distances in metres: the box may have unequal sides.
        e0, e1, e2 = (u0 - n0) * sides[0], (u1 - n1) * sides[1], (u2 - n2) * sides[2]
        best_d = e0 * e0 + e1 * e1 + e2 * e2
        for c in range(1, shifts.shape[0]):
            v0 = u0 - shifts[c, 0] * inv_sides[0]
            v1 = u1 - shifts[c, 1] * inv_sides[1]
            v2 = u2 - shifts[c, 2] * inv_sides[2]
            m0, m1, m2 = np.rint(v0), np.rint(v1), np.rint(v2)
            e0, e1, e2 = (v0 - m0) * sides[0], (v1 - m1) * sides[1], (v2 - m2) * sides[2]
            d = e0 * e0 + e1 * e1 + e2 * e2
            if d < best_d:
                best_d, n0, n1, n2, bc = d, m0, m1, m2, c
    i0, i1, i2 = np.int64(n0), np.int64(n1), np.int64(n2)
    return (mb[0, 0] * i0 + mb[0, 1] * i1 + mb[0, 2] * i2 + mo[bc, 0],
            mb[1, 0] * i0 + mb[1, 1] * i1 + mb[1, 2] * i2 + mo[bc, 1],
            mb[2, 0] * i0 + mb[2, 1] * i1 + mb[2, 2] * i2 + mo[bc, 2])


@njit_cached(nogil=True)
def quantize_cosets3(x, frame, inv_sides, sides, shifts, mb, mo, out):  # pragma: no cover
    """Quantize ``x`` ((N, 3) float64, m) into ``out`` ((N, 3) int64) by
    :func:`closest_coset3` (the tables of a :class:`CosetQuantizer`)."""
    for i in range(x.shape[0]):
        a0, a1, a2 = x[i, 0], x[i, 1], x[i, 2]
        y0 = frame[0, 0] * a0 + frame[0, 1] * a1 + frame[0, 2] * a2
        y1 = frame[1, 0] * a0 + frame[1, 1] * a1 + frame[1, 2] * a2
        y2 = frame[2, 0] * a0 + frame[2, 1] * a1 + frame[2, 2] * a2
        out[i, 0], out[i, 1], out[i, 2] = closest_coset3(y0, y1, y2, inv_sides, sides,
                                                         shifts, mb, mo)


def quantize(lattice, points: np.ndarray) -> np.ndarray:
    """(N, 3) int64 indices of the cells of ``lattice`` holding ``points`` ((N, 3), m): the
    coset kernel when the lattice has one, else :meth:`planner.lattice.Lattice.quantize`
    (the same cells but for ties). For lattices derived from a named one (scaled levels,
    summaries), which lose the named lattice's dedicated kernel."""
    cq = coset_quantizer(lattice)
    if cq is None:
        return lattice.quantize(points)
    return quantize_with(cq, points)


def quantize_with(cq: CosetQuantizer, points: np.ndarray) -> np.ndarray:
    """:func:`quantize` with the lattice's :class:`CosetQuantizer` already in hand."""
    x = np.ascontiguousarray(points, dtype=np.float64)
    out = np.empty((len(x), 3), dtype=np.int64)
    quantize_cosets3(x, cq.frame, cq.inv_sides, cq.sides, cq.shifts, cq.index_basis,
                     cq.index_offsets, out)
    return out
