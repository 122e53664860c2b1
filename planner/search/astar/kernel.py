"""The search kernel (numba): A* / Dijkstra over lattice cells, with the any-angle parent
rules of Theta* and Lazy Theta*. Resumable: the driver (:mod:`planner.search.astar.driver`)
grows the arrays when the kernel asks.

Theta* (``anyangle`` 1) checks line of sight from the expanded node's parent to each
neighbour when it is generated and links the neighbour to that parent when it can see it
(skipped when neither that parent nor the lattice move would improve the neighbour's g).
Lazy Theta* (``anyangle`` 2) assumes the sight line and verifies it once, when the node is
expanded, falling back to its best closed lattice neighbour (SetVertex). Both use the
Euclidean heuristic and the exact walk of :mod:`planner.search._los`.

One loop (:func:`_loop`) serves every method on every world; it is compiled once per
*variant*, a compile-time constant that fixes the tests the general case makes on every
expansion, so that each variant is the code a copy written for its case would be:
``GENERAL`` reads the method, the node map (dense or paged), the occupancy (dense or hashed)
and the stencil test (bit mask or move lists) from its arguments; ``DENSE_LAZY`` is Lazy
Theta* on a dense grid with the dense node array and the bit mask, the case a copy of this
loop (``dense_theta.py``) used to serve (``benchmarks/loop_speed.py`` measures it against
the paged map; ``tests/test_anyangle.py`` checks it against ``GENERAL``). Lattice A* / Dijkstra on a dense grid still runs its own loop,
:mod:`planner.search.astar.dense`.
"""

from __future__ import annotations

from typing import NamedTuple

import numba
import numpy as np

from planner._numba import njit_cached
from planner.occupancy.grid import cell_free, occ_free
from planner.occupancy.keys import mix64, pack3, step3, unpack3
from planner.search import _heap
from planner.search._los import DDA_MAX, cubic_walk, dense_walk, is_cubic, sight
from planner.search._nodes import (
    PAGE,
    block_key,
    dense_index,
    find_slot,
    finish,
    local,
    new_page,
)
from planner.search.astar.dense import dense_astar, grid_offsets, stencil_mask
from planner.search.heuristic import H_EUCLID, estimate, length, node_estimate, rows
from planner.search.moves import MAX_BITS, move_allowed
from planner.search.result import (
    RUN_BAD_GOAL,
    RUN_BAD_START,
    RUN_BUDGET,
    RUN_EXHAUSTED,
    RUN_FOUND,
    RUN_GROW,
    RUN_LIMIT,
)

_EMPTY = -1
THETA, LAZY_THETA = 1, 2  # SearchParams.anyangle
#: :func:`_loop`'s variants (compile-time constants, see there)
GENERAL, DENSE_LAZY = 0, 1


class SearchParams(NamedTuple):
    """Scalar settings of one search."""

    anyangle: int  # 0 lattice A* / Dijkstra, THETA, LAZY_THETA
    max_nodes: int  # stop (RUN_LIMIT) once this many nodes exist; <= 0 no limit
    max_expansions: int  # stop (RUN_BUDGET) after this many expansions; <= 0 no limit
    h_weight: float = 1.0  # the straight-line heuristic's factor (any-angle only)


@njit_cached(_nrt=False)
def search_init(start, goal, ms, g, nodes, heap, slots, st):  # pragma: no cover - compiled
    """Put the start node in empty node arrays (slot 0), the slot map and the heap."""
    bmask = slots.btab.shape[0] - 1
    nodes.key[0] = pack3(start[0], start[1], start[2])
    nodes.g[0] = 0.0
    nodes.h[0] = estimate(ms, g, goal[0] - start[0], goal[1] - start[1], goal[2] - start[2])
    nodes.par[0] = 0
    st.pages = 0
    st.queued = _heap.push(heap, nodes.pos, 0, 0, nodes.h[0], 0.0)
    if slots.dense.shape[0] > 1:
        slots.dense[dense_index(slots, start[0], start[1], start[2])] = 1  # slot 0, + 1
    else:
        bk = block_key(start[0], start[1], start[2])
        q = new_page(slots, st, bk, mix64(bk) & bmask)
        slots.pages[q * PAGE + local(start[0], start[1], start[2])] = 0
    st.nodes = 1


