"""Closest-lattice-point kernels (numba), one pass over the points, no temporaries, and the
tables of the generic kernel as one typed struct (:class:`Quantizer`).

Specialised kernels follow Conway and Sloane, "Fast quantizing and decoding algorithms
for lattice quantizers and codes" (1982): Z^n by rounding, D3 (FCC) by rounding with a
parity fix, D3* (BCC) and A2 (hexagonal) as unions of two shifted rectangular lattices.
Each computes the world lattice point, then the indices ``round(G^-1 p)`` (exact since
``p`` is a lattice point). The generic kernel rounds in a reduced basis and tests a
precomputed, provably sufficient candidate set.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from planner._numba import njit_cached


class Quantizer(NamedTuple):
    """Tables of the exact generic quantizer (:func:`quantize_generic3`), plain arrays that
    can be pickled and shipped to another process.

    Attributes
    ----------
    basis : ndarray, shape (d, d)
        LLL-reduced basis ``B`` (metres).
    basis_inv : ndarray, shape (d, d)
        ``B^-1``.
    cand : ndarray, shape (2**d, k, d)
        Candidate offsets in metres, per sign pattern of the rounding residual.
    cand_z : ndarray, shape (2**d, k, d), int64
        The same offsets in reduced coefficients.
    counts : ndarray, shape (2**d,), int64
        How many rows of ``cand`` are used per sign pattern.
    reduction : ndarray, shape (d, d), float64
        ``T`` with ``G T = B``: indices in the user's generator are ``T z``.
    """

    basis: np.ndarray
    basis_inv: np.ndarray
    cand: np.ndarray
    cand_z: np.ndarray
    counts: np.ndarray
    reduction: np.ndarray


def make_quantizer(geo: dict) -> Quantizer:
    """The generic quantizer's tables from a lattice geometry (writable contiguous copies:
    numba types read-only and writable arrays differently)."""
    b = np.array(geo["reduced"], dtype=float)
    cand_z = np.array(geo["orthant_offsets"], dtype=np.int64)
    return Quantizer(b, np.linalg.inv(b), np.ascontiguousarray(cand_z.astype(float) @ b.T),
                     cand_z, np.array(geo["orthant_counts"], dtype=np.int64),
                     np.array(geo["reduction"], dtype=float))


def run_generic(q: Quantizer, x: np.ndarray, out: np.ndarray) -> None:
    """Quantize ``x`` (N, d) into ``out`` (N, d) int64 with the generic kernel."""
    kernel = quantize_generic3 if x.shape[1] == 3 else quantize_generic
    kernel(x, q.basis, q.basis_inv, q.cand, q.cand_z, q.counts, q.reduction, out)


def named_scalars(kind: str, g: np.ndarray) -> tuple[int, float, float] | None:
    """The specialised kernel of a named lattice and the scalars it takes from the generator
    ``g`` (3, 3): ``(code, a, b)``, code 1 cubic, 2 FCC, 3 BCC, 4 hexagonal prism (also
    :func:`planner.occupancy.grid.point_cell`'s codes); None when there is none."""
    if kind == "cubic":
        return 1, 1.0 / g[0, 0], 0.0
    if kind == "fcc":
        return 2, -g[2, 2], 0.0  # FCC = b * D3, b = -G[2,2]
    if kind == "bcc":
        return 3, g[0, 0], 0.0  # BCC = a * (Z3 u Z3 + 1/2)
    if kind == "hex":
        return 4, g[0, 0], g[2, 2]  # A2 (side a) x Z (height h)
    return None


def run_named(kind: str, g: np.ndarray, ginv: np.ndarray, x: np.ndarray, out: np.ndarray
              ) -> bool:
    """Quantize with the specialised kernel of a named lattice; False if there is none."""
    named = named_scalars(kind, g)
    if named is None:
        return False
    code, a, b = named
    quantize_code(code, a, b, ginv, x, out)
    return True


@njit_cached(nogil=True)
def quantize_code(code, a, b, ginv, x, out):  # pragma: no cover - compiled
    """:func:`run_named` inside compiled code: quantize ``x`` ((N, 3) float64, m) into
    ``out`` ((N, 3) int64) with the kernel ``code`` (1 cubic, 2 FCC, 3 BCC, 4 hexagonal
    prism) and its scalars ``a``, ``b`` (:func:`named_scalars`)."""
    if code == 1:
        quantize_cubic(x, a, out)
    elif code == 2:
        quantize_fcc(x, a, ginv, out)
    elif code == 3:
        quantize_bcc(x, a, ginv, out)
    else:
        quantize_hex(x, a, b, ginv, out)


@njit_cached(nogil=True)
def quantize_cubic(x, inv_s, out):  # pragma: no cover - compiled
    n, d = x.shape
    for i in range(n):
        for j in range(d):
            out[i, j] = np.int64(np.rint(x[i, j] * inv_s))


@njit_cached(nogil=True)
def _indices3(p0, p1, p2, ginv, out, i):  # pragma: no cover - compiled
    for j in range(3):
        out[i, j] = np.int64(np.rint(ginv[j, 0] * p0 + ginv[j, 1] * p1 + ginv[j, 2] * p2))


@njit_cached(_nrt=False)
def _scaled3(x, i, inv):  # pragma: no cover - compiled
    """Row i of x times inv, and its rounding."""
    u0, u1, u2 = x[i, 0] * inv, x[i, 1] * inv, x[i, 2] * inv
    return u0, u1, u2, np.rint(u0), np.rint(u1), np.rint(u2)


@njit_cached(nogil=True)
def quantize_fcc(x, b, ginv, out):  # pragma: no cover - compiled
    """FCC = b * D3 (integer vectors with even coordinate sum)."""
    inv_b = 1.0 / b
    for i in range(x.shape[0]):
        u0, u1, u2, f0, f1, f2 = _scaled3(x, i, inv_b)
        s = int(f0 + f1 + f2)
        if s & 1:
            # Odd sum: re-round the coordinate with the largest rounding error the other way.
            e0 = u0 - f0
            e1 = u1 - f1
            e2 = u2 - f2
            a0, a1, a2 = abs(e0), abs(e1), abs(e2)
            if a0 >= a1 and a0 >= a2:
                f0 += 1.0 if e0 > 0 else -1.0
            elif a1 >= a2:
                f1 += 1.0 if e1 > 0 else -1.0
            else:
                f2 += 1.0 if e2 > 0 else -1.0
        _indices3(f0 * b, f1 * b, f2 * b, ginv, out, i)


@njit_cached(nogil=True)
def quantize_bcc(x, a, ginv, out):  # pragma: no cover - compiled
    """BCC = a * (Z3 u (Z3 + 1/2)): the nearer of the two roundings."""
    inv_a = 1.0 / a
    for i in range(x.shape[0]):
        u0, u1, u2, p0, p1, p2 = _scaled3(x, i, inv_a)
        q0 = np.rint(u0 - 0.5) + 0.5
        q1 = np.rint(u1 - 0.5) + 0.5
        q2 = np.rint(u2 - 0.5) + 0.5
        dp = (u0 - p0) ** 2 + (u1 - p1) ** 2 + (u2 - p2) ** 2
        dq = (u0 - q0) ** 2 + (u1 - q1) ** 2 + (u2 - q2) ** 2
        if dq < dp:
            p0, p1, p2 = q0, q1, q2
        _indices3(p0 * a, p1 * a, p2 * a, ginv, out, i)


@njit_cached(nogil=True)
def quantize_hex(x, a, h, ginv, out):  # pragma: no cover - compiled
    """Hexagonal prism: A2 with side a in x-y (union of two rectangular lattices
    a x a*sqrt(3), one shifted by (a/2, a*sqrt(3)/2)), times h*Z along z."""
    ry = a * np.sqrt(3.0)
    for i in range(x.shape[0]):
        u = x[i, 0] / a
        v = x[i, 1] / ry
        p0 = np.rint(u)
        p1 = np.rint(v)
        q0 = np.rint(u - 0.5) + 0.5
        q1 = np.rint(v - 0.5) + 0.5
        dp = ((u - p0) * a) ** 2 + ((v - p1) * ry) ** 2
        dq = ((u - q0) * a) ** 2 + ((v - q1) * ry) ** 2
        if dq < dp:
            p0, p1 = q0, q1
        z = np.rint(x[i, 2] / h)
        _indices3(p0 * a, p1 * ry, z * h, ginv, out, i)


@njit_cached(nogil=True)
def quantize_generic(x, b, binv, cand, cand_z, counts, t, out):  # pragma: no cover - compiled
    """Round in reduced basis b, then pick the nearest of the candidate offsets.

    The sign pattern of the rounding residual f = b^-1 x - round(b^-1 x) selects a row
    o = sum_i (f_i > 0) << i of cand (2^d, k, d) world offsets (cand_z: the same in
    reduced coefficients), of which the first counts[o] are the exact candidate set.
    t is the reduction: indices in the user's generator are t @ z.
    """
    n, d = x.shape
    k = cand.shape[1]
    z = np.empty(d, dtype=np.float64)
    r = np.empty(d, dtype=np.float64)
    cn = np.empty((cand.shape[0], k), dtype=np.float64)
    for o in range(cand.shape[0]):
        for j in range(k):
            s = 0.0
            for m in range(d):
                s += cand[o, j, m] * cand[o, j, m]
            cn[o, j] = s
    for i in range(n):
        o = 0
        for m in range(d):
            s = 0.0
            for c in range(d):
                s += binv[m, c] * x[i, c]
            z[m] = np.rint(s)
            if s > z[m]:
                o |= 1 << m
        for m in range(d):
            s = x[i, m]
            for c in range(d):
                s -= b[m, c] * z[c]
            r[m] = s
        # |r - c|^2 = |r|^2 - 2 r.c + |c|^2: minimise the last two terms.
        best = 0
        best_v = np.inf
        for j in range(counts[o]):
            s = cn[o, j]
            for m in range(d):
                s -= 2.0 * r[m] * cand[o, j, m]
            if s < best_v:
                best_v = s
                best = j
        for m in range(d):
            acc = 0.0
            for c in range(d):
                acc += t[m, c] * (z[c] + cand_z[o, best, c])
            out[i, m] = np.int64(np.rint(acc))


@njit_cached
def candidate_norms3(cand):  # pragma: no cover - compiled
    """(8, k) squared lengths of the candidate offsets ``cand`` (8, k, 3) of a 3D quantizer."""
    k = cand.shape[1]
    cn = np.empty((8, k), dtype=np.float64)
    for o in range(8):
        for j in range(k):
            cn[o, j] = cand[o, j, 0] ** 2 + cand[o, j, 1] ** 2 + cand[o, j, 2] ** 2
    return cn


@njit_cached(_nrt=False)
def closest_point3(x0, x1, x2, b, binv, cand, cand_z, counts, t, cn):  # pragma: no cover
    """Indices (three int64, in the user's generator) of the lattice point closest to
    ``(x0, x1, x2)`` (metres): the body of :func:`quantize_generic3`, called by every
    compiled caller; ``cn`` from :func:`candidate_norms3`."""
    y0 = binv[0, 0] * x0 + binv[0, 1] * x1 + binv[0, 2] * x2
    y1 = binv[1, 0] * x0 + binv[1, 1] * x1 + binv[1, 2] * x2
    y2 = binv[2, 0] * x0 + binv[2, 1] * x1 + binv[2, 2] * x2
    z0, z1, z2 = np.rint(y0), np.rint(y1), np.rint(y2)
    o = (1 if y0 > z0 else 0) | (2 if y1 > z1 else 0) | (4 if y2 > z2 else 0)
    r0 = 2.0 * (x0 - b[0, 0] * z0 - b[0, 1] * z1 - b[0, 2] * z2)
    r1 = 2.0 * (x1 - b[1, 0] * z0 - b[1, 1] * z1 - b[1, 2] * z2)
    r2 = 2.0 * (x2 - b[2, 0] * z0 - b[2, 1] * z1 - b[2, 2] * z2)
    # |r - c|^2 = |r|^2 - 2 r.c + |c|^2: minimise the last two terms.
    best = 0
    best_v = np.inf
    for j in range(counts[o]):
        s = cn[o, j] - r0 * cand[o, j, 0] - r1 * cand[o, j, 1] - r2 * cand[o, j, 2]
        if s < best_v:
            best_v = s
            best = j
    w0 = z0 + cand_z[o, best, 0]
    w1 = z1 + cand_z[o, best, 1]
    w2 = z2 + cand_z[o, best, 2]
    return (np.int64(np.rint(t[0, 0] * w0 + t[0, 1] * w1 + t[0, 2] * w2)),
            np.int64(np.rint(t[1, 0] * w0 + t[1, 1] * w1 + t[1, 2] * w2)),
            np.int64(np.rint(t[2, 0] * w0 + t[2, 1] * w1 + t[2, 2] * w2)))


@njit_cached(nogil=True)
def quantize_generic3(x, b, binv, cand, cand_z, counts, t, out):  # pragma: no cover - compiled
    """:func:`quantize_generic` unrolled for d = 3 (the hot case: MCC, user lattices)."""
    cn = candidate_norms3(cand)
    for i in range(x.shape[0]):
        out[i, 0], out[i, 1], out[i, 2] = closest_point3(x[i, 0], x[i, 1], x[i, 2], b, binv,
                                                         cand, cand_z, counts, t, cn)
