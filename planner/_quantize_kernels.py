"""Compiled closest-lattice-point kernels (numba), one pass over the points, no temporaries.

Specialised kernels follow Conway and Sloane, "Fast quantizing and decoding algorithms
for lattice quantizers and codes" (1982): Z^n by rounding, D3 (FCC) by rounding with a
parity fix, D3* (BCC) and A2 (hexagonal) as unions of two shifted rectangular lattices.
Each computes the world lattice point, then the indices ``round(G^-1 p)`` (exact since
``p`` is a lattice point). The generic kernel rounds in a reduced basis and tests a
precomputed, provably sufficient candidate set.
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True, nogil=True)
def quantize_cubic(x, inv_s, out):  # pragma: no cover - compiled
    n, d = x.shape
    for i in range(n):
        for j in range(d):
            out[i, j] = np.int64(np.rint(x[i, j] * inv_s))


@njit(cache=True, nogil=True)
def _indices3(p0, p1, p2, ginv, out, i):  # pragma: no cover - compiled
    for j in range(3):
        out[i, j] = np.int64(np.rint(ginv[j, 0] * p0 + ginv[j, 1] * p1 + ginv[j, 2] * p2))


@njit(cache=True, nogil=True)
def quantize_fcc(x, b, ginv, out):  # pragma: no cover - compiled
    """FCC = b * D3 (integer vectors with even coordinate sum)."""
    inv_b = 1.0 / b
    for i in range(x.shape[0]):
        u0 = x[i, 0] * inv_b
        u1 = x[i, 1] * inv_b
        u2 = x[i, 2] * inv_b
        f0 = np.rint(u0)
        f1 = np.rint(u1)
        f2 = np.rint(u2)
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


@njit(cache=True, nogil=True)
def quantize_bcc(x, a, ginv, out):  # pragma: no cover - compiled
    """BCC = a * (Z3 u (Z3 + 1/2)): the nearer of the two roundings."""
    inv_a = 1.0 / a
    for i in range(x.shape[0]):
        u0 = x[i, 0] * inv_a
        u1 = x[i, 1] * inv_a
        u2 = x[i, 2] * inv_a
        p0 = np.rint(u0)
        p1 = np.rint(u1)
        p2 = np.rint(u2)
        q0 = np.rint(u0 - 0.5) + 0.5
        q1 = np.rint(u1 - 0.5) + 0.5
        q2 = np.rint(u2 - 0.5) + 0.5
        dp = (u0 - p0) ** 2 + (u1 - p1) ** 2 + (u2 - p2) ** 2
        dq = (u0 - q0) ** 2 + (u1 - q1) ** 2 + (u2 - q2) ** 2
        if dq < dp:
            p0, p1, p2 = q0, q1, q2
        _indices3(p0 * a, p1 * a, p2 * a, ginv, out, i)


@njit(cache=True, nogil=True)
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


@njit(cache=True, nogil=True)
def quantize_generic(x, b, binv, cand, cand_z, t, out):  # pragma: no cover - compiled
    """Round in reduced basis b, then pick the nearest of the candidate offsets.

    cand: (k, d) world offsets B @ delta, cand_z: (k, d) the deltas, t: reduction
    (indices in the user's generator are t @ z).
    """
    n, d = x.shape
    k = cand.shape[0]
    z = np.empty(d, dtype=np.float64)
    r = np.empty(d, dtype=np.float64)
    cn = np.empty(k, dtype=np.float64)
    for j in range(k):
        s = 0.0
        for m in range(d):
            s += cand[j, m] * cand[j, m]
        cn[j] = s
    for i in range(n):
        for m in range(d):
            s = 0.0
            for c in range(d):
                s += binv[m, c] * x[i, c]
            z[m] = np.rint(s)
        for m in range(d):
            s = x[i, m]
            for c in range(d):
                s -= b[m, c] * z[c]
            r[m] = s
        # |r - c|^2 = |r|^2 - 2 r.c + |c|^2: minimise the last two terms.
        best = 0
        best_v = np.inf
        for j in range(k):
            s = cn[j]
            for m in range(d):
                s -= 2.0 * r[m] * cand[j, m]
            if s < best_v:
                best_v = s
                best = j
        for m in range(d):
            acc = 0.0
            for c in range(d):
                acc += t[m, c] * (z[c] + cand_z[best, c])
            out[i, m] = np.int64(np.rint(acc))
