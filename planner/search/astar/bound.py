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
therefore goes from :func:`search_bound` to the search loop directly, and counts no
references at all: reading a field of :class:`Bound` counts one for each array of the
field's struct, so the dense search runs in kernels compiled without reference counting
(``_nrt=False``) that read the fields through :func:`planner._numba.borrow_fields`, and
only the path's allocation runs in the kernel that counts them.
"""

from __future__ import annotations

import numpy as np
from numba import types
from numba.experimental import structref

from planner._numba import borrow_fields, njit_cached
from planner.occupancy.grid import occ_free, point_cells
from planner.search._nodes import end_search, path_length
from planner.search.astar.dense import dense_tables
from planner.search.astar.kernel import search_call, search_init
from planner.search.astar.loop import DENSE_ASTAR, search_loop
from planner.search.heuristic import H_EUCLID
from planner.search.moves import MAX_BITS
from planner.search.result import RUN_BAD_GOAL, RUN_BAD_START, RUN_BUDGET, RUN_FOUND, RUN_GROW

__all__ = ["Bound", "new_bound", "search_bound", "search_cells", "search_points"]


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
    """:class:`Bound` of these structs (their arrays shared, not copied), with the search
    loop's tables of ``ms`` on ``occ``'s grid."""
    return Bound(occ, walk, ms, nodes, heap, slots, sc, ufree, ends, state,
                 dense_tables(ms, occ.dims))


_NOT_DENSE = -1  # _dense_run: not a lattice A* / Dijkstra search on a dense grid


@njit_cached(_nrt=False, nogil=True)
def _dense_run(b, params, pausing):  # pragma: no cover - compiled
    """:func:`search_bound`'s dense search up to the path: ``(status, K)``, K the path's
    cells when found (else 0); ``(_NOT_DENSE, 0)``, and nothing done, when the search is
    not lattice A* / Dijkstra on a dense grid."""
    occ, walk, ms, nodes, heap, slots, sc, ufree, ends, counts, dt = borrow_fields(b)
    if not (params.anyangle == 0 and occ.mode == 0 and slots.dense.shape[0] > 1
            and ms.union.shape[0] <= MAX_BITS and ms.hkind != H_EUCLID):
        return _NOT_DENSE, 0
    # search_run's first steps and its DENSE_ASTAR branch, written out
    st = counts[0]
    goal = ends[1]
    if st.nodes == 0:
        start = ends[0]
        status = 0
        if not occ_free(occ, start[0], start[1], start[2]):
            status = RUN_BAD_START
        elif not occ_free(occ, goal[0], goal[1], goal[2]):
            status = RUN_BAD_GOAL
        if status != 0:
            st.status = status
            return status, 0
        search_init(start, goal, ms, walk.g, nodes, heap, slots, st)
    status = search_loop(occ, walk, ms, nodes, heap, slots, sc, ufree, params, goal, st, dt,
                         DENSE_ASTAR)
    st.status = status
    return status, path_length(nodes, st.goal) if status == RUN_FOUND else 0


@njit_cached(_nrt=False, nogil=True)
def _dense_end(b, path):  # pragma: no cover - compiled
    """:func:`~planner.search._nodes.end_search` on the arrays of ``b``."""
    occ, walk, ms, nodes, heap, slots, sc, ufree, ends, counts, dt = borrow_fields(b)
    return end_search(nodes, slots, counts, path)


@njit_cached(nogil=True)  # threads search in parallel (search_many)
def search_bound(b, params, pausing):  # pragma: no cover - compiled
    """:func:`~planner.search.astar.kernel.search_call` on the arrays of ``b``: the same
    answer, and for lattice A* / Dijkstra on a dense grid the same steps without the calls
    between, in kernels that count no references (module docstring)."""
    status, k = _dense_run(b, params, pausing)
    if status == _NOT_DENSE:
        return search_call(b.occ, b.walk, b.ms, b.nodes, b.heap, b.slots, b.sc, b.ufree, params,
                           b.ends, b.counts, pausing, b.dt)
    if status == RUN_GROW or (pausing and status == RUN_BUDGET):
        return status, np.empty((0, 3), np.int64), np.inf, 0, 0, 0
    path = np.empty((k, 3), np.int64)
    cost, exp, n, look = _dense_end(b, path)
    return status, path, cost, exp, n, look


@njit_cached(_nrt=False)
def _put_ends(b, s0, s1, s2, g0, g1, g2):  # pragma: no cover - compiled
    ends = borrow_fields(b)[8]
    ends[0, 0], ends[0, 1], ends[0, 2] = s0, s1, s2
    ends[1, 0], ends[1, 1], ends[1, 2] = g0, g1, g2


@njit_cached(nogil=True)
def search_cells(b, params, pausing, s0, s1, s2, g0, g1, g2):  # pragma: no cover - compiled
    """:func:`search_bound` from cell (s0, s1, s2) to cell (g0, g1, g2), written to
    ``b.ends`` first: Python passes six integers for less than it takes to copy two small
    arrays into ``b.ends``."""
    _put_ends(b, s0, s1, s2, g0, g1, g2)
    return search_bound(b, params, pausing)


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
