"""One A* search's arrays as one compiled object, so that a call unboxes one argument.

A compiled call unboxes each array of its ``NamedTuple`` arguments from its Python object;
the kernel's world, move set and search arrays are about 40 of them, which cost more than a
short search. :class:`Bound` holds them (shared, not copied); the driver keeps one per
thread context and makes it again only when one of the arrays is replaced (another world,
another move set, grown arrays).

Inside compiled code every call to a function that is not inlined counts a reference to
each array of its arguments on entry and releases it on return: passing the 13 structs
down :func:`search_bound` -> ``search_call`` -> ``search_run`` cost more than a
one-expansion search itself. The commonest case (lattice A* / Dijkstra on a dense grid)
therefore goes from :func:`search_bound` to the dense loop directly.
"""

from __future__ import annotations

import numpy as np
from numba import types
from numba.experimental import structref

from planner._numba import njit_cached
from planner.occupancy.grid import occ_free, point_cells
from planner.search._nodes import finish
from planner.search.astar.dense import dense_astar, dense_tables
from planner.search.astar.kernel import search_call, search_init
from planner.search.heuristic import H_EUCLID
from planner.search.moves import MAX_BITS
from planner.search.result import RUN_BAD_GOAL, RUN_BAD_START, RUN_BUDGET, RUN_FOUND, RUN_GROW

__all__ = ["Bound", "new_bound", "search_bound", "search_points"]


@structref.register
class _BoundType(types.StructRef):
    def preprocess_fields(self, fields):
        return tuple((n, types.unliteral(t)) for n, t in fields)


class Bound(structref.StructRefProxy):
    """The arguments of :func:`planner.search.astar.kernel.search_call` but ``params`` and
    ``pausing``, as one object (made by :func:`new_bound`)."""


structref.define_proxy(Bound, _BoundType,
                       ["occ", "walk", "ms", "nodes", "heap", "slots", "sc", "ufree", "ends",
                        "counts", "dt"])


@njit_cached
def new_bound(occ, walk, ms, nodes, heap, slots, sc, ufree, ends, state):
    # pragma: no cover - compiled
    """:class:`Bound` of these structs (their arrays shared, not copied), with the dense
    loop's tables of ``ms`` on ``occ``'s grid when that loop may run on them."""
    used = occ.mode == 0 and ms.union.shape[0] <= MAX_BITS and ms.hkind != H_EUCLID
    return Bound(occ, walk, ms, nodes, heap, slots, sc, ufree, ends, state,
                 dense_tables(ms, occ.dims, used))


@njit_cached(nogil=True)  # threads search in parallel (search_many)
def search_bound(b, params, pausing):  # pragma: no cover - compiled
    """:func:`~planner.search.astar.kernel.search_call` on the arrays of ``b``: the same
    answer, and for lattice A* / Dijkstra on a dense grid the same steps without the calls
    between (module docstring)."""
    occ, ms = b.occ, b.ms
    dsl = b.slots.dense
    if not (params.anyangle == 0 and occ.mode == 0 and dsl.shape[0] > 1
            and ms.union.shape[0] <= MAX_BITS and ms.hkind != H_EUCLID):
        return search_call(occ, b.walk, ms, b.nodes, b.heap, b.slots, b.sc, b.ufree, params,
                           b.ends, b.counts, pausing, b.dt)
    # search_run's first steps and its dense branch, then search_call's end, written out
    st = b.counts[0]
    goal = b.ends[1]
    if st.nodes == 0:
        start = b.ends[0]
        status = 0
        if not occ_free(occ, start[0], start[1], start[2]):
            status = RUN_BAD_START
        elif not occ_free(occ, goal[0], goal[1], goal[2]):
            status = RUN_BAD_GOAL
        if status != 0:
            st.status = status
            path, cost, exp, n, look = finish(b.nodes, b.slots, b.counts, False)
            return status, path, cost, exp, n, look
        search_init(start, goal, ms, b.walk.g, b.nodes, b.heap, b.slots, st)
    status = dense_astar(occ.grid, occ.lo, occ.dims, ms, b.nodes, b.heap, dsl, st,
                         params.max_nodes, params.max_expansions, goal, b.dt)
    st.status = status
    if status == RUN_GROW or (pausing and status == RUN_BUDGET):
        return status, np.empty((0, 3), np.int64), np.inf, 0, 0, 0
    path, cost, exp, n, look = finish(b.nodes, b.slots, b.counts, status == RUN_FOUND)
    return status, path, cost, exp, n, look


@njit_cached(nogil=True)
def search_points(b, params, pausing, kind, ra, rb, ginv, reach, x0, x1, x2, y0, y1, y2):
    # pragma: no cover - compiled
    """:func:`search_bound` between the cells of two points, (x0, x1, x2) and (y0, y1, y2)
    (m), that :func:`planner.occupancy.grid.point_cells` finds with the rounding arguments
    ``kind, ra, rb, ginv`` and writes to ``b.ends`` first: a plan's endpoint lookups and
    its search in one call. RUN_BAD_START or RUN_BAD_GOAL, and nothing else done, when a
    cell is out of bounds or blocked, or a coordinate is past the rounding's exact range
    ``reach`` (m)."""
    free = 0
    if (-reach <= x0 <= reach and -reach <= x1 <= reach and -reach <= x2 <= reach
            and -reach <= y0 <= reach and -reach <= y1 <= reach and -reach <= y2 <= reach):
        free = point_cells(b.occ, kind, ra, rb, ginv, x0, x1, x2, y0, y1, y2, b.ends)
    if free != 3:
        status = RUN_BAD_START if free & 1 == 0 else RUN_BAD_GOAL
        return status, np.empty((0, 3), np.int64), np.inf, 0, 0, 0
    return search_bound(b, params, pausing)
