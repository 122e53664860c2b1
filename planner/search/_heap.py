"""Indexed 4-ary min-heap kernels (numba) for every engine: push, pop, decrease-key, key
change and removal.

The heap holds node slots; ``pos[slot]`` is the slot's index in the heap (the caller marks
closed / unseen slots with negative values, the heap only writes positions of entries it
holds). Each entry keeps its key ``f`` and tie-breaker ``g`` beside the slot
(:class:`Heap`): sifting then compares contiguous memory instead of chasing slots into the
node table (a cache miss per level). Four children per entry: half the levels of a binary
heap, and the four keys a sift-down compares sit side by side (``benchmarks/cpp_anchor.py
--variants`` measures the same choice on the compiled floor), in one cache line: the arrays
are placed so that item 1 starts a line (:func:`new_heap`, :func:`grown_heap`).

Order: lower ``f`` first; among equal ``f`` the larger ``g`` first (deeper nodes: fewer
expansions on the many equal-cost paths of a lattice). Entries equal in both come out in an
unspecified order. A* keys its entries (f, g); D* Lite (k1, tie-break) with the same rule
(:mod:`planner.search.dstar.kernel`).

The A* loops queue through the ``pq_*`` functions: the same storage, split in two. Entries
whose f equals the f of the current plateau (``fcur``: the f popped last while the plateau
was empty) go to a side heap ordered by g alone, kept at the top end of the arrays (side
entry ``i`` at index ``cap - 1 - i``, ``pos = SIDE - i``); all others to the main heap at
the bottom end. On a lattice most generated nodes lie on the plateau (a move towards the
goal keeps f), so most pushes and pops run in a small heap and compare one float,
instead of sifting through the whole open list. A pop compares the two tops by (f, g) as
above, so the order is the one heap's order for any keys, consistent or not; only entries
equal in both f and g may come out in another order. ``fcur`` changes only when the side
heap is empty, so every side entry always has f == fcur.

All functions are ``inline="always"`` (numba copies their bodies into each caller): as
calls, the search loop's dense A* variant ran about 4% slower on long queries
(``benchmarks/search_speed.py``), while inlining them adds little to the compile. Inside,
heap indices are unsigned: numba then adds no negative-index fix-up to each load and store
(the sifts run markedly faster).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from planner._numba import njit_cached, prefetch

_U0, _U1, _U2, _U3, _U4, _U8 = (np.uint64(0), np.uint64(1), np.uint64(2), np.uint64(3),
                               np.uint64(4), np.uint64(8))

__all__ = ["Heap", "fkey", "new_heap", "grown_heap", "push", "pop", "decrease_key",
           "change_key", "remove", "sift_up", "sift_down", "SIDE", "side_index", "pq_push",
           "pq_pop", "pq_decrease", "pq_flush"]


class Heap(NamedTuple):
    """Heap storage, capacity ``len(slot)``; the entry count lives with the caller."""

    slot: np.ndarray  # (cap,) int64 node slots
    f: np.ndarray  # (cap,) float64 key of each entry
    g: np.ndarray  # (cap,) float64 tie-breaker of each entry (larger first)


def new_heap(cap: int) -> Heap:
    """Empty heap storage for ``cap`` entries (C-contiguous, writable; :func:`_lined`)."""
    return Heap(_lined(cap, np.int64), _lined(cap, np.float64), _lined(cap, np.float64))


def grown_heap(h: Heap, cap: int, keep: int) -> Heap:
    """Heap storage for ``cap`` entries holding the first ``keep`` entries of ``h``."""
    out = new_heap(cap)
    for a, b in zip(out, h, strict=True):
        a[:keep] = b[:keep]
    return out


_LINE = 64  # bytes per cache line
#: entries above which a sift-down prefetches and picks the best child by branches, not selects
#: (24 bytes an entry: past the first-level caches, about where the loads dominate)
_BIG = np.uint64(1 << 14)


def _lined(cap: int, dtype) -> np.ndarray:
    """``np.empty(cap, dtype)`` (8-byte items) whose item 1 starts a cache line: the four
    children ``4 i + 1 .. 4 i + 4`` of every entry then share one line of each array, so
    a sift-down level reads one line of keys instead of two half the time."""
    item = np.dtype(dtype).itemsize
    buf = np.empty(cap * item + _LINE, np.uint8)
    start = (-(buf.ctypes.data + item)) % _LINE
    return buf[start:start + cap * item].view(dtype)



@njit_cached(_nrt=False)
def fkey(x, f0, fq, fq_inv):  # pragma: no cover - compiled
    """``x`` (an f value, m) on the A* loops' f grid of step ``fq`` through ``f0`` (m;
    ``fq_inv`` the step's inverse; :data:`planner.search.astar.loop.F_STEP`): equal-cost
    paths tie exactly (float noise would otherwise decide), so the larger-g tie-break can
    dive; the node table keeps the exact costs."""
    return f0 + np.floor((x - f0) * fq_inv + 0.5) * fq

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
        parent = (i - _U1) >> _U2
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
        c0 = (i << _U2) + _U1
        if c0 >= n:
            break
        c, cf, cg = c0, hf[c0], hg[c0]
        end = min(c0 + _U4, n)
        if n > _BIG:
            # a big heap (a long search), whose lower levels come from memory: the
            # grandchildren of all four children are the 16 entries from 4 c0 + 1, two
            # cache lines of keys and two of tie-breakers (see _lined), fetched while this
            # level compares, so that it waits on one miss per level, not two; and
            # branches, so that the next level's loads need not wait for the last select
            # (a mispredicted branch costs less than that wait). A small heap sits in the
            # cache, where the prefetches would only add work.
            g0 = (c0 << _U2) + _U1
            if g0 < n:
                prefetch(hf, g0)
                prefetch(hf, g0 + _U8)
                prefetch(hg, g0)
                prefetch(hg, g0 + _U8)
            for d in range(c0 + _U1, end):
                df = hf[d]
                if df < cf or (df == cf and hg[d] > cg):
                    c, cf, cg = d, df, hg[d]
        elif end == c0 + _U4:
            # four children (all but one family of the heap): the best without branches
            # (non-short-circuit & and |; which child wins is a coin toss, and a
            # mispredicted branch costs more than the loads: one cache line of
            # tie-breakers, see _lined), as a tournament: the two pairs at once, then
            # their winners, two compares deep instead of three; each winner an index
            # (compare results added), its keys loaded again from the line just read, as
            # the floor does it (float selects compiled to branches). The earlier child
            # wins a tie, as in the scan below.
            f1, g1 = hf[c0 + _U1], hg[c0 + _U1]
            f2, g2 = hf[c0 + _U2], hg[c0 + _U2]
            f3, g3 = hf[c0 + _U3], hg[c0 + _U3]
            ca = c0 + np.uint64((f1 < cf) | ((f1 == cf) & (g1 > cg)))
            cb = c0 + _U2 + np.uint64((f3 < f2) | ((f3 == f2) & (g3 > g2)))
            fa, ga, fb, gb = hf[ca], hg[ca], hf[cb], hg[cb]
            c = ca + (cb - ca) * np.uint64((fb < fa) | ((fb == fa) & (gb > ga)))
            cf, cg = hf[c], hg[c]
        else:
            for d in range(c0 + _U1, end):
                df, dg = hf[d], hg[d]
                b = (df < cf) | ((df == cf) & (dg > cg))
                c = d if b else c
                cf = df if b else cf
                cg = dg if b else cg
        if not _before(cf, cg, xf, xg):
            break
        _put(h, pos, i, slot[c], cf, cg)
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


#: ``pos`` of side entry 0 (``SIDE - i`` for entry i); below the callers' own marks
#: (-1 closed, -2 generated but not queued)
SIDE = -3


@njit_cached(inline="always")
def side_index(p):  # pragma: no cover - compiled
    """Side heap index of an entry whose ``pos`` is ``p`` (<= SIDE)."""
    return SIDE - p


@njit_cached(inline="always")
def _sput(h, pos, top, i, x, xg):  # pragma: no cover - compiled
    a = np.uint64(top - i)
    h.slot[a] = x
    h.g[a] = xg
    pos[np.uint64(x)] = SIDE - i


@njit_cached(inline="always")
def _side_up(h, pos, i, x, xg):  # pragma: no cover - compiled
    """Place slot ``x`` (g ``xg``) at side index ``i`` or above (larger g first)."""
    slot, hg = h.slot, h.g
    top = slot.shape[0] - 1
    while i > 0:
        p = (i - 1) >> 1
        a = np.uint64(top - p)
        if hg[a] >= xg:
            break
        _sput(h, pos, top, i, slot[a], hg[a])
        i = p
    _sput(h, pos, top, i, x, xg)


@njit_cached(inline="always")
def _side_down(h, pos, i, sn, x, xg):  # pragma: no cover - compiled
    """Place slot ``x`` (g ``xg``) at side index ``i`` or below in a side heap of ``sn``."""
    slot, hg = h.slot, h.g
    top = slot.shape[0] - 1
    while True:
        c = i + i + 1
        if c >= sn:
            break
        if c + 1 < sn and hg[np.uint64(top - c - 1)] > hg[np.uint64(top - c)]:
            c += 1
        a = np.uint64(top - c)
        if hg[a] <= xg:
            break
        _sput(h, pos, top, i, slot[a], hg[a])
        i = c
    _sput(h, pos, top, i, x, xg)


@njit_cached(inline="always")
def _side_take(h, pos, sn, i):  # pragma: no cover - compiled
    """Remove side entry ``i`` from a side heap of ``sn``; returns sn - 1."""
    sn -= 1
    if i < sn:
        a = np.uint64(h.slot.shape[0] - 1 - sn)
        x, xg = h.slot[a], h.g[a]
        _side_up(h, pos, i, x, xg)
        _side_down(h, pos, side_index(pos[np.uint64(x)]), sn, x, xg)
    return sn


@njit_cached(inline="always")
def pq_push(h, pos, hn, sn, fcur, x, xf, xg):  # pragma: no cover - compiled
    """Queue slot ``x`` with key ``xf`` / tie-breaker ``xg``; returns ``(hn, sn)``, the main
    and side heap sizes. The two together hold at most ``len(h.slot)`` entries."""
    if xf == fcur:
        _side_up(h, pos, sn, x, xg)
        return hn, sn + 1
    return push(h, pos, hn, x, xf, xg), sn


@njit_cached(inline="always")
def pq_pop(h, pos, hn, sn, fcur):  # pragma: no cover - compiled
    """Take the first entry (``hn + sn > 0``); returns ``(slot, g, hn, sn, fcur)`` with the
    entry's tie-breaker ``g`` (A* keys its entries by g: the node's g without a load from
    the node table). The popped slot's ``pos`` is left for the caller to mark (closed)."""
    top = np.uint64(h.slot.shape[0] - 1)
    if sn > 0 and (hn == 0 or not _before(h.f[0], h.g[0], fcur, h.g[top])):
        s, sg = h.slot[top], h.g[top]
        sn -= 1
        if sn > 0:
            a = np.uint64(h.slot.shape[0] - 1 - sn)
            _side_down(h, pos, 0, sn, h.slot[a], h.g[a])
        return s, sg, hn, sn, fcur
    if sn == 0:
        fcur = h.f[0]
    sg = h.g[0]
    s, hn = pop(h, pos, hn)
    return s, sg, hn, sn, fcur