@njit_cached(nogil=True)  # threads search in parallel (search_many)
def search_run(occ, walk, ms, nodes, heap, slots, sc, ufree, params, ends, state, dt):
    # pragma: no cover - compiled
    """A* / Dijkstra / Theta* / Lazy Theta* over lattice cells, resumable.

    The node arrays are fixed-size inside the kernel: before each expansion it checks that
    the arrays and the slot map (load <= 0.5) can take every possible new node, else it
    returns ``RUN_GROW`` and the driver doubles them and calls again. Not reassigning arrays
    inside the loop lets numba drop per-iteration reference counting.

    Parameters
    ----------
    occ : Occupancy
    walk : Walk
        Lattice data of the line-of-sight walk (any-angle methods).
    ms : MoveSet
        Moves, their safe-rule cells and the heuristic.
    nodes : NodeTable
    heap : planner.search._heap.Heap
    slots : SlotMap
    sc : SightScratch
    ufree : (U,) bool
        Scratch for the union stencil lookups of one expansion.
    params : SearchParams
    ends : (2, 3) int64
        Start and goal cells. The first call (``nodes == 0``) checks that both are free
        (else it returns RUN_BAD_START or RUN_BAD_GOAL; no lookup counted) and puts the
        start in the empty structs (:func:`search_init`): one kernel call per search.
    state : (1,) ``planner.search._nodes.ASTAR_STATE``
        The search's counters (:mod:`planner.search._state`); the code returned is also
        left in ``status``.
    dt : planner.search.astar.dense.DenseTables
        The dense loop's tables of ``ms`` on ``occ``'s grid (made once per move set and
        world, not per search).

    Returns
    -------
    int
        RUN_FOUND, RUN_EXHAUSTED, RUN_LIMIT, RUN_BUDGET, RUN_GROW, RUN_BAD_START or
        RUN_BAD_GOAL.
    """
    st = state[0]
    goal = ends[1]
    if st.nodes == 0:
        start = ends[0]
        if not occ_free(occ, start[0], start[1], start[2]):
            st.status = RUN_BAD_START
            return RUN_BAD_START
        if not occ_free(occ, goal[0], goal[1], goal[2]):
            st.status = RUN_BAD_GOAL
            return RUN_BAD_GOAL
        search_init(start, goal, ms, walk.g, nodes, heap, slots, st)
    if (params.anyangle == 0 and occ.mode == 0 and slots.dense.shape[0] > 1
            and ms.union.shape[0] <= MAX_BITS and ms.hkind != H_EUCLID):
        status = dense_astar(occ.grid, occ.lo, occ.dims, ms, nodes, heap, slots.dense, st,
                             params.max_nodes, params.max_expansions, goal, dt)
        st.status = status
        return status
    # the loop's tables, made here: the loop allocates nothing (see _loop)
    uoff, moff, reach = grid_offsets(ms.union, ms.moves, occ.dims[1], occ.dims[2])
    ubit = np.arange(ms.union.shape[0])  # each stencil cell's bit in the mask: its order
    nm = ms.moves.shape[0]
    mkey = np.empty(nm, np.int64)
    for m in range(nm):
        mkey[m] = step3(ms.moves[m, 0], ms.moves[m, 1], ms.moves[m, 2])
    fq = 1e-9 * ms.cost.min()
    if (params.anyangle == LAZY_THETA and occ.mode == 0 and slots.dense.shape[0] > 1
            and ms.union.shape[0] <= MAX_BITS and ms.hkind == H_EUCLID and ms.octile <= 0.0):
        status = _loop(occ, walk, ms, nodes, heap, slots, sc, ufree, params, goal, st, uoff,
                       ubit, moff, reach, mkey, fq, DENSE_LAZY)
    else:
        status = _loop(occ, walk, ms, nodes, heap, slots, sc, ufree, params, goal, st, uoff,
                       ubit, moff, reach, mkey, fq, GENERAL)
    st.status = status
    return status


