"""The search kernel (numba): A* / Dijkstra over lattice cells, with the any-angle parent
rules of Theta* and Lazy Theta*. Resumable: the driver (:mod:`planner.search.astar.driver`)
grows the arrays when the kernel asks.

Theta* (``anyangle`` 1) checks line of sight from the expanded node's parent to each
neighbour when it is generated and links the neighbour to that parent when it can see it
(skipped when neither that parent nor the lattice move would improve the neighbour's g).
Lazy Theta* (``anyangle`` 2) assumes the sight line and verifies it once, when the node is
expanded, falling back to its best closed lattice neighbour (SetVertex). Both use the
Euclidean heuristic and the exact walk of :mod:`planner.search._los`.

Every search runs the one search loop, :func:`planner.search.astar.loop.search_loop`,
compiled per variant: :func:`search_run` picks ``DENSE_ASTAR`` (lattice A* / Dijkstra) or
``DENSE_LAZY`` (Lazy Theta*) on a dense grid with the dense node array and a stencil that
fits the bit mask, else ``GENERAL``.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from planner._numba import njit_cached
from planner.occupancy.grid import occ_free
from planner.occupancy.keys import mix64, pack3
from planner.search import _heap
from planner.search._nodes import PAGE, block_key, dense_index, finish, local, new_page
from planner.search.astar.loop import (
    DENSE_ASTAR,
    DENSE_LAZY,
    GENERAL,
    LAZY_THETA,
    THETA,
    search_loop,
)
from planner.search.heuristic import H_EUCLID, estimate
from planner.search.moves import MAX_BITS
from planner.search.result import RUN_BAD_GOAL, RUN_BAD_START, RUN_BUDGET, RUN_FOUND, RUN_GROW

__all__ = ["LAZY_THETA", "THETA", "SearchParams", "search_call", "search_init", "search_run"]


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
    returns ``RUN_GROW`` and the driver doubles them and calls again (the loop then
    allocates nothing and counts no references).

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
        The loop's tables of ``ms`` on ``occ``'s grid (made once per move set and world,
        not per search).

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
    dense = occ.mode == 0 and slots.dense.shape[0] > 1 and ms.union.shape[0] <= MAX_BITS
    if dense and params.anyangle == 0 and ms.hkind != H_EUCLID:
        status = search_loop(occ, walk, ms, nodes, heap, slots, sc, ufree, params, goal, st,
                             dt, DENSE_ASTAR)
    elif (dense and params.anyangle == LAZY_THETA and ms.hkind == H_EUCLID
            and ms.octile <= 0.0):
        status = search_loop(occ, walk, ms, nodes, heap, slots, sc, ufree, params, goal, st,
                             dt, DENSE_LAZY)
    else:
        status = search_loop(occ, walk, ms, nodes, heap, slots, sc, ufree, params, goal, st,
                             dt, GENERAL)
    st.status = status
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
