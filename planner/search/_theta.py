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
from planner._world_kernels import mix64
from planner.search._nodes import PAGE, block_key, local
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
    generated s). ``ufree`` holds the union stencil lookups of u.

    The slot lookups are written out over the unpacked slot map: calling ``find_slot``
    with the struct cost ~70 ns of reference counting per move (measured)."""
    par, ng, npos = nodes.par, nodes.g, nodes.pos
    moves, mcost, mptr, midx = ms.moves, ms.cost, ms.ptr, ms.idx
    pages, btab, bkeys, dsl, lo, dims = slots
    dense = dsl.shape[0] > 1
    bmask = btab.shape[0] - 1
    best = np.inf
    bp = -1
    for m in range(moves.shape[0]):
        if not move_allowed(ufree, mptr, midx, m):
            continue
        v0, v1, v2 = u0 + moves[m, 0], u1 + moves[m, 1], u2 + moves[m, 2]
        t = np.int64(-1)
        if dense:
            a, b, c = v0 - lo[0], v1 - lo[1], v2 - lo[2]
            if 0 <= a < dims[0] and 0 <= b < dims[1] and 0 <= c < dims[2]:
                t = np.int64(dsl[(a * dims[1] + b) * dims[2] + c]) - 1
        else:
            bk = block_key(v0, v1, v2)
            q = mix64(bk) & bmask
            while btab[q] != -1:
                if bkeys[btab[q]] == bk:
                    t = np.int64(pages[btab[q] * PAGE + local(v0, v1, v2)])
                    break
                q = (q + 1) & bmask
        if t == -1 or npos[t] != -1:
            continue
        v = ng[t] + mcost[m]
        if v < best:
            best = v
            bp = t
    par[s] = bp
    ng[s] = best
