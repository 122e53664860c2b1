"""Each thread's search arrays, kept between its searches (:mod:`planner.search.astar.driver`).

A :class:`_Context` holds one search's node table, heap, paged slot map, state and scratch;
a thread keeps up to :data:`CONTEXTS_KEPT` free contexts and its next search reuses them:
the one its last search on the same world left ready (a query loop that takes turns
between worlds, lattices compared query by query, finds each world's as it left it), else
the one holding the dense slot array of the same grid, else a new one while the thread
keeps fewer, else the least recently used (a search run inside another, such as the goal
probe, takes another than its caller's). A context also keeps the compiled
:class:`~planner.search.astar.bound.Bound` of each of the last :data:`BOUNDS_KEPT` worlds it
searched, until the world's structs' owner is freed (:func:`_unbind`, registered by
:func:`_settle`).
"""

from __future__ import annotations

import threading
import weakref
from typing import NamedTuple

import numpy as np

from planner.lattice import Lattice
from planner.occupancy.walk import walk_of
from planner.search._heap import new_heap
from planner.search._kept import kept_scratch
from planner.search._los import is_cubic, new_scratch
from planner.search._nodes import ASTAR_STATE, new_nodes, new_slots
from planner.search._state import new_state
from planner.search.astar._pool import give

__all__ = ["CONTEXTS_KEPT", "KEEP_NODES"]

#: free contexts a thread keeps: a new one costs some 17 us and 280 KB (with the arrays a
#: long search grew, at most twice the dense slot array it holds: :meth:`_Context.keep`)
CONTEXTS_KEPT = 8
#: node capacity a context keeps between searches (larger arrays are dropped after use)
KEEP_NODES = 1 << 16
_CAP, _PCAP = 4096, 64  # initial node and page capacity (powers of 2)


class _Fast:
    """What :func:`~planner.search.astar.driver.run`'s short path needs to repeat a
    context's last search (set by the driver's ``_run``): the arguments a search must match
    to take it, and the compiled call with its own arguments. A class with slots, not a
    tuple read by index: its attributes read as fast (the short path reads ten of them)."""

    __slots__ = ("occ", "ms", "params", "owner", "walk", "pause_at", "no_probe", "bound",
                 "search", "first", "pausing", "small", "rest", "cells", "tag")

    def __init__(self, occ, ms, params, owner: int, walk, pause_at: int, no_probe: bool,
                 bound, search, first, pausing: bool, small: int, rest: int, cells, tag):
        self.occ, self.ms, self.params, self.walk = occ, ms, params, walk
        self.owner = owner  # id of the structs' owner
        self.pause_at, self.no_probe = pause_at, no_probe  # no_probe: keep_going was None
        self.bound, self.search, self.cells = bound, search, cells  # Bound, its entry points
        self.first, self.pausing = first, pausing  # the settings the kernel runs with
        self.small, self.rest = small, rest  # peak bytes at the initial capacity; the rest
        self.tag = tag  # stands for every argument but the cells (see run)


class _Memo:
    """A context's :class:`~planner.search.astar.bound.Bound` and the objects it was made
    from (compared by identity before it is reused), with its two compiled entry points."""

    __slots__ = ("occ", "walk", "ms", "sc", "dense", "nodes", "slots", "ufree", "params",
                 "ptypes", "bound", "search", "cells", "owner")

    def __init__(self, occ, walk, ms, sc, dense, nodes, slots, ufree, params, ptypes, bound,
                 search, cells):
        self.occ, self.walk, self.ms, self.sc, self.dense = occ, walk, ms, sc, dense
        self.nodes, self.slots, self.ufree = nodes, slots, ufree
        self.params, self.ptypes = params, ptypes  # the settings and their field types
        self.bound, self.search, self.cells = bound, search, cells
        self.owner = 0  # id of the owner of the world's structs (see run); 0 not yet known

    def made_of(self, occ, walk, ms, sc, dense, nodes, slots, ufree) -> bool:
        """Made from exactly these objects."""
        return (self.occ is occ and self.walk is walk and self.ms is ms and self.sc is sc
                and self.dense is dense and self.nodes is nodes and self.slots is slots
                and self.ufree is ufree)


