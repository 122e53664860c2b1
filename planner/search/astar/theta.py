"""Any-angle parts of the search kernel (numba): Theta* and Lazy Theta*.

Theta* (``anyangle`` 1) checks line of sight from the expanded node's parent to each
neighbour when it is generated and links the neighbour to that parent when it can see it
(skipped when neither that parent nor the lattice move would improve the neighbour's g).
Lazy Theta* (``anyangle`` 2) assumes the sight line and verifies it once, when the node is
expanded, falling back to its best closed lattice neighbour (SetVertex).
Both use the Euclidean heuristic and the exact walk of :mod:`planner.search._los`. The
parent rules are written out in the kernel (:func:`planner.search.astar.kernel.search_run`):
helpers taking the structs were not inlined there and cost more than an A* expansion.
"""

from __future__ import annotations

import numpy as np

from planner._numba import njit_cached

THETA, LAZY_THETA = 1, 2


@njit_cached(inline="always")
def euclid(g, p0, p1, p2, q0, q1, q2):  # pragma: no cover - compiled
    """|G (q - p)| (m) for cells p and q."""
    d0, d1, d2 = q0 - p0, q1 - p1, q2 - p2
    x = g[0, 0] * d0 + g[0, 1] * d1 + g[0, 2] * d2
    y = g[1, 0] * d0 + g[1, 1] * d1 + g[1, 2] * d2
    z = g[2, 0] * d0 + g[2, 1] * d1 + g[2, 2] * d2
    return np.sqrt(x * x + y * y + z * z)
