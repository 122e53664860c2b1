"""Each thread's search arrays, kept between its searches (:mod:`planner.search.astar.driver`).

A :class:`_Context` holds one search's node table, heap, paged slot map, state and scratch;
a thread keeps up to two free contexts (a search run inside another, such as the goal
probe, takes a second) and its next search reuses them. A context also keeps the compiled
:class:`~planner.search.astar.bound.Bound` of the world it last searched, until the
world's structs' owner is freed (:func:`_unbind`, registered by :func:`_settle`).
"""

from __future__ import annotations

import threading
import weakref

import numpy as np

from planner.lattice import Lattice
from planner.occupancy.walk import walk_of
from planner.search._heap import new_heap
from planner.search._los import is_cubic, new_scratch
from planner.search._nodes import ASTAR_STATE, new_nodes, new_slots
from planner.search._state import new_state
from planner.search.astar._pool import give

__all__ = ["KEEP_NODES"]

#: node capacity a thread keeps between searches (larger arrays are dropped after use)
KEEP_NODES = 1 << 16
_CAP, _PCAP = 4096, 64  # initial node and page capacity (powers of 2)


class _Context:
    """One thread's kernel arrays, reused by its next search (module docstring)."""

    __slots__ = ("nodes", "heap", "slots", "state", "ufree", "ends", "end0", "end1", "sc",
                 "sc_key", "bound", "owner", "held", "fast", "points", "__weakref__")

    def __init__(self):
        self.nodes = new_nodes(_CAP)
        self.heap = new_heap(_CAP)
        self.slots = new_slots(_PCAP)
        self.state = new_state(ASTAR_STATE)
        self.ufree = np.empty(64, np.bool_)
        self.ends = np.empty((2, 3), np.int64)
        self.end0, self.end1 = self.ends  # its rows: ``row[...] = cell`` is the fastest copy
        self.sc = _no_sight()
        self.sc_key = None
        self.bound = None  # (its structs..., params, their types, Bound, its two entry points)
        self.owner = 0  # id of the owner of the bound world (see run)
        self.held = None  # (grid, its dense slot array, owner id) last searched: _dense
        self.fast = None  # what run's short path needs to repeat the last search (_run)
        self.points = None  # (compiled search_bound, rounding's ginv, its search_points)

    def keep(self, room: int = 0) -> None:
        """Drop arrays a long search grew past the kept size: :data:`KEEP_NODES` node slots,
        or ``room`` bytes of node table and heap (the dense slot array the context holds for
        its grid anyway). A query loop on one grid then grows them once, not per long query
        (the regrowth, its copies and first-touch page faults were a fifth of a long
        query's time); the bound stays unless an array goes."""
        dropped = False
        if (len(self.nodes.key) > KEEP_NODES
                and sum(a.nbytes for a in (*self.nodes, *self.heap)) > room):
            self.nodes, self.heap = new_nodes(_CAP), new_heap(_CAP)
            dropped = True
        if len(self.slots.bkeys) > KEEP_NODES // 8:
            self.slots = new_slots(_PCAP)
            dropped = True
        if dropped:
            self.bound = self.fast = None


_LOCAL = threading.local()
_CONTEXTS: weakref.WeakSet = weakref.WeakSet()  # every thread's contexts (see _unbind)
_OWNERS: set[int] = set()  # ids of the owners _unbind watches


def _context() -> _Context:
    """This thread's free context (a new one when a search is already running on it, e.g.
    the goal probe inside a paused search)."""
    free = getattr(_LOCAL, "free", None)
    if free is None:
        free = _LOCAL.free = []
    if free:
        return free.pop()
    ctx = _Context()
    _CONTEXTS.add(ctx)
    return ctx


def _release(ctx: _Context) -> None:
    free = _LOCAL.free
    if len(free) < 2:
        free.append(ctx)


_NO_SIGHT: list = []


def _no_sight():
    """A tiny sight scratch for lattice A* / Dijkstra (they never walk): allocated once."""
    if not _NO_SIGHT:
        _NO_SIGHT.append(new_scratch(0.0, walk_of(Lattice.named("cubic", 1.0))))
    return _NO_SIGHT[0]


def _sight(ctx: _Context, walk, span: float):
    """The any-angle sight scratch for ``walk`` and ``span``: kept in the context while the
    thread searches the same world."""
    if span <= 0 or is_cubic(walk.g):
        return _no_sight()  # cubic sight lines need no scratch
    key = (id(walk), span)
    if ctx.sc_key != key:
        ctx.sc, ctx.sc_key = new_scratch(span, walk), key
    return ctx.sc


def _settle(ctx: _Context, owner) -> None:
    """After a search of ``ctx`` for ``owner`` (see :func:`run`): keep its bound for the
    owner's next search, or drop what only the owner's lifetime would free; release it."""
    if owner is None:
        ctx.bound = ctx.fast = None
        h = ctx.held
        if h is not None:  # nothing would drop it when the grid is freed: back to the pool
            ctx.held = None
            give(h[0], h[1])
    else:
        ctx.owner = id(owner)
        if ctx.owner not in _OWNERS:
            _OWNERS.add(ctx.owner)
            weakref.finalize(owner, _unbind, ctx.owner)
    _release(ctx)  # not after an exception: a context left mid-search is dropped


def _unbind(owner_id: int) -> None:
    """The owner ``owner_id`` of a world's structs was freed: drop every context's
    :class:`Bound` of them (it holds the world's arrays, and the dense slot array pooled for
    them, which would otherwise outlive the world)."""
    _OWNERS.discard(owner_id)
    for ctx in list(_CONTEXTS):
        if ctx.owner == owner_id:
            ctx.bound, ctx.fast, ctx.owner = None, None, 0
        h = ctx.held
        if h is not None and h[2] == owner_id:
            ctx.held = ctx.fast = None