#: Bounds a context keeps for the worlds it searched last (:attr:`_Context.bounds`): a
#: query loop that takes turns between worlds (a comparison of lattices, query by query)
#: then makes each once instead of on every search (about 20 us each).
BOUNDS_KEPT = 8


class _Held(NamedTuple):
    """The dense slot array a context holds for the grid it last searched."""

    grid: object
    slots: np.ndarray
    owner: int  # id of the owner of the structs it was taken for


class _Points:
    """The compiled ``search_points`` (``call``) a context last used, for its
    ``search_bound`` entry point and the rounding's ``ginv`` array (read on every plan)."""

    __slots__ = ("search", "ginv", "call")

    def __init__(self, search, ginv: np.ndarray, call):
        self.search, self.ginv, self.call = search, ginv, call


class _Context:
    """One thread's kernel arrays, reused by its next search (module docstring)."""

    __slots__ = ("nodes", "heap", "slots", "state", "ufree", "ends", "end0", "end1",
                 "scratch", "bound", "bounds", "held", "fast", "points", "__weakref__")

    def __init__(self):
        self.nodes = new_nodes(_CAP)
        self.heap = new_heap(_CAP)
        self.slots = new_slots(_PCAP)
        self.state = new_state(ASTAR_STATE)
        self.ufree = np.empty(64, np.bool_)
        self.ends = np.empty((2, 3), np.int64)
        self.end0, self.end1 = self.ends  # its rows: ``row[...] = cell`` is the fastest copy
        self.scratch: dict = {}  # any-angle sight scratch per walk (_sight)
        self.bound: _Memo | None = None  # the Bound of the last world searched
        self.bounds: dict[tuple, _Memo] = {}  # the last BOUNDS_KEPT, by their objects' ids
        self.held: _Held | None = None  # the dense slot array of the last grid: _dense
        self.fast: _Fast | None = None  # how run's short path repeats the last search
        self.points: _Points | None = None  # the last search_points (run_points)

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
            self.forget()

    def forget(self) -> None:
        """Drop the kept bounds (their arrays are no longer the context's)."""
        self.bound = self.fast = None
        self.bounds.clear()

    def remember(self, memo: _Memo) -> None:
        """Keep ``memo`` among the last :data:`BOUNDS_KEPT` bounds, as the current one."""
        key = (id(memo.occ), id(memo.ms), id(memo.sc), id(memo.dense))
        kept = self.bounds  # (_unbind, on any thread, replaces the dict: never changes it)
        kept.pop(key, None)
        if len(kept) >= BOUNDS_KEPT:
            kept.pop(next(iter(kept)), None)  # the least recently made
        kept[key] = self.bound = memo

    def recall(self, occ, walk, ms, sc, dense) -> _Memo | None:
        """The kept bound made from these objects and the context's arrays, or None."""
        memo = self.bounds.get((id(occ), id(ms), id(sc), id(dense)))
        if memo is None or not memo.made_of(occ, walk, ms, sc, dense, self.nodes, self.slots,
                                            self.ufree):
            return None
        return memo


_LOCAL = threading.local()
_CONTEXTS: weakref.WeakSet = weakref.WeakSet()  # every thread's contexts (see _unbind)
_OWNERS: set[int] = set()  # ids of the owners _unbind watches


def _release(ctx: _Context, free: list) -> None:
    """Put ``ctx`` back among the thread's ``free`` contexts while it keeps fewer than
    :data:`CONTEXTS_KEPT`."""
    if len(free) < CONTEXTS_KEPT:
        free.append(ctx)  # the most recently used last


