"""The search heuristic, once for every engine: numba kernels and their numpy forms side by side.

Every engine (A*, Theta*, Lazy Theta*, D* Lite and the networkx reference) estimates the cost
between two cells from their index difference ``e = b - a`` ((3,) int) alone:

- ``H_GAUGE`` (A*, D* Lite): the move-set gauge ``max(0, max_f hmat[f] . e)`` (m), the exact
  obstacle-free path length with the lattice moves (:mod:`planner.search.moves`). On the
  cubic lattice with 26 neighbours it equals the octile distance, evaluated in closed form
  (:func:`octile`) when ``MoveSet.octile`` holds the cell size. A lattice move set is
  symmetric, so its facets come in antipodal pairs and the search loop takes the same
  value to the bit over one facet of each pair (:func:`half_facets`, :func:`half_gauge`).
- ``H_EUCLID`` (any-angle): the straight-line distance ``|G e|`` (m), ``G`` the lattice
  generator (3, 3) (:func:`length`, also the any-angle loops' step cost).
- ``H_ZERO`` (Dijkstra): 0.

The numba functions are compiled without reference counting (``_nrt=False``): the A*
kernel calls them once per generated node, and counting the array arguments' references
there would cost more than the estimate. The loops' forms (:func:`rows`, :func:`length`,
:func:`node_estimate`) are inlined into them (``inline="always"``): they take ``G`` as the
nine floats a loop reads once per search, where a call reading the array each time would
re-load it after every store to the node table (which numba cannot prove does not alias).
The numpy forms take (..., 3) arrays of index differences and serve the Python side (D* Lite's
key offset ``km``, the networkx reference); ``tests/test_search.py`` checks the two agree.
"""

from __future__ import annotations

import numpy as np

from planner._numba import njit_cached

__all__ = ["H_ZERO", "H_GAUGE", "H_EUCLID", "octile", "gauge", "half_facets", "half_gauge",
           "euclid", "estimate", "rows", "length", "node_estimate", "octile_np", "gauge_np",
           "euclid_np", "estimate_np"]

H_ZERO, H_GAUGE, H_EUCLID = 0, 1, 2

_R3M2 = np.sqrt(3.0) - np.sqrt(2.0)
_R2M1 = np.sqrt(2.0) - 1.0


@njit_cached(_nrt=False)
def octile(s, e0, e1, e2):  # pragma: no cover - compiled
    """Octile distance (m) of index difference e on the cubic lattice of cell size s (m):
    sqrt 3 per full diagonal, sqrt 2 per face diagonal, 1 per face step, times s."""
    a, b, c = abs(e0), abs(e1), abs(e2)
    lo = min(a, min(b, c))
    hi = max(a, max(b, c))
    return s * (_R3M2 * lo + _R2M1 * (a + b + c - lo - hi) + hi)


@njit_cached(_nrt=False)
def gauge(hmat, e0, e1, e2):  # pragma: no cover - compiled
    """Move-set gauge (m) of index difference e: ``max(0, max_f hmat[f] . e)``, hmat (F, 3)."""
    hv = 0.0
    for f in range(hmat.shape[0]):
        x = hmat[f, 0] * e0 + hmat[f, 1] * e1 + hmat[f, 2] * e2
        if x > hv:
            hv = x
    return hv