# Without the runtime's reference counting, as the dense loops (planner.search.astar.dense):
# each heap operation here would otherwise incref / decref the heap arrays it binds.
# Its rare allocating paths (the sight walk on fresh arrays, the float clipping of very
# long cubic lines) are separate compiled functions, which keep theirs.
@njit_cached(_nrt=False)
def _loop(occ, walk, ms, nodes, heap, slots, sc, ufree, params, goal, st, uoff, ubit, moff,
          reach, mkey, fq, variant):  # pragma: no cover - compiled
    """:func:`search_run`'s loop, given its tables: ``uoff`` (U,) and ``moff`` (M,)
    the stencil's and the moves' grid offsets and ``reach`` their margin (cells)
    (:func:`planner.search.astar.dense.grid_offsets`), ``ubit`` (U,) each stencil cell's
    bit in the free mask (:func:`planner.search.astar.dense.stencil_mask`), ``mkey`` (M,)
    each move as an offset of the packed key, ``fq`` the f grid (1e-9 of the shortest
    move, m). Returns the run code (see :func:`search_run`).

    ``variant`` (a compile-time constant: one compiled loop each) fixes what the loop
    would otherwise read from its arguments on every expansion: :data:`GENERAL` reads
    everything (method, dense or paged node map, dense or hashed occupancy, bit mask or
    move lists); :data:`DENSE_LAZY` is Lazy Theta* on a dense grid with the dense node
    array and the bit mask, where those tests fold away and the loop is the code a copy
    written for that case would be (``benchmarks/loop_speed.py`` measures it)."""
    numba.literally(variant)
    fixed = variant == DENSE_LAZY
    mode, grid, lo, dims, otable, otmask, gg, blo, bhi = occ
    lo0, lo1, lo2 = lo[0], lo[1], lo[2]
    d0, d1, d2 = dims[0], dims[1], dims[2]
    moves, mcost, ust, mptr, midx, hmat, hkind, need, oct_s = ms
    nkey, ng, nh, npar, npos = nodes
    pages, btab, bkeys, dsl, _, _ = slots
    gridded = fixed or mode == 0
    dense = fixed or (dsl.shape[0] > 1 and mode == 0)  # the dense slot box is the grid's box
    anyangle, max_nodes, max_exp, hw = params
    if fixed:
        anyangle = LAZY_THETA
    lazy = anyangle == LAZY_THETA
    theta = anyangle == THETA
    g = walk.g
    cubic = is_cubic(g)
    # sight lines between free cells of a dense grid stay inside its box: the walk on the
    # grid's arrays
    cubic_dense = cubic and gridded and max(d0, max(d1, d2)) <= DDA_MAX
    gl0, gl1, gl2 = goal[0], goal[1], goal[2]
    gm = rows(g)
    cap = nkey.shape[0]
    pcap = bkeys.shape[0]
    bsize = btab.shape[0]
    bmask = bsize - 1
    last_bk = np.int64(-1)
    last_pg = np.int64(0)
    nu = ust.shape[0]
    nm = moves.shape[0]
    bits = fixed or nu <= MAX_BITS  # one mask test per move instead of its CSR list
    all_u = (np.int64(1) << nu) - 1 if bits else np.int64(0)
    gk = pack3(goal[0], goal[1], goal[2])
    base = np.int64(0)
    fq_inv = 1.0 / fq
    n = st.nodes
    hn = st.queued
    # The f plateau's side heap (planner.search._heap) for lattice A* / Dijkstra; the
    # any-angle methods keep the one heap (plain push / pop: the side heap stays empty).
    sn = 0
    fcur = np.nan
    plateau = anyangle == 0
    expansions = st.expansions
    lookups = st.lookups
    status = RUN_EXHAUSTED
    while hn + sn > 0:
        if n + nm > cap or (not dense and (st.pages + nm > pcap
                                            or 2 * (st.pages + nm) > bsize)):
            status = RUN_GROW
            break
        if max_exp > 0 and expansions >= max_exp:
            status = RUN_BUDGET
            break
        if plateau:
            s, hn, sn, fcur = _heap.pq_pop(heap, npos, hn, sn, fcur)
        else:
            s, hn = _heap.pop(heap, npos, hn)
        npos[s] = -1
        expansions += 1
        ks = nkey[s]
        u0, u1, u2 = unpack3(ks)
        blocked = np.int64(0)
        if gridded:
            a0, b0, c0 = u0 - lo0, u1 - lo1, u2 - lo2
            base = (a0 * d1 + b0) * d2 + c0
            if bits:  # straight into the mask of free cells
                free = stencil_mask(grid, a0, b0, c0, d0, d1, d2, base, reach, ust, uoff,
                                    ubit)
                blocked = all_u & ~free
            elif (a0 >= reach and b0 >= reach and c0 >= reach and a0 < d0 - reach
                    and b0 < d1 - reach and c0 < d2 - reach):
                for j in range(nu):
                    f = base + uoff[j]
                    ufree[j] = (grid[f >> 3] >> (f & 7)) & 1 != 0
            else:
                for j in range(nu):
                    a = a0 + ust[j, 0]
                    b = b0 + ust[j, 1]
                    c = c0 + ust[j, 2]
                    f = (a * d1 + b) * d2 + c
                    ufree[j] = (a >= 0 and b >= 0 and c >= 0 and a < d0 and b < d1
                                and c < d2 and (grid[f >> 3] >> (f & 7)) & 1 != 0)
        else:
            for j in range(nu):
                ufree[j] = cell_free(mode, grid, lo, dims, otable, otmask, gg, blo, bhi,
                                     u0 + ust[j, 0], u1 + ust[j, 1], u2 + ust[j, 2])
            if bits:
                for j in range(nu):
                    if not ufree[j]:
                        blocked |= np.int64(1) << j
        lookups += nu
        ps = npar[s]
        p0, p1, p2 = u0, u1, u2
        if anyangle != 0 and ps != s:
            p0, p1, p2 = unpack3(nkey[ps])
        # Verify the assumed sight line, walked from s: a blocked cell is likelier near s
        # (its parent saw s's generator), so the walk stops sooner.
        if lazy and ps != s:
            if cubic_dense:
                ok, c = dense_walk(grid, lo, dims, u0, u1, u2, p0, p1, p2)
            elif cubic and not fixed:  # (a box too long for it: the face walk)
                ok, c = cubic_walk(occ, u0, u1, u2, p0, p1, p2)
            else:
                ok, c = sight(occ, walk, sc, st, u0, u1, u2, p0, p1, p2)
            lookups += c
            if not ok:
                # SetVertex: the best closed neighbour that an allowed move reaches (one
                # exists: the node that generated s)
                best = np.inf
                bp = np.int64(-1)
                for m in range(nm):
                    if bits:
                        if need[m] & blocked:
                            continue
                    elif not move_allowed(ufree, mptr, midx, m):
                        continue
                    if dense:  # an allowed move's target is free, hence inside the box
                        t = np.int64(dsl[np.uint64(base + moff[m])]) - 1
                    else:
                        t = find_slot(slots, u0 + moves[m, 0], u1 + moves[m, 1],
                                      u2 + moves[m, 2])
                    if t < 0 or npos[t] != -1:
                        continue
                    gv = ng[t] + mcost[m]
                    if gv < best:
                        best = gv
                        bp = t
                npar[s] = bp
                ng[s] = best
                ps = bp
                p0, p1, p2 = unpack3(nkey[ps])
        if ks == gk:
            status = RUN_FOUND
            st.goal = s
            break
        if max_nodes > 0 and n >= max_nodes:
            status = RUN_LIMIT
            break
        gs = ng[s]
        gp = ng[ps]
        for m in range(nm):
            # Safe rule first: with the bitmask it is one test, and an allowed move's target
            # is free, hence inside the dense box.
            if bits:
                if need[m] & blocked:
                    continue
            elif not move_allowed(ufree, mptr, midx, m):
                continue
            v0 = u0 + moves[m, 0]
            v1 = u1 + moves[m, 1]
            v2 = u2 + moves[m, 2]
            if dense:
                loc = np.uint64(base + moff[m])
                t = np.int64(dsl[loc]) - 1  # stored as slot + 1, 0 none
            else:
                bk = block_key(v0, v1, v2)
                if bk != last_bk:
                    p = mix64(bk) & bmask
                    while True:
                        q = btab[p]
                        if q == _EMPTY or bkeys[q] == bk:
                            break
                        p = (p + 1) & bmask
                    if q == _EMPTY:
                        q = new_page(slots, st, bk, p)
                    last_bk = bk
                    last_pg = q
                loc = np.uint64(last_pg * PAGE + local(v0, v1, v2))
                t = np.int64(pages[loc])
            tu = np.uint64(t)  # unsigned: no negative-index fix-up on each access
            if t >= 0:
                if npos[tu] == -1:
                    continue  # closed: a consistent heuristic never improves it
                if lazy and npar[tu] == ps:
                    # its g came through this parent, the sum below to the bit (a closed
                    # node's g stays): not less, so no square root
                    continue
            if anyangle == 0:
                gt = gs + mcost[m]
                par = s
            else:
                gt = gp + length(gm, v0 - p0, v1 - p1, v2 - p2)  # through s's parent
                par = ps
                if theta and ps != s:
                    g1 = gs + mcost[m]
                    if t >= 0 and gt >= ng[tu] and g1 >= ng[tu]:
                        continue  # neither parent improves t: its sight line is moot
                    if cubic_dense:
                        ok, c = dense_walk(grid, lo, dims, v0, v1, v2, p0, p1, p2)
                    elif cubic:
                        ok, c = cubic_walk(occ, v0, v1, v2, p0, p1, p2)
                    else:
                        ok, c = sight(occ, walk, sc, st, p0, p1, p2, v0, v1, v2)
                    lookups += c
                    if not ok:
                        gt = g1
                        par = s
            if t < 0:  # a new node
                t = n
                tu = np.uint64(t)
                n += 1
                if dense:
                    dsl[loc] = t + 1
                    nkey[tu] = ks + mkey[m]  # keys are linear inside the grid's box
                else:
                    pages[loc] = t
                    nkey[tu] = pack3(v0, v1, v2)
                if fixed:  # its move set's heuristic is the straight line (search_run)
                    hv = hw * length(gm, gl0 - v0, gl1 - v1, gl2 - v2)
                else:
                    hv = node_estimate(oct_s, hkind, hmat, hw, gm, gl0 - v0, gl1 - v1,
                                       gl2 - v2)
                nh[tu] = hv
                ng[tu] = gt
                npar[tu] = par
                fv = _heap.fkey(gt + hv, fq, fq_inv)
                if plateau:
                    hn, sn = _heap.pq_push(heap, npos, hn, sn, fcur, t, fv, gt)
                else:
                    hn = _heap.push(heap, npos, hn, t, fv, gt)
            elif gt < ng[tu]:
                ng[tu] = gt
                fv = _heap.fkey(gt + nh[tu], fq, fq_inv)
                npar[tu] = par
                if plateau:
                    hn, sn = _heap.pq_decrease(heap, npos, hn, sn, fcur, t, fv, gt)
                else:
                    _heap.decrease_key(heap, npos, t, fv, gt)
    if status != RUN_FOUND:  # the arrays may be copied or the search resumed
        hn = _heap.pq_flush(heap, npos, hn, sn, fcur)
    st.nodes = n
    st.queued = hn
    st.expansions = expansions
    st.lookups = lookups
    return status


@njit_cached(nogil=True)  # threads search in parallel (search_many)
def search_call(occ, walk, ms, nodes, heap, slots, sc, ufree, params, ends, state, pausing,
                dt):
    # pragma: no cover - compiled
    """:func:`search_run`, and when its code is final also
    :func:`planner.search._nodes.finish`: the one compiled call of a search that needs no
    growth. ``pausing``: RUN_BUDGET is a pause (the caller decides whether to go on), not
    final. ``dt``: as in :func:`search_run`.

    Returns
    -------
    tuple
        ``(status, path, cost, expansions, nodes, lookups)``: finish's path, cost and
        counts when final, else an empty path, inf and zeros (the state is kept).
    """
    status = search_run(occ, walk, ms, nodes, heap, slots, sc, ufree, params, ends, state, dt)
    if status == RUN_GROW or (pausing and status == RUN_BUDGET):
        return status, np.empty((0, 3), np.int64), np.inf, 0, 0, 0
    path, cost, exp, n, look = finish(nodes, slots, state, status == RUN_FOUND)
    return status, path, cost, exp, n, look
