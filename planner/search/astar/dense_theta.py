"""The Lazy Theta* loop on a dense occupancy grid (numba), every lattice: the A* kernel's
(:mod:`planner.search.astar.kernel`) any-angle path for its commonest case, written for
that case alone, as :mod:`planner.search.astar.dense` is for lattice A*.

It runs when the world is a dense bit grid, the cell -> slot map is dense too and the move
set's union stencil fits a bit mask. Per expansion it reads the union stencil once into a
mask of free cells, verifies the assumed sight line to the parent (falling back to the
best closed lattice neighbour, SetVertex), and per allowed move finds the target's node
in one load of the dense slot array. The sight line is the lattice's walk, chosen once per
call: on the cubic lattice the integer walk on the grid's arrays
(:func:`planner.search._los.dense_walk`, when the box's longest side is at most
``DDA_MAX``), on every other lattice the face walk (:func:`planner.search._los.sight`), as
in the general loop. Same expansions, costs, paths and lookups as the general loop, which
stays its reference (``tests/test_anyangle.py``).
"""

from __future__ import annotations

import numpy as np

from planner._numba import njit_cached
from planner.occupancy.keys import pack3, step3, unpack3
from planner.search import _heap
from planner.search._los import DDA_MAX, dense_walk, is_cubic, sight
from planner.search.astar.dense import grid_offsets, stencil_mask
from planner.search.heuristic import length, rows
from planner.search.result import RUN_BUDGET, RUN_EXHAUSTED, RUN_FOUND, RUN_GROW, RUN_LIMIT

__all__ = ["dense_lazy_theta"]


@njit_cached
def dense_lazy_theta(occ, walk, ms, nodes, heap, dsl, sc, st, max_nodes, max_exp, goal, hw):
    # pragma: no cover - compiled
    """Run Lazy Theta* from the kernel's state ``st`` until it ends or needs room.

    Parameters
    ----------
    occ : Occupancy
        Dense (mode 0).
    walk : Walk
        The lattice's sight walk data (its generator ``g``, the face walk's table).
    ms : MoveSet
        With ``len(ms.union) <= 63``.
    nodes : NodeTable
    heap : planner.search._heap.Heap
    dsl : (prod(occ.dims),) int32
        Dense cell -> node slot + 1 (0: none) over the grid's box.
    sc : SightScratch
        The face walk's scratch (non-cubic lattices).
    st : ``ASTAR_STATE`` record
        The search's counters; the start node is already in place.
    max_nodes, max_exp : int
        Limits (<= 0: none).
    goal : (3,) int64
    hw : float
        The straight-line heuristic's factor.

    Returns
    -------
    int
        RUN_FOUND, RUN_EXHAUSTED, RUN_LIMIT, RUN_BUDGET or RUN_GROW.
    """
    moves = ms.moves
    nm = moves.shape[0]
    uoff, moff, reach = grid_offsets(ms.union, moves, occ.dims[1], occ.dims[2])
    ubit = np.arange(ms.union.shape[0])  # each stencil cell's bit: the stencil's order
    mkey = np.empty(nm, np.int64)
    for m in range(nm):
        mkey[m] = step3(moves[m, 0], moves[m, 1], moves[m, 2])
    # the integer walk on the grid's arrays: sight lines between free cells of a dense grid
    # stay inside its box
    cubic = is_cubic(walk.g) and occ.dims.max() <= DDA_MAX
    return _loop(occ, walk, ms, nodes, heap, dsl, sc, st, max_nodes, max_exp, goal, hw, uoff,
                 ubit, moff, reach, mkey, 1e-9 * ms.cost.min(), cubic)


