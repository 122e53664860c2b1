"""Any-angle parts of the search kernel (numba): Theta* and Lazy Theta*.

Theta* (``anyangle`` 1) checks line of sight from the expanded node's parent to each
neighbour when it is generated and links the neighbour to that parent when it can see it
(skipped when neither that parent nor the lattice move would improve the neighbour's g).
Lazy Theta* (``anyangle`` 2) assumes the sight line and verifies it once, when the node is
expanded (in the kernel), falling back to its best closed lattice neighbour
(:func:`lazy_fallback`).
Both use the Euclidean heuristic and the exact walk of :mod:`planner.search._los`. The
parent rules are written out in the kernel (:func:`planner.search._astar.search_run`):
helpers taking the structs were not inlined there and cost more than an A* expansion.
"""

from __future__ import annotations

import numpy as np

from planner._jit import njit_cached
from planner.search._nodes import find_slot
from planner.search.stencils import move_allowed

THETA, LAZY_THETA = 1, 2


@njit_cached(inline="always")
def euclid(g, p0, p1, p2, q0, q1, q2):  # pragma: no cover - compiled
    """|G (q - p)| (m) for cells p and q."""
    d0, d1, d2 = q0 - p0, q1 - p1, q2 - p2
    x = g[0, 0] * d0 + g[0, 1] * d1 + g[0, 2] * d2
    y = g[1, 0] * d0 + g[1, 1] * d1 + g[1, 2] * d2
    z = g[2, 0] * d0 + g[2, 1] * d1 + g[2, 2] * d2
    return np.sqrt(x * x + y * y + z * z)


@njit_cached
def lazy_fallback(ms, nodes, slots, ufree, s, u0, u1, u2):  # pragma: no cover - compiled
    """Lazy Theta* SetVertex when slot ``s`` at cell u does not see its assumed parent:
    take the best closed neighbour that an allowed move reaches (one exists: the node that
    generated s). ``ufree`` holds the union stencil lookups of u."""
    par = nodes.par
    moves, mcost, mptr, midx = ms.moves, ms.cost, ms.ptr, ms.idx
    best = np.inf
    bp = -1
    for m in range(moves.shape[0]):
        if not move_allowed(ufree, mptr, midx, m):
            continue
        t = find_slot(slots, u0 + moves[m, 0], u1 + moves[m, 1], u2 + moves[m, 2])
        if t == -1 or nodes.pos[t] != -1:
            continue
        v = nodes.g[t] + mcost[m]
        if v < best:
            best = v
            bp = t
    par[s] = bp
    nodes.g[s] = best
