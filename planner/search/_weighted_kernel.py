"""Weighted Lazy Theta* (numba): the kernel of :mod:`planner.search.weighted`.

Lazy Theta* over lattice cells with the heuristic ``w |x - goal|`` (``w >= 1``). Nodes live
in arrays numbered in creation order; an open-addressing hash set maps a cell's packed key
to its number. The arrays grow inside the kernel (doubling), so one call runs one search.
Moves follow the move set's rule (its cells looked up around each expanded cell); parents
are verified with the exact line of sight of :mod:`planner.search._los`.
"""

from __future__ import annotations

import numpy as np

from planner._numba import njit_cached
from planner.occupancy.grid import cell_free
from planner.occupancy.keys import mix64, pack3, unpack3
from planner.search import _heap
from planner.search._los import cubic_walk, is_cubic, los
from planner.search.moves import MAX_BITS, move_allowed

__all__ = ["weighted_run", "W_FOUND", "W_EXHAUSTED", "W_BUDGET", "W_LIMIT"]

_NONE = -1  # empty hash entry / cell without a node
W_EXHAUSTED, W_FOUND, W_LIMIT, W_BUDGET = 0, 1, 2, 4  # the RUN_* codes of search.result


@njit_cached(inline="always")
def _dist(g, e0, e1, e2):  # pragma: no cover - compiled
    """Length (m) of the index offset ``e``."""
    x = g[0, 0] * e0 + g[0, 1] * e1 + g[0, 2] * e2
    y = g[1, 0] * e0 + g[1, 1] * e1 + g[1, 2] * e2
    z = g[2, 0] * e0 + g[2, 1] * e1 + g[2, 2] * e2
    return np.sqrt(x * x + y * y + z * z)


@njit_cached(inline="always")
def _sight(occ, walk, sc, gen, cubic, p0, p1, p2, q0, q1, q2):  # pragma: no cover
    """``(free, lookups)`` of the sight line between cells p and q, walked from p."""
    if cubic:
        return cubic_walk(occ, p0, p1, p2, q0, q1, q2)
    sc.p[0] = p0
    sc.p[1] = p1
    sc.p[2] = p2
    sc.q[0] = q0
    sc.q[1] = q1
    sc.q[2] = q2
    return los(occ, walk, sc.p, sc.q, sc, gen)


@njit_cached
def _grown(a, n):  # pragma: no cover - compiled
    b = np.empty(2 * a.shape[0], a.dtype)
    b[:n] = a[:n]
    return b


@njit_cached
def _rehash(key, n, size):  # pragma: no cover - compiled
    """A hash table of ``size`` entries (power of two) holding nodes ``0 .. n - 1``."""
    tkey = np.full(size, _NONE, np.int64)
    tval = np.empty(size, np.int64)
    mask = size - 1
    for i in range(n):
        p = mix64(key[i]) & mask
        while tkey[p] != _NONE:
            p = (p + 1) & mask
        tkey[p] = key[i]
        tval[p] = i
    return tkey, tval