def _free_context(free: list, grid) -> _Context:
    """For a search that no free context's last search matches (module docstring): the
    free context holding ``grid``'s dense slot array, else a new one while ``free`` has
    room to keep it, else the least recently used; taken out of ``free``."""
    for k in range(len(free) - 1, -1, -1):
        h = free[k].held
        if h is not None and h.grid is grid:
            return free.pop(k)
    if free and len(free) >= CONTEXTS_KEPT - 1:
        return free.pop(0)
    ctx = _Context()
    _CONTEXTS.add(ctx)
    return ctx


_NO_SIGHT: list = []


def _no_sight():
    """A tiny sight scratch for lattice A* / Dijkstra (they never walk): allocated once."""
    if not _NO_SIGHT:
        _NO_SIGHT.append(new_scratch(0.0, walk_of(Lattice.named("cubic", 1.0))))
    return _NO_SIGHT[0]


def _sight(ctx: _Context, walk, span: float):
    """The any-angle sight scratch for ``walk`` and ``span``, kept in the context for the
    walks it searches (:mod:`planner.search._kept`; the search state's ``stamp``, which
    keeps counting, stamps every one of them)."""
    if span <= 0 or is_cubic(walk.g):
        return _no_sight()  # cubic sight lines need no scratch
    return kept_scratch(ctx.scratch, walk, span).sc


_SCRATCH_BYTES: dict[tuple, tuple] = {}  # (id(walk), span) -> (walk, bytes)


def _fresh_scratch_bytes(walk, span: float) -> int:
    """Bytes of the sight scratch a search alone would make for ``walk`` and sight lines up
    to ``span`` m: the context's kept one may be larger (made for a longer span before), and
    a search's reported memory must not depend on what ran before it. One throwaway scratch
    per walk and span (a world's searches share its span)."""
    hit = _SCRATCH_BYTES.get((id(walk), span))
    if hit is not None and hit[0] is walk:
        return hit[1]
    n = sum(a.nbytes for a in new_scratch(span, walk))
    if len(_SCRATCH_BYTES) >= 64:
        _SCRATCH_BYTES.clear()
    _SCRATCH_BYTES[(id(walk), span)] = (walk, n)  # holds the walk: its id stays its own
    return n


def _settle(ctx: _Context, owner) -> None:
    """After a search of ``ctx`` for ``owner`` (see :func:`run`): keep its bound for the
    owner's next search, or drop what only the owner's lifetime would free; release it."""
    bd = ctx.bound
    if owner is None:
        if bd is not None:  # nothing would drop it when the world is freed
            ctx.bounds = {k: m for k, m in ctx.bounds.items() if m is not bd}
        ctx.bound = ctx.fast = None
        h = ctx.held
        if h is not None:  # nothing would drop it when the grid is freed: back to the pool
            ctx.held = None
            give(h.grid, h.slots)
    else:
        oid = id(owner)
        if bd is not None:
            bd.owner = oid
        if oid not in _OWNERS:
            _OWNERS.add(oid)
            weakref.finalize(owner, _unbind, oid)
    _release(ctx, _LOCAL.free)  # not after an exception: a context left mid-search is dropped


def _unbind(owner_id: int) -> None:
    """The owner ``owner_id`` of a world's structs was freed: drop every context's
    :class:`Bound` of them (it holds the world's arrays, and the dense slot array pooled for
    them, which would otherwise outlive the world)."""
    _OWNERS.discard(owner_id)
    for ctx in list(_CONTEXTS):
        kept = list(ctx.bounds.items())  # (one C call: atomic against the context's thread)
        if any(m.owner == owner_id for _, m in kept):
            ctx.bounds = {k: m for k, m in kept if m.owner != owner_id}  # replaced, not changed
        if ctx.bound is not None and ctx.bound.owner == owner_id:
            ctx.bound = None
        if ctx.fast is not None and ctx.fast.owner == owner_id:
            ctx.fast = None
        h = ctx.held
        if h is not None and h.owner == owner_id:
            ctx.held = ctx.fast = None
