"""Indexed binary min-heap kernels (numba) for every engine: push, pop, decrease-key, key
change and removal.

The heap holds node slots; ``pos[slot]`` is the slot's index in the heap (the caller marks
closed / unseen slots with negative values, the heap only writes positions of entries it
holds). Each entry keeps its key ``f`` and tie-breaker ``g`` beside the slot
(:class:`Heap`): sifting then compares contiguous memory instead of chasing slots into the
node table (a cache miss per level).

Order: lower ``f`` first; among equal ``f`` the larger ``g`` first (deeper nodes: fewer
expansions on the many equal-cost paths of a lattice). Entries equal in both come out in an
unspecified order. A* keys its entries (f, g); D* Lite (k1, tie-break) with the same rule
(:mod:`planner.search.dstar.kernel`).

All functions are ``inline="always"`` (numba copies their bodies into each caller): as
calls, the dense A* loop ran about 4% slower on long queries
(``benchmarks/search_speed.py``), while inlining them adds little to the compile. Inside,
heap indices are unsigned: numba then adds no negative-index fix-up to each load and store
(the sifts run markedly faster).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from planner._numba import njit_cached

_U0, _U1 = np.uint64(0), np.uint64(1)

__all__ = ["Heap", "new_heap", "push", "pop", "decrease_key", "change_key", "remove",
           "sift_up", "sift_down"]


class Heap(NamedTuple):
    """Heap storage, capacity ``len(slot)``; the entry count lives with the caller."""

    slot: np.ndarray  # (cap,) int64 node slots
    f: np.ndarray  # (cap,) float64 key of each entry
    g: np.ndarray  # (cap,) float64 tie-breaker of each entry (larger first)


def new_heap(cap: int) -> Heap:
    """Empty heap storage for ``cap`` entries (C-contiguous, writable)."""
    return Heap(np.empty(cap, np.int64), np.empty(cap, np.float64), np.empty(cap, np.float64))


@njit_cached(inline="always")
def _put(h, pos, i, x, xf, xg):  # pragma: no cover - compiled
    h.slot[i] = x
    h.f[i] = xf
    h.g[i] = xg
    pos[np.uint64(x)] = i


@njit_cached(inline="always")
def _before(af, ag, bf, bg):  # pragma: no cover - compiled
    return af < bf or (af == bf and ag > bg)


@njit_cached(inline="always")
def sift_up(h, pos, i0):  # pragma: no cover - compiled
    """Move entry ``i0`` up to its place (after a push or a key decrease)."""
    slot, hf, hg = h.slot, h.f, h.g
    i = np.uint64(i0)
    x, xf, xg = slot[i], hf[i], hg[i]
    while i > _U0:
        parent = (i - _U1) >> _U1
        if not _before(xf, xg, hf[parent], hg[parent]):
            break
        _put(h, pos, i, slot[parent], hf[parent], hg[parent])
        i = parent
    _put(h, pos, i, x, xf, xg)


@njit_cached(inline="always")
def sift_down(h, pos, i0, n0):  # pragma: no cover - compiled
    """Move entry ``i0`` of a heap of ``n0`` entries down to its place."""
    slot, hf, hg = h.slot, h.f, h.g
    i = np.uint64(i0)
    n = np.uint64(n0)
    x, xf, xg = slot[i], hf[i], hg[i]
    while True:
        c = i + i + _U1
        if c >= n:
            break
        d = c + _U1
        if d < n and _before(hf[d], hg[d], hf[c], hg[c]):
            c = d
        if not _before(hf[c], hg[c], xf, xg):
            break
        _put(h, pos, i, slot[c], hf[c], hg[c])
        i = c
    _put(h, pos, i, x, xf, xg)


@njit_cached(inline="always")
def push(h, pos, n, x, xf, xg):  # pragma: no cover - compiled
    """Add slot ``x`` with key ``xf`` / tie-breaker ``xg`` to a heap of ``n``; returns n + 1."""
    _put(h, pos, np.uint64(n), x, xf, xg)
    sift_up(h, pos, n)
    return n + 1


@njit_cached(inline="always")
def pop(h, pos, n):  # pragma: no cover - compiled
    """Remove the first entry of a heap of ``n`` > 0; returns ``(slot, n - 1)``. The popped
    slot's ``pos`` is left for the caller to mark (closed)."""
    s = h.slot[0]
    n -= 1
    if n > 0:
        u = np.uint64(n)
        _put(h, pos, _U0, h.slot[u], h.f[u], h.g[u])
        sift_down(h, pos, _U0, n)
    return s, n


@njit_cached(inline="always")
def decrease_key(h, pos, x, xf, xg):  # pragma: no cover - compiled
    """Lower the key of slot ``x`` (in the heap) to ``xf`` with tie-breaker ``xg``."""
    i = np.uint64(pos[np.uint64(x)])
    h.f[i] = xf
    h.g[i] = xg
    sift_up(h, pos, i)


@njit_cached(inline="always")
def change_key(h, pos, n, x, xf, xg):  # pragma: no cover - compiled
    """Set the key of slot ``x`` (in a heap of ``n``) to ``xf`` / ``xg``, up or down."""
    i = np.uint64(pos[np.uint64(x)])
    h.f[i] = xf
    h.g[i] = xg
    sift_up(h, pos, i)
    sift_down(h, pos, pos[np.uint64(x)], n)


@njit_cached(inline="always")
def remove(h, pos, n, x):  # pragma: no cover - compiled
    """Take slot ``x`` out of a heap of ``n``; returns n - 1 and sets ``pos[x] = -1``."""
    i = pos[x]
    pos[x] = -1
    n -= 1
    if i < n:
        y = h.slot[n]
        _put(h, pos, i, y, h.f[n], h.g[n])
        sift_up(h, pos, i)
        sift_down(h, pos, pos[y], n)
    return n