@njit_cached(inline="always")
def pq_decrease(h, pos, hn, sn, fcur, x, xf, xg):  # pragma: no cover - compiled
    """Lower the g of queued slot ``x`` to ``xg`` and its f to ``xf`` (<= its f); returns
    ``(hn, sn)``."""
    p = pos[np.uint64(x)]
    if p >= 0:
        if xf != fcur:
            i = np.uint64(p)
            if xf < h.f[i]:
                decrease_key(h, pos, x, xf, xg)
            else:  # f kept (the 1e-9 grid), smaller g: later among its equals
                h.g[i] = xg
                sift_down(h, pos, i, hn)
            return hn, sn
        hn = _take(h, pos, hn, p)
        _side_up(h, pos, sn, x, xg)
        return hn, sn + 1
    i = side_index(p)
    if xf == fcur:  # stays on the plateau: a smaller g moves it down
        _side_down(h, pos, i, sn, x, xg)
        return hn, sn
    sn = _side_take(h, pos, sn, i)  # below the plateau (inconsistent keys only)
    return push(h, pos, hn, x, xf, xg), sn


@njit_cached(inline="always")
def pq_flush(h, pos, hn, sn, fcur):  # pragma: no cover - compiled
    """Move every side entry into the main heap (before the storage is copied or the
    search pauses); returns the main heap's new size."""
    top = h.slot.shape[0] - 1
    # deepest first: the main heap then grows into cells already read
    for i in range(sn - 1, -1, -1):
        a = np.uint64(top - i)
        hn = push(h, pos, hn, h.slot[a], fcur, h.g[a])
    return hn


@njit_cached(inline="always")
def _take(h, pos, n, i0):  # pragma: no cover - compiled
    """Remove the entry at index ``i0`` of a heap of ``n``; returns n - 1 (the removed
    slot's ``pos`` is left for the caller)."""
    i = np.uint64(i0)
    n -= 1
    u = np.uint64(n)
    if i < u:
        y = h.slot[u]
        _put(h, pos, i, y, h.f[u], h.g[u])
        sift_up(h, pos, i)
        sift_down(h, pos, pos[np.uint64(y)], n)
    return n