# Without the runtime's reference counting, as the dense A* loop (planner.search.astar.dense):
# each heap operation here would otherwise incref / decref the heap arrays it binds.
@njit_cached(_nrt=False)
def _loop(occ, walk, ms, nodes, heap, dsl, sc, st, max_nodes, max_exp, goal, hw, uoff, ubit, moff,
          reach, mkey, fq, cubic):  # pragma: no cover - compiled
    """:func:`dense_lazy_theta`'s loop, given its tables: ``uoff`` (U,) and ``moff`` (M,) the
    stencil's and the moves' grid offsets and ``reach`` their margin (cells)
    (:func:`planner.search.astar.dense.grid_offsets`), ``ubit`` (U,) each stencil cell's
    bit in the free mask (:func:`planner.search.astar.dense.stencil_mask`),
    ``mkey`` (M,) each move as an offset of the packed key, ``fq`` the f grid (1e-9 of the
    shortest move, m), ``cubic`` the sight line by the integer walk on the grid's arrays
    (else :func:`sight`)."""
    grid, lo, dims = occ.grid, occ.lo, occ.dims
    lo0, lo1, lo2 = lo[0], lo[1], lo[2]
    d0, d1, d2 = dims[0], dims[1], dims[2]
    moves, mcost, ust, need = ms.moves, ms.cost, ms.union, ms.need
    nkey, ng, nh, npar, npos = nodes
    nu = ust.shape[0]
    nm = moves.shape[0]
    cap = nkey.shape[0]
    g = walk.g
    gm = rows(g)
    gl0, gl1, gl2 = goal[0], goal[1], goal[2]
    gk = pack3(gl0, gl1, gl2)
    all_u = (np.int64(1) << nu) - 1
    fq_inv = 1.0 / fq
    n = st.nodes
    hn = st.queued
    expansions = st.expansions
    lookups = st.lookups
    status = RUN_EXHAUSTED
    while hn > 0:
        if n + nm > cap:
            status = RUN_GROW
            break
        if max_exp > 0 and expansions >= max_exp:
            status = RUN_BUDGET
            break
        s, hn = _heap.pop(heap, npos, hn)
        npos[s] = -1
        expansions += 1
        ks = nkey[s]
        u0, u1, u2 = unpack3(ks)
        a0, b0, c0 = u0 - lo0, u1 - lo1, u2 - lo2
        base = (a0 * d1 + b0) * d2 + c0
        free = stencil_mask(grid, a0, b0, c0, d0, d1, d2, base, reach, ust, uoff, ubit)
        blocked = all_u & ~free
        lookups += nu
        ps = npar[s]
        p0, p1, p2 = u0, u1, u2
        if ps != s:
            # Verify the assumed sight line, walked from s (a blocked cell is likelier
            # near s: its parent saw s's generator).
            p0, p1, p2 = unpack3(nkey[ps])
            if cubic:
                ok, c = dense_walk(grid, lo, dims, u0, u1, u2, p0, p1, p2)
            else:
                ok, c = sight(occ, walk, sc, st, u0, u1, u2, p0, p1, p2)
            lookups += c
            if not ok:
                # SetVertex: the best closed neighbour that an allowed move reaches (one
                # exists: the node that generated s).
                best = np.inf
                bp = np.int64(-1)
                for m in range(nm):
                    if need[m] & blocked:
                        continue
                    t = np.int64(dsl[np.uint64(base + moff[m])]) - 1
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
        gp = ng[ps]
        for m in range(nm):
            if need[m] & blocked:
                continue
            # an allowed move's target is free, hence in the box
            loc = np.uint64(base + moff[m])
            t = np.int64(dsl[loc]) - 1
            if t >= 0:
                tu = np.uint64(t)
                if npos[tu] == -1:
                    continue  # closed: a consistent heuristic never improves it
                if npar[tu] == ps:
                    # its g came through this parent, the sum below to the bit (a closed
                    # node's g stays): not less, so no square root
                    continue
            v0 = u0 + moves[m, 0]
            v1 = u1 + moves[m, 1]
            v2 = u2 + moves[m, 2]
            gt = gp + length(gm, v0 - p0, v1 - p1, v2 - p2)  # through s's parent, as _loop
            if t < 0:
                t = n
                n += 1
                dsl[loc] = t + 1
                nkey[t] = ks + mkey[m]
                hv = hw * length(gm, gl0 - v0, gl1 - v1, gl2 - v2)
                nh[t] = hv
                ng[t] = gt
                f = _heap.fkey(gt + hv, fq, fq_inv)
                npar[t] = ps
                hn = _heap.push(heap, npos, hn, t, f, gt)
                continue
            if gt < ng[tu]:
                ng[tu] = gt
                f = _heap.fkey(gt + nh[tu], fq, fq_inv)
                npar[tu] = ps
                _heap.decrease_key(heap, npos, t, f, gt)
    st.nodes = n
    st.queued = hn
    st.expansions = expansions
    st.lookups = lookups
    return status
