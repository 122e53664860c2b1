"""Line of sight between cell centres (numba): the exact segment walk of the validity
checker (:mod:`planner._world_kernels`) on reusable scratch, and greedy path shortcutting.

Two cells see each other iff every cell whose closed Voronoi cell the centre-to-centre
segment touches is free (the same test as a motion check of :class:`planner.world.
ValidityChecker`). On the cubic lattice (:func:`cubic_sight`) those cells are enumerated
directly by nested clipping, with no walk search; tests check both give the same cells.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from planner._jit import njit_cached
from planner._world_kernels import _SEG_TOL, occ_free, segment_walk, walk_on, walk_scratch


class SightScratch(NamedTuple):
    """Reusable scratch of the walk (see ``walk_scratch``) plus two cell buffers."""

    vis: np.ndarray  # (S,) int64 visited keys
    vgen: np.ndarray  # (S,) int64 generation stamp per entry
    queue: np.ndarray  # (Q, 3) int64 BFS queue
    p: np.ndarray  # (3,) int64
    q: np.ndarray  # (3,) int64


def new_scratch(span: float, walk) -> SightScratch:
    """Scratch for sight lines up to ``span`` metres (longer ones fall back to fresh
    arrays inside the kernel)."""
    vis, vgen, queue = walk_scratch(span, math.sqrt(2.0 * walk.rhs.min()), len(walk.full))
    return SightScratch(vis, vgen, queue, np.empty(3, np.int64), np.empty(3, np.int64))


@njit_cached(inline="always")
def _clip(u, dk, h, t0, t1):  # pragma: no cover - compiled
    """[t0, t1] cut to the t where |t dk - u| <= h (one axis of a cubic cell)."""
    if dk > 0:
        return max(t0, (u - h) / dk), min(t1, (u + h) / dk)
    if dk < 0:
        return max(t0, (u + h) / dk), min(t1, (u - h) / dk)
    if abs(u) <= h:
        return t0, t1
    return 1.0, 0.0


@njit_cached(inline="always")
def _span(x0, x1, h, dk):  # pragma: no cover - compiled
    """Cells (first, count, step) whose axis interval [c - h, c + h] meets [x0, x1] (either
    order), listed in the segment's direction ``dk``."""
    lo = np.int64(np.ceil(min(x0, x1) - h))
    hi = np.int64(np.floor(max(x0, x1) + h))
    if dk < 0:
        return hi, hi - lo + 1, -1
    return lo, hi - lo + 1, 1


@njit_cached
def cubic_sight(occ, p, q):  # pragma: no cover - compiled
    """:func:`los` on the cubic lattice without the walk's search: the cells whose closed
    cube (widened by the walk's tolerance) meets the centre-to-centre segment, enumerated
    by nested clipping (x cells, then y cells within each x cell's t range, then z), in
    index units with p at the origin. Same cells as the generic walk; each costs a few
    divisions and one lookup. Returns ``(free, lookups)``."""
    h = 0.5 * (1.0 + _SEG_TOL)
    d0 = np.float64(q[0] - p[0])
    d1 = np.float64(q[1] - p[1])
    d2 = np.float64(q[2] - p[2])
    lookups = 0
    i, ni, si = _span(0.0, d0, h, d0)
    for _ in range(ni):
        a0, a1 = _clip(i, d0, h, 0.0, 1.0)
        if a0 <= a1:
            j, nj, sj = _span(a0 * d1, a1 * d1, h, d1)
            for _ in range(nj):
                b0, b1 = _clip(j, d1, h, a0, a1)
                if b0 <= b1:
                    k, nk, sk = _span(b0 * d2, b1 * d2, h, d2)
                    for _ in range(nk):
                        c0, c1 = _clip(k, d2, h, b0, b1)
                        if c0 <= c1:
                            lookups += 1
                            if not occ_free(occ, p[0] + i, p[1] + j, p[2] + k):
                                return False, lookups
                        k += sk
                j += sj
        i += si
    return True, lookups


@njit_cached(inline="always")
def is_cubic(g):  # pragma: no cover - compiled
    """The generator is a multiple of the identity (the cubic lattice)."""
    return (g[0, 1] == 0.0 and g[0, 2] == 0.0 and g[1, 0] == 0.0 and g[1, 2] == 0.0
            and g[2, 0] == 0.0 and g[2, 1] == 0.0 and g[0, 0] == g[1, 1] == g[2, 2])


@njit_cached
def los(occ, walk, p, q, sc, gen):  # pragma: no cover - compiled
    """Line of sight between the centres of cells p and q ((3,) int64 each) on scratch ``sc``
    with a fresh generation ``gen``. Returns ``(free, lookups)``."""
    g = walk.g
    if is_cubic(g):
        return cubic_sight(occ, p, q)
    a = g @ p.astype(np.float64)
    b = g @ q.astype(np.float64)
    _, free, n, ok = walk_on(occ, walk, a, b, p, True, sc.vis, sc.vgen, gen, sc.queue)
    if not ok:  # longer than the scratch was sized for: walk again on fresh arrays
        _, free, n = segment_walk(occ, walk, a, b, p, True)
    return free, n


@njit_cached(inline="always")
def sight(occ, walk, sc, st, wslot, p0, p1, p2, q0, q1, q2):  # pragma: no cover - compiled
    """:func:`los` between cells p and q given by components, inside a search: the
    generation counter lives in ``st[wslot]``."""
    sc.p[0] = p0
    sc.p[1] = p1
    sc.p[2] = p2
    sc.q[0] = q0
    sc.q[1] = q1
    sc.q[2] = q2
    st[wslot] += 1
    return los(occ, walk, sc.p, sc.q, sc, st[wslot])


@njit_cached
def shortcut_kernel(occ, walk, cells, sc):  # pragma: no cover - compiled
    """Greedy shortcutting: from each kept cell go to the farthest later cell still in
    sight (scanning forward, stopping at the first cell out of sight). Consecutive input
    cells that are not in sight of each other (corner-cutting paths) are kept as they are.
    Returns ``(kept indices into cells, lookups)``."""
    n = cells.shape[0]
    keep = np.empty(n, dtype=np.int64)
    nk = 0
    lookups = 0
    gen = 0
    i = 0
    keep[nk] = 0
    nk += 1
    while i < n - 1:
        j = i + 1
        while j + 1 < n:
            gen += 1
            ok, c = los(occ, walk, cells[i], cells[j + 1], sc, gen)
            lookups += c
            if not ok:
                break
            j += 1
        keep[nk] = j
        nk += 1
        i = j
    return keep[:nk].copy(), lookups
