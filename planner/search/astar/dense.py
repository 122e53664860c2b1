"""The lattice A* / Dijkstra loop on a dense occupancy grid (numba): the A* kernel's
(:mod:`planner.search.astar.kernel`) path for its commonest case, written for that case
alone.

It runs when the world is a dense bit grid, the cell -> slot map is dense too (one int32
per grid cell), the move set's union stencil fits a bit mask (``MoveSet.need``) and the
method has no any-angle rule. Per expansion it reads the union stencil once into a mask of
free cells (without bounds tests away from the box faces), tests each move as one AND with
the cells it needs (the stencil read as a few bit windows, one per row of cells along the
grid's fastest axis), finds the target's node and whether it is closed in one load of the
dense slot array (a closed node's entry is negated), and makes
a new node's key by adding the move's key offset (packed keys are linear in the cell
while a cell stays inside the key range). Same expansions, costs, paths and lookups as the
general loop: one stays the reference of the other (``tests/test_search.py``).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from planner._numba import njit_cached
from planner.occupancy.keys import pack3, step3, unpack3
from planner.search import _heap
from planner.search.heuristic import H_GAUGE, octile
from planner.search.result import RUN_BUDGET, RUN_EXHAUSTED, RUN_FOUND, RUN_GROW, RUN_LIMIT

__all__ = ["DenseTables", "dense_astar", "dense_tables", "stencil_mask"]


@njit_cached
def grid_offsets(ust, moves, d1, d2):  # pragma: no cover - compiled
    """Each stencil cell (U, 3) and move (M, 3) as one offset into a C-order grid of dims
    (., d1, d2), and the margin (cells) inside which no stencil cell leaves the box: an
    expansion there looks up its cells without bounds tests or index arithmetic."""
    uoff = np.empty(ust.shape[0], np.int64)
    reach = 0
    for j in range(ust.shape[0]):
        uoff[j] = (ust[j, 0] * d1 + ust[j, 1]) * d2 + ust[j, 2]
        reach = max(reach, abs(ust[j, 0]), abs(ust[j, 1]), abs(ust[j, 2]))
    moff = np.empty(moves.shape[0], np.int64)
    for m in range(moves.shape[0]):
        moff[m] = (moves[m, 0] * d1 + moves[m, 1]) * d2 + moves[m, 2]
    return uoff, moff, reach


@njit_cached(_nrt=False, inline="always")
def stencil_mask(grid, a0, b0, c0, d0, d1, d2, base, reach, ust, uoff, bit):  # pragma: no cover
    """The union stencil around grid cell (a0, b0, c0) read into a mask of its free cells:
    the one home of that read for the A* loops (dense, dense Lazy Theta*, general).

    ``grid`` the bit grid (uint8, C order, dims (d0, d1, d2)), ``base`` the cell's offset
    in it, ``ust`` (U, 3) the stencil, ``uoff`` (U,) and ``reach`` its offsets and margin
    (:func:`grid_offsets`), ``bit`` (U,) each stencil cell's bit in the mask. Inside the
    margin the cells are read without bounds tests; a cell outside the box reads as
    blocked. Returns the mask (int64)."""
    free = np.int64(0)
    if (a0 >= reach and b0 >= reach and c0 >= reach and a0 < d0 - reach
            and b0 < d1 - reach and c0 < d2 - reach):
        for j in range(ust.shape[0]):
            f = base + uoff[j]
            free |= np.int64((grid[np.uint64(f >> 3)] >> (f & 7)) & 1) << bit[j]
    else:
        for j in range(ust.shape[0]):
            a = a0 + ust[j, 0]
            b = b0 + ust[j, 1]
            c = c0 + ust[j, 2]
            if a >= 0 and b >= 0 and c >= 0 and a < d0 and b < d1 and c < d2:
                f = (a * d1 + b) * d2 + c
                free |= np.int64((grid[f >> 3] >> (f & 7)) & 1) << bit[j]
    return free


@njit_cached
def stencil_rows(ust, need, d1, d2):  # pragma: no cover - compiled
    """The union stencil (U, 3) as runs of cells along the grid's fastest axis, read as
    one bit window each instead of one lookup per cell.

    Returns ``(roff, rshift, rmask, ubit, need2, all2, ok)``: per row (R,) its first cell's grid
    offset (int64, C-order grid of dims (., d1, d2)), the bit where its window starts in the
    free mask and the window's mask; per stencil cell (U,) its bit in that mask; each move's
    ``need`` (M,) and the mask of every stencil cell, with the bits renumbered so. A row
    spans at most 9 cells (its window then fits two bytes); ``ok`` False when the rows do
    not fit (more than 63 bits or a longer row): then the bits keep the stencil's order
    and each cell is read alone."""
    nu = ust.shape[0]
    row = np.full(nu, -1, np.int64)
    cmin = np.empty(nu, np.int64)
    span = np.empty(nu, np.int64)
    nr = 0
    for j in range(nu):
        if row[j] >= 0:
            continue
        lo_c = ust[j, 2]
        hi_c = ust[j, 2]
        for i in range(j, nu):
            if ust[i, 0] == ust[j, 0] and ust[i, 1] == ust[j, 1]:
                row[i] = nr
                lo_c = min(lo_c, ust[i, 2])
                hi_c = max(hi_c, ust[i, 2])
        cmin[nr] = lo_c
        span[nr] = hi_c - lo_c + 1
        nr += 1
    roff = np.empty(nr, np.int64)
    rshift = np.empty(nr, np.int64)
    rmask = np.empty(nr, np.int64)
    at = 0
    for r in range(nr):
        rshift[r] = at
        rmask[r] = (np.int64(1) << span[r]) - 1
        at += span[r]
    ubit = np.empty(nu, np.int64)
    all2 = np.int64(0)
    for j in range(nu):
        r = row[j]
        roff[r] = (ust[j, 0] * d1 + ust[j, 1]) * d2 + cmin[r]
        ubit[j] = rshift[r] + ust[j, 2] - cmin[r]
        all2 |= np.int64(1) << ubit[j]
    if at > 63 or span[:nr].max() > 9:  # no windows: the stencil's own bit order
        for j in range(nu):
            ubit[j] = j
        return roff, rshift, rmask, ubit, need.copy(), (np.int64(1) << nu) - 1, False
    need2 = np.zeros(need.shape[0], np.int64)
    for m in range(need.shape[0]):
        for j in range(nu):
            if (need[m] >> j) & 1:
                need2[m] |= np.int64(1) << ubit[j]
    return roff, rshift, rmask, ubit, need2, all2, True


class DenseTables(NamedTuple):
    """What :func:`dense_astar` needs of a move set on a grid of dims (., d1, d2) besides the
    move set itself: made once per move set and grid (:func:`dense_tables`, kept in the
    driver's ``Bound``) instead of on every search, where it cost more than a short search.
    Also the loop's per-search scratch, so that a search allocates nothing but its path."""

    uoff: np.ndarray  # (U,) int64 grid offset of each stencil cell (grid_offsets)
    moff: np.ndarray  # (M,) int64 grid offset of each move
    reach: int  # margin (cells) inside which no stencil cell leaves the box
    roff: np.ndarray  # (R,) int64 stencil rows (stencil_rows)
    rshift: np.ndarray  # (R,) int64
    rmask: np.ndarray  # (R,) int64
    ubit: np.ndarray  # (U,) int64
    need2: np.ndarray  # (M,) int64
    all_u: int  # mask of every stencil cell
    rows: bool  # the rows fit their windows
    mkey: np.ndarray  # (M,) int64 each move as an offset of the packed key
    hmd: float  # largest change of a gauge facet's value along one move (0: no gauge)
    fval: np.ndarray  # (F,) float64 scratch: facet values at the expanded node
    cand: np.ndarray  # (F,) int64 scratch: facets that can hold a new node's maximum


@njit_cached
def dense_tables(ms, dims, used):  # pragma: no cover - compiled
    """:class:`DenseTables` of move set ``ms`` on a grid of dims ``dims`` (3,) int64; empty
    unless ``used`` (the kernel may run :func:`dense_astar` on them)."""
    moves, ust, hmat = ms.moves, ms.union, ms.hmat
    d1, d2 = dims[1], dims[2]
    nm = moves.shape[0]
    nfac = hmat.shape[0]
    if not used:
        e = np.empty(0, np.int64)
        return DenseTables(e, e, 0, e, e, e, e, e, np.int64(0), False, e, 0.0,
                           np.empty(0, np.float64), e)
    uoff, moff, reach = grid_offsets(ust, moves, d1, d2)
    roff, rshift, rmask, ubit, need2, all_u, rows = stencil_rows(ust, ms.need, d1, d2)
    mkey = np.empty(nm, np.int64)
    for m in range(nm):
        mkey[m] = step3(moves[m, 0], moves[m, 1], moves[m, 2])
    # The gauge's facets that can hold a new node's maximum: a move changes each facet's
    # value by at most hmd (see dense_astar).
    gauge = ms.hkind == H_GAUGE and ms.octile <= 0.0
    hmd = 0.0
    for k in range(nfac if gauge else 0):
        for m in range(nm):
            hmd = max(hmd, abs(hmat[k, 0] * moves[m, 0] + hmat[k, 1] * moves[m, 1]
                               + hmat[k, 2] * moves[m, 2]))
    return DenseTables(uoff, moff, reach, roff, rshift, rmask, ubit, need2, all_u, rows, mkey,
                       hmd, np.empty(nfac, np.float64), np.empty(nfac, np.int64))


# Without the runtime's reference counting: the loop allocates nothing, and each heap
# operation it runs would otherwise incref / decref the heap arrays it binds (an
# atomic add each, tens per expansion: about 45% of the loop's time on cubic-26).
@njit_cached(_nrt=False)
def dense_astar(grid, lo, dims, ms, nodes, heap, dsl, st, max_nodes, max_exp, goal, dt):
    # pragma: no cover - compiled
    """Run the search from the kernel's state ``st`` until it ends or needs room.

    Parameters
    ----------
    grid : (ceil(n / 8),) uint8
        The dense occupancy bits (:class:`planner.occupancy.grid.Occupancy`), box ``lo``
        (3,) int64 and ``dims`` (3,) int64.
    ms : MoveSet
        With ``len(ms.union) <= 63``.
    nodes : NodeTable
    heap : planner.search._heap.Heap
    dsl : (prod(dims),) int32
        Dense cell -> node slot + 1 (0: none) over the grid's box; this loop stores
        -(slot + 1) at a node it closes (:func:`planner.search._nodes.finish` clears both).
    st : ``ASTAR_STATE`` record
        The search's counters; the start node is already in place.
    max_nodes, max_expansions : int
        Limits (<= 0: none).
    goal : (3,) int64
    dt : DenseTables
        Of ``ms`` on this grid (:func:`dense_tables`).

    Returns
    -------
    int
        RUN_FOUND, RUN_EXHAUSTED, RUN_LIMIT, RUN_BUDGET or RUN_GROW.
    """
    lo0, lo1, lo2 = lo[0], lo[1], lo[2]
    d0, d1, d2 = dims[0], dims[1], dims[2]
    moves, mcost, ust, hmat = ms.moves, ms.cost, ms.union, ms.hmat
    oct_s = ms.octile
    gauge = ms.hkind == H_GAUGE and oct_s <= 0.0
    nkey, ng, nh, npar, npos = nodes
    nfac = hmat.shape[0]
    nu = ust.shape[0]
    nm = moves.shape[0]
    cap = nkey.shape[0]
    gl0, gl1, gl2 = goal[0], goal[1], goal[2]
    gk = pack3(gl0, gl1, gl2)
    uoff, moff, reach = dt.uoff, dt.moff, dt.reach
    roff, rshift, rmask, ubit, need2, all_u, rows = (dt.roff, dt.rshift, dt.rmask, dt.ubit,
                                                     dt.need2, dt.all_u, dt.rows)
    nr = roff.shape[0]
    last = np.uint64(grid.shape[0] - 1)
    mkey = dt.mkey
    # The gauge's facets that can hold a new node's maximum: a move changes each facet's
    # value by at most hmd, so a facet below the expanded node's best by more than 2 hmd
    # never wins at a neighbour (found once per expansion, at its first new node; the
    # value of a new node is still the full formula, over fewer facets).
    hmd, fval, cand = dt.hmd, dt.fval, dt.cand
    cmin = np.inf
    for m in range(mcost.shape[0]):  # not mcost.min(): it needs the runtime
        cmin = min(cmin, mcost[m])
    fq = 1e-9 * cmin
    fq_inv = 1.0 / fq
    n = st.nodes
    hn = st.queued
    sn = 0  # the side heap of the f plateau (planner.search._heap): empty between runs
    fcur = np.nan
    expansions = st.expansions
    lookups = st.lookups
    status = RUN_EXHAUSTED
    while hn + sn > 0:
        if n + nm > cap:
            status = RUN_GROW
            break
        if max_exp > 0 and expansions >= max_exp:
            status = RUN_BUDGET
            break
        s, hn, sn, fcur = _heap.pq_pop(heap, npos, hn, sn, fcur)
        su = np.uint64(s)  # unsigned node indices: no negative-index fix-up on each access
        npos[su] = -1
        expansions += 1
        ks = nkey[su]
        u0, u1, u2 = unpack3(ks)
        a0, b0, c0 = u0 - lo0, u1 - lo1, u2 - lo2
        base = (a0 * d1 + b0) * d2 + c0
        # closed: the slot map holds -(slot + 1), so a neighbour's one load of it tells
        # closed from open (no load of its heap position)
        dsl[np.uint64(base)] = -(s + 1)
        if rows and (a0 >= reach and b0 >= reach and c0 >= reach and a0 < d0 - reach
                     and b0 < d1 - reach and c0 < d2 - reach):
            # each row of stencil cells along the fastest axis as one window of the
            # bit grid: two byte loads instead of a load per cell
            free = np.int64(0)
            for r in range(nr):
                f = np.uint64(base + roff[r])
                i = f >> np.uint64(3)
                w = np.int64(grid[i]) | (np.int64(grid[min(i + np.uint64(1), last)]) << 8)
                free |= ((w >> np.int64(f & np.uint64(7))) & rmask[r]) << rshift[r]
        else:
            free = stencil_mask(grid, a0, b0, c0, d0, d1, d2, base, reach, ust, uoff, ubit)
        blocked = all_u & ~free
        lookups += nu
        if ks == gk:
            status = RUN_FOUND
            st.goal = s
            break
        if max_nodes > 0 and n >= max_nodes:
            status = RUN_LIMIT
            break
        gs = ng[su]
        e0, e1, e2 = gl0 - u0, gl1 - u1, gl2 - u2
        ncand = -1
        for m in range(nm):
            if need2[m] & blocked:
                continue
            # an allowed move's target is free, hence in the box; unsigned indices spare
            # the negative-index fix-up on these loads
            loc = np.uint64(base + moff[m])
            v = dsl[loc]
            if v < 0:
                continue  # closed: a consistent heuristic never improves it
            gt = gs + mcost[m]
            if v > 0:
                tu = np.uint64(v - 1)
                if gt >= ng[tu]:
                    continue  # no better
                ng[tu] = gt
                f = _heap.fkey(gt + nh[tu], fq, fq_inv)
                npar[tu] = s
                hn, sn = _heap.pq_decrease(heap, npos, hn, sn, fcur, np.int64(v) - 1, f, gt)
                continue
            t = n
            tn = np.uint64(t)
            n += 1
            dsl[loc] = t + 1
            nkey[tn] = ks + mkey[m]
            x0 = e0 - moves[m, 0]
            x1 = e1 - moves[m, 1]
            x2 = e2 - moves[m, 2]
            hv = 0.0
            if oct_s > 0.0:
                hv = octile(oct_s, x0, x1, x2)
            elif gauge:
                if ncand < 0:
                    best = -np.inf
                    for k in range(nfac):
                        x = hmat[k, 0] * e0 + hmat[k, 1] * e1 + hmat[k, 2] * e2
                        fval[k] = x
                        best = max(best, x)
                    # the margin's last term outweighs any rounding of these sums
                    thr = best - 2.0 * hmd - 1e-9 * (1.0 + abs(best))
                    ncand = 0
                    for k in range(nfac):
                        if fval[k] >= thr:
                            cand[ncand] = k
                            ncand += 1
                for i in range(ncand):
                    k = cand[i]
                    x = hmat[k, 0] * x0 + hmat[k, 1] * x1 + hmat[k, 2] * x2
                    if x > hv:
                        hv = x
            nh[tn] = hv
            ng[tn] = gt
            f = _heap.fkey(gt + hv, fq, fq_inv)
            npar[tn] = s
            hn, sn = _heap.pq_push(heap, npos, hn, sn, fcur, t, f, gt)
    if status != RUN_FOUND:  # the arrays may be copied or the search resumed
        hn = _heap.pq_flush(heap, npos, hn, sn, fcur)
    st.nodes = n
    st.queued = hn
    st.expansions = expansions
    st.lookups = lookups
    return status