@njit_cached
def half_facets(hmat):  # pragma: no cover - compiled
    """The gauge's facets ``hmat`` (F, 3) halved: ``(half, True)`` with one facet of each
    antipodal pair when every facet's negation is also a facet (a move set closed under
    negation: its gauge is a symmetric norm), so that ``max(0, max_f hmat[f] . e)`` is
    ``max_h |half[h] . e|``, to the bit (a negated facet's sum is the negated sum) over
    half the facets; else ``(hmat, False)``. Made once per move set (the search loop's
    ``DenseTables``)."""
    nfac = hmat.shape[0]
    pair = np.full(nfac, -1, np.int64)
    for k in range(nfac):
        for j in range(nfac):
            if (hmat[j, 0] == -hmat[k, 0] and hmat[j, 1] == -hmat[k, 1]
                    and hmat[j, 2] == -hmat[k, 2]):
                pair[k] = j
                break
        if pair[k] < 0 or pair[k] == k:
            return hmat.copy(), False
    half = np.empty((nfac // 2, 3), np.float64)
    nh = 0
    for k in range(nfac):
        if pair[k] > k:
            half[nh] = hmat[k]
            nh += 1
    return half, True


@njit_cached(_nrt=False, inline="always")
def half_gauge(half, halved, e0, e1, e2):  # pragma: no cover - compiled
    """:func:`gauge` (m) of index difference e from :func:`half_facets`' ``(half, halved)``:
    ``max_h |half[h] . e|`` when ``halved``, else ``max(0, max_h half[h] . e)``; the search
    loop's form, in one pass per new node."""
    hv = 0.0
    for k in range(half.shape[0]):
        x = half[k, 0] * e0 + half[k, 1] * e1 + half[k, 2] * e2
        if halved:
            x = abs(x)
        hv = max(hv, x)
    return hv


@njit_cached(_nrt=False, inline="always")
def rows(g):  # pragma: no cover - compiled
    """The (3, 3) generator ``g``'s nine entries, row by row (a tuple of floats, read once
    per search by the loops; module docstring)."""
    return (g[0, 0], g[0, 1], g[0, 2], g[1, 0], g[1, 1], g[1, 2], g[2, 0], g[2, 1], g[2, 2])


@njit_cached(_nrt=False, inline="always")
def length(gm, e0, e1, e2):  # pragma: no cover - compiled
    """Straight-line length |G e| (m) of index difference e, ``gm`` = :func:`rows` of G:
    the one home of the formula (the Euclidean heuristic, any-angle g)."""
    x = gm[0] * e0 + gm[1] * e1 + gm[2] * e2
    y = gm[3] * e0 + gm[4] * e1 + gm[5] * e2
    z = gm[6] * e0 + gm[7] * e1 + gm[8] * e2
    return np.sqrt(x * x + y * y + z * z)


@njit_cached(_nrt=False)
def euclid(g, e0, e1, e2):  # pragma: no cover - compiled
    """Straight-line length |G e| (m) of index difference e, g the (3, 3) generator."""
    return length(rows(g), e0, e1, e2)


@njit_cached(_nrt=False, inline="always")
def node_estimate(oct_s, hkind, hmat, hw, gm, e0, e1, e2):  # pragma: no cover - compiled
    """The heuristic (m) of a node at index difference e from the goal, from a move set's
    fields (``octile``, ``hkind``, ``hmat``) and ``gm`` = :func:`rows` of G, as the loops
    read them once per search; ``hw`` weighs the Euclidean one (weighted-theta)."""
    if oct_s > 0.0:
        return octile(oct_s, e0, e1, e2)
    if hkind == H_GAUGE:
        return gauge(hmat, e0, e1, e2)
    if hkind == H_EUCLID:
        return hw * length(gm, e0, e1, e2)
    return 0.0


@njit_cached(_nrt=False)
def estimate(ms, g, e0, e1, e2):  # pragma: no cover - compiled
    """The heuristic of move set ``ms`` (its ``hkind``) for index difference e (m)."""
    return node_estimate(ms.octile, ms.hkind, ms.hmat, 1.0, rows(g), e0, e1, e2)


def octile_np(s: float, e: np.ndarray) -> np.ndarray:
    """:func:`octile` of (..., 3) index differences; returns (...,) float64 (m)."""
    a = np.sort(np.abs(np.asarray(e, np.float64)), axis=-1)
    return s * (_R3M2 * a[..., 0] + _R2M1 * a[..., 1] + a[..., 2])


def gauge_np(hmat: np.ndarray, e: np.ndarray) -> np.ndarray:
    """:func:`gauge` of (..., 3) index differences; returns (...,) float64 (m)."""
    return np.maximum(0.0, (np.asarray(e, np.float64) @ np.asarray(hmat).T).max(axis=-1))


def euclid_np(g: np.ndarray, e: np.ndarray) -> np.ndarray:
    """:func:`euclid` of (..., 3) index differences; returns (...,) float64 (m)."""
    return np.linalg.norm(np.asarray(e, np.float64) @ np.asarray(g).T, axis=-1)


def estimate_np(ms, g: np.ndarray, e: np.ndarray) -> np.ndarray:
    """:func:`estimate` of (..., 3) index differences; returns (...,) float64 (m)."""
    if ms.octile > 0.0:
        return octile_np(ms.octile, e)
    if ms.hkind == H_GAUGE:
        return gauge_np(ms.hmat, e)
    if ms.hkind == H_EUCLID:
        return euclid_np(g, e)
    return np.zeros(np.shape(e)[:-1])
