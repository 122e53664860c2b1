"""One A* search's arrays as one compiled object, so that a call unboxes one argument.

A compiled call unboxes each array of its ``NamedTuple`` arguments from its Python object;
the kernel's world, move set and search arrays are about 40 of them, which cost more than a
short search. :class:`Bound` holds them (shared, not copied); the driver keeps one per
thread context and makes it again only when one of the arrays is replaced (another world,
another move set, grown arrays).
"""

from __future__ import annotations

from numba import types
from numba.experimental import structref

from planner._numba import njit_cached
from planner.search.astar.dense import dense_tables
from planner.search.astar.kernel import search_call
from planner.search.heuristic import H_EUCLID
from planner.search.moves import MAX_BITS

__all__ = ["Bound", "new_bound", "search_bound"]


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
    """:func:`~planner.search.astar.kernel.search_call` on the arrays of ``b``."""
    return search_call(b.occ, b.walk, b.ms, b.nodes, b.heap, b.slots, b.sc, b.ufree, params,
                       b.ends, b.counts, pausing, b.dt)