@njit_cached(nogil=True)  # search_many runs searches in threads
def weighted_run(occ, walk, ms, start, goal, weight, sc, cap, max_nodes, max_exp):
    # pragma: no cover - compiled
    """Weighted Lazy Theta* from cell ``start`` to cell ``goal`` ((3,) int64 each).

    Parameters
    ----------
    occ : Occupancy
    walk : Walk
    ms : MoveSet
        Moves and the cells each needs free (its heuristic fields are unused).
    weight : float
        Heuristic weight ``w >= 1`` on the Euclidean distance to the goal (m).
    sc : SightScratch
    cap : int
        Initial node capacity (grows by doubling).
    max_nodes, max_exp : int
        Stop once this many nodes exist / after this many expansions (<= 0: no limit).

    Returns
    -------
    status : int
        ``W_FOUND``, ``W_EXHAUSTED``, ``W_LIMIT`` or ``W_BUDGET``.
    cells : (P, 3) int64
        The parent chain from start to goal (turning cells); empty when not found.
    cost : float
        Its length (m); inf when not found.
    expansions, generated, lookups, peak_bytes : int
    """
    mode, grid, lo, dims, otable, otmask, gg, blo, bhi = occ
    moves, mcost, ust, mptr, midx, _, _, need, _ = ms
    g = walk.g
    cubic = is_cubic(g)
    lo0, lo1, lo2 = lo[0], lo[1], lo[2]
    d0, d1, d2 = dims[0], dims[1], dims[2]
    nu = ust.shape[0]
    nm = moves.shape[0]
    bits = nu <= MAX_BITS
    uoff = np.empty(nu, np.int64)  # stencil cells as flat offsets into a dense grid
    reach = 0
    for j in range(nu):
        uoff[j] = (ust[j, 0] * d1 + ust[j, 1]) * d2 + ust[j, 2]
        reach = max(reach, abs(ust[j, 0]), abs(ust[j, 1]), abs(ust[j, 2]))
    ufree = np.empty(nu, np.bool_)
    cap = max(cap, 2 * nm)
    key = np.empty(cap, np.int64)
    ng = np.empty(cap)
    nh = np.empty(cap)
    npar = np.empty(cap, np.int64)
    npos = np.empty(cap, np.int64)  # -2 open-to-be, -1 closed, >= 0 heap position
    hslot = np.empty(cap, np.int64)
    hf = np.empty(cap)
    hg = np.empty(cap)
    tkey, tval = _rehash(key, 0, 2 * cap)
    tmask = 2 * cap - 1
    gl0, gl1, gl2 = goal[0], goal[1], goal[2]
    gk = pack3(gl0, gl1, gl2)
    fq = 1e-9 * mcost.min()
    fq_inv = 1.0 / fq
    key[0] = pack3(start[0], start[1], start[2])
    p = mix64(key[0]) & tmask
    tkey[p] = key[0]
    tval[p] = 0
    ng[0] = 0.0
    nh[0] = weight * _dist(g, gl0 - start[0], gl1 - start[1], gl2 - start[2])
    npar[0] = 0
    n = 1
    heap = _heap.Heap(hslot, hf, hg)
    hn = _heap.push(heap, npos, 0, 0, nh[0], 0.0)
    expansions = 0
    lookups = 0
    gen = 0
    status = W_EXHAUSTED
    goal_node = -1
    while hn > 0:
        if n + nm > key.shape[0]:  # room for every node this expansion may create
            key = _grown(key, n)
            ng = _grown(ng, n)
            nh = _grown(nh, n)
            npar = _grown(npar, n)
            npos = _grown(npos, n)
            hslot = _grown(hslot, hn)
            hf = _grown(hf, hn)
            hg = _grown(hg, hn)
            heap = _heap.Heap(hslot, hf, hg)
            tkey, tval = _rehash(key, n, 2 * key.shape[0])
            tmask = tkey.shape[0] - 1
        if max_exp > 0 and expansions >= max_exp:
            status = W_BUDGET
            break
        s, hn = _heap.pop(heap, npos, hn)
        npos[s] = -1
        expansions += 1
        u0, u1, u2 = unpack3(key[s])
        a0, b0, c0 = u0 - lo0, u1 - lo1, u2 - lo2
        if (mode == 0 and a0 >= reach and b0 >= reach and c0 >= reach
                and a0 < d0 - reach and b0 < d1 - reach and c0 < d2 - reach):
            base = (a0 * d1 + b0) * d2 + c0  # every stencil cell inside the dense box
            for j in range(nu):
                f = base + uoff[j]
                ufree[j] = (grid[f >> 3] >> (f & 7)) & 1 != 0
        else:
            for j in range(nu):
                ufree[j] = cell_free(mode, grid, lo, dims, otable, otmask, gg, blo, bhi,
                                     u0 + ust[j, 0], u1 + ust[j, 1], u2 + ust[j, 2])
        blocked = np.int64(0)
        if bits:
            for j in range(nu):
                if not ufree[j]:
                    blocked |= np.int64(1) << j
        lookups += nu
        if npar[s] != s:  # verify the assumed sight line, walked from s
            p0, p1, p2 = unpack3(key[npar[s]])
            gen += 1
            ok, c = _sight(occ, walk, sc, gen, cubic, u0, u1, u2, p0, p1, p2)
            lookups += c
            if not ok:  # SetVertex: the best closed neighbour an allowed move reaches
                best = np.inf
                bp = np.int64(-1)
                for m in range(nm):
                    if bits:
                        if need[m] & blocked:
                            continue
                    elif not move_allowed(ufree, mptr, midx, m):
                        continue
                    k = pack3(u0 + moves[m, 0], u1 + moves[m, 1], u2 + moves[m, 2])
                    q = mix64(k) & tmask
                    while tkey[q] != k and tkey[q] != _NONE:
                        q = (q + 1) & tmask
                    if tkey[q] == _NONE:
                        continue
                    t = tval[q]
                    if npos[t] != -1:
                        continue
                    gv = ng[t] + mcost[m]
                    if gv < best:
                        best = gv
                        bp = t
                npar[s] = bp
                ng[s] = best
        if key[s] == gk:
            status = W_FOUND
            goal_node = s
            break
        if max_nodes > 0 and n >= max_nodes:
            status = W_LIMIT
            break
        ps = npar[s]
        p0, p1, p2 = unpack3(key[ps])
        gps = ng[ps]
        for m in range(nm):
            if bits:
                if need[m] & blocked:
                    continue
            elif not move_allowed(ufree, mptr, midx, m):
                continue
            v0 = u0 + moves[m, 0]
            v1 = u1 + moves[m, 1]
            v2 = u2 + moves[m, 2]
            k = pack3(v0, v1, v2)
            q = mix64(k) & tmask
            while tkey[q] != k and tkey[q] != _NONE:
                q = (q + 1) & tmask
            if tkey[q] == _NONE:
                t = n
                n += 1
                tkey[q] = k
                tval[q] = t
                key[t] = k
                ng[t] = np.inf
                nh[t] = weight * _dist(g, gl0 - v0, gl1 - v1, gl2 - v2)
                npos[t] = -2
            else:
                t = tval[q]
                if npos[t] == -1:
                    continue  # closed
            gt = gps + _dist(g, v0 - p0, v1 - p1, v2 - p2)
            if gt < ng[t]:
                ng[t] = gt
                # f on a 1e-9-cell grid: equal-cost paths tie exactly, so the larger-g
                # tie-break decides, not float noise
                ft = np.floor((gt + nh[t]) * fq_inv + 0.5) * fq
                npar[t] = ps
                if npos[t] == -2:
                    hn = _heap.push(heap, npos, hn, t, ft, gt)
                else:
                    _heap.decrease_key(heap, npos, t, ft, gt)
    peak = (7 * 8 + 2 * 16) * key.shape[0]
    if status != W_FOUND:
        return status, np.zeros((0, 3), np.int64), np.inf, expansions, n, lookups, peak
    k = 1
    x = goal_node
    while npar[x] != x:
        x = npar[x]
        k += 1
    cells = np.empty((k, 3), np.int64)
    x = goal_node
    for i in range(k - 1, -1, -1):
        cells[i, 0], cells[i, 1], cells[i, 2] = unpack3(key[x])
        x = npar[x]
    return status, cells, ng[goal_node], expansions, n, lookups, peak
