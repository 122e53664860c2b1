"""Stencil inflation: the Minkowski sum of occupied cells with a stencil of lattice offsets
derived exactly from the Voronoi cell (conservative; what :meth:`OccupiedVoxelList.inflate`
runs), on a dense grid when it fits the memory budget, else on sorted keys.
"""

from __future__ import annotations

import numpy as np

from planner.checks import check_radius
from planner.lattice import Lattice
from planner.occupancy.keys import BITS, check_range, index_limit, unique_keys, unpack
from planner.voxels import kernels as vk
from planner.voxels._checks import (
    DEFAULT_BUDGET,
    REL_TOL,
    cell_diameter,
    grid_strides,
    key_offsets,
    offsets_within,
    over_budget,
    resolve_budget,
)

__all__ = ["inflation_stencil", "stencil_inflation"]


# -- stencil inflation --------------------------------------------------------------------------
def inflation_stencil(lat: Lattice, radius: float, memory_budget: float | None = DEFAULT_BUDGET
                      ) -> np.ndarray:
    """Offsets ``delta`` whose closed Voronoi cell comes closer than ``radius`` to V(0).

    For the point-symmetric convex cell V, ``dist(V, V + G delta) = 2 dist(G delta / 2, V)``
    (``V - V = 2V``); it is computed exactly. Candidates have ``|G delta| < r + 2 R`` (R the
    covering radius). The zero offset is always included.

    Parameters
    ----------
    lat : Lattice
    radius : float
        Metres, >= 0.

    Returns
    -------
    ndarray, shape (n, d), int64
        Zero offset first, then by world length.
    """
    r = check_radius(radius)
    zero = np.zeros((1, lat.dim), dtype=np.int64)
    if r == 0:
        return zero
    cand = offsets_within(lat, r + 2 * lat.covering_radius, memory_budget, r)
    tol = REL_TOL * cell_diameter(lat)
    half = np.ascontiguousarray(cand @ lat.generator.T / 2)
    dist = np.empty(len(cand))
    vk.cell_distances(half, vk.cell_polytope(lat.voronoi), tol, dist)
    # Conservative by tol: a pair at distance exactly r (up to rounding) is blocked.
    sel = cand[(2 * dist < r + tol) & np.any(cand != 0, axis=1)]
    order = np.argsort(np.linalg.norm(sel @ lat.generator.T, axis=1), kind="stable")
    return np.concatenate([zero, sel[order]])

def stencil_inflation(keys: np.ndarray, lat: Lattice, r: float, budget: float | None
                      ) -> np.ndarray:
    """Keys of :meth:`OccupiedVoxelList.inflate`: sorted unique ``keys`` (M,) dilated by
    :func:`inflation_stencil` (``r`` > 0 metres), on a dense grid when it fits ``budget``
    bytes (None: the memory budget), else by key arithmetic in chunks."""
    budget = resolve_budget(budget)
    stencil = inflation_stencil(lat, r, budget)
    full = lat.neighbors("full")
    w = unpack(keys, lat.dim)
    ext = np.maximum(np.abs(stencil).max(axis=0), np.abs(full).max(axis=0))
    lo, hi = w.min(axis=0) - ext, w.max(axis=0) + ext
    check_range(lo, hi, lat.dim)
    # The result holds at least one whole stencil: a cheap lower bound for the budget.
    least = len(stencil) * 8
    dims = hi - lo + 1
    cells = float(np.prod(dims.astype(float)))
    if least > budget:
        raise over_budget(r, least, budget)
    if cells + 8 * len(keys) <= budget:
        return _dilate_dense(keys, lo, dims, stencil, full, budget, r)
    return _dilate_keys(keys, stencil, full, budget, r)


def _dilate_dense(keys: np.ndarray, lo: np.ndarray, dims: np.ndarray, stencil: np.ndarray,
                  full: np.ndarray, budget: float, radius: float) -> np.ndarray:
    """Minkowski sum on a dense uint8 scratch grid over the padded index box."""
    d = len(dims)
    strides = grid_strides(dims)
    grid = np.zeros(int(np.prod(dims)), dtype=np.uint8)
    flat = np.empty(len(keys), dtype=np.int64)
    vk.flat_positions(keys, lo.astype(np.int64), strides, BITS[d], index_limit(d), flat)
    runs = _stencil_runs(stencil)
    if runs is not None and grid.nbytes * 5 + 8 * len(keys) <= budget:  # + int32 diff
        diff = np.zeros(grid.size + 1, dtype=np.int32)
        vk.dilate_rows(grid, flat, full @ strides, runs[0] @ strides, runs[1], diff)
        del diff
    else:
        vk.dilate(grid, flat, stencil @ strides, full @ strides)
    n = int(np.count_nonzero(grid))
    if grid.nbytes + 8 * n > budget:
        raise over_budget(radius, grid.nbytes + 8 * n, budget)
    out = np.empty(n, dtype=np.int64)
    vk.grid_keys(grid, lo.astype(np.int64), dims.astype(np.int64), BITS[d], index_limit(d), out)
    return out


def _stencil_runs(stencil: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    """The stencil (S, d) as runs along its last axis: ``(starts (R, d), lengths (R,))``
    covering exactly the same offsets, or None when a row has a gap (the stencil is the
    lattice points of a convex set, so rows are runs; None only guards rounding)."""
    order = np.lexsort(stencil.T[::-1])
    s = stencil[order]
    new_row = np.ones(len(s), dtype=bool)
    new_row[1:] = (s[1:, :-1] != s[:-1, :-1]).any(axis=1)
    first = np.flatnonzero(new_row)
    lengths = np.diff(np.append(first, len(s)))
    last = s[np.append(first[1:], len(s)) - 1, -1]
    if not np.array_equal(last - s[first, -1] + 1, lengths):
        return None
    return np.ascontiguousarray(s[first]), lengths.astype(np.int64)


def _dilate_keys(keys: np.ndarray, stencil: np.ndarray, full: np.ndarray, budget: float,
                 radius: float) -> np.ndarray:
    """Minkowski sum by key arithmetic in chunks (no scratch grid), for sparse huge boxes."""
    nb = key_offsets(full)
    # Boundary cells: some full neighbour is free (interior cells add nothing, see vk.dilate).
    boundary = np.zeros(len(keys), dtype=bool)
    for o in nb:
        q = keys + o
        pos = np.minimum(np.searchsorted(keys, q), len(keys) - 1)
        boundary |= keys[pos] != q
    src = keys[boundary]
    sk = key_offsets(stencil)
    chunk = max(1, int(budget / 4 / 8 / len(sk)))
    out = keys
    for s in range(0, len(src), chunk):
        part = unique_keys((src[s: s + chunk, None] + sk[None, :]).ravel())
        out = unique_keys(np.concatenate([out, part]))
        if out.nbytes * 2 > budget:
            raise over_budget(radius, out.nbytes * 2, budget)
    return out
