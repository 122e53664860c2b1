"""Python driver of the resumable search kernel: keeps each thread's kernel arrays between
searches, grows them when the kernel asks, and traces the path.

A search's fixed cost is what it pays outside the expansions, so nothing here is allocated
per call: each thread keeps up to :data:`~planner.search.astar._context.CONTEXTS_KEPT`
:class:`_Context` s (node table, heap, paged slot map, state, scratch) whose arrays its next
searches reuse, and a dense grid's cell -> slot array is held by the context that last
searched the grid (pooled per grid when it moves on). Arrays grown past :data:`KEEP_NODES`
for a long search are dropped afterwards, unless they fit in the bytes of the dense grid's
slot array the context keeps anyway, so an idle context holds at most a short search's
memory or twice that array.

A search like a free context's last one (same structs, settings and owner: the usual query
loop, or one world's turn in a loop taking turns between worlds) takes :func:`run`'s short
path: one compiled call, given the end cells as six
integers, and the answer. Anything else (another world or move set, grown arrays, a
pause, a search that needs room) takes the general path, which also sets the short path
up for the next one.
:func:`run_points` is the short path from two points instead of two cells: a plan's two
endpoint lookups made in the same compiled call.
"""

from __future__ import annotations

import numpy as np

from planner._entry import entry_point, raw_entry_point, signal_cause
from planner.search._grow import grown
from planner.search._heap import grown_heap, new_heap
from planner.search._nodes import (
    ASTAR_STATE,
    PAGE,
    NodeTable,
    SlotMap,
    finish,
    new_nodes,
    new_slots,
    rehash,
)
from planner.search._state import new_state
from planner.search.astar._context import (
    _CAP,
    _LOCAL,
    _PCAP,
    KEEP_NODES,
    _Context,
    _Fast,
    _free_context,
    _fresh_scratch_bytes,
    _Held,
    _Memo,
    _no_sight,
    _Points,
    _release,
    _settle,
    _sight,
)
from planner.search.astar._pool import give, lazy_zeros, take
from planner.search.astar.bound import new_bound, search_bound, search_cells, search_points
from planner.search.result import RUN_BUDGET, RUN_GROW, RUN_STOPPED

__all__ = ["run", "run_points", "repeat", "DENSE_SLOT_BUDGET", "KEEP_NODES"]

#: largest dense cell -> slot array (bytes, int32 per grid cell); bigger grids use pages.
DENSE_SLOT_BUDGET = 512 * 2**20
_ROW_BYTES = sum(a.itemsize for a in (*new_nodes(1), *new_heap(1)))  # per node slot
_PAGE_BYTES = PAGE * 4 + 2 * 8 + 8  # a page of int32 slots, its 2 table entries and key
_STATE_BYTES = new_state(ASTAR_STATE).nbytes


def _dense(ctx: _Context, occ, owner) -> np.ndarray | None:
    """The dense slot array for a search of ``ctx`` on ``occ``'s grid: the one the context
    holds for it, else the pool's or a new one (None when the grid is paged or too big for
    :data:`DENSE_SLOT_BUDGET`). The context then holds it, until :func:`_unbind` of
    ``owner`` (the structs' owner, see :func:`run`); the array it held for another grid goes
    back to the pool."""
    grid = occ.grid
    h = ctx.held
    if h is not None:
        if h.grid is grid:
            return h.slots
        ctx.held = ctx.fast = None
        give(h.grid, h.slots)
    a = take(grid)
    if a is None:
        cells = int(np.prod(occ.dims))  # the occupancy grid holds one bit per cell
        if occ.mode != 0 or 4 * cells > DENSE_SLOT_BUDGET:
            return None
        a = lazy_zeros(cells)
    ctx.held = _Held(grid, a, id(owner))
    return a


def _short(ctx: _Context, f: _Fast, free: list, start, goal):
    """The short path's one compiled call, from ``start`` to ``goal`` on ``f``'s arrays.

    Returns ``(out, peak)`` as :func:`run`'s, with ``ctx`` back among the thread's ``free``
    contexts; ``peak`` is None when the search needs room or paused, and the general path
    then resumes it from ``out``.
    """
    try:
        out = f.cells(f.bound, f.first, f.pausing, *start.tolist(), *goal.tolist())
    except SystemError as exc:  # as entry_point's wrapper, which this call saves
        raise signal_cause(exc) from None  # the context, left mid-search, is dropped
    return out, _done(ctx, f, free, out)


def _done(ctx: _Context, f: _Fast, free: list, out: tuple) -> int | None:
    """The peak bytes of the short path's search that gave ``out``, with ``ctx`` back among
    the thread's ``free`` contexts; None when it needs room or paused (``ctx`` stays out)."""
    status, _, _, _, n, _ = out
    if status == RUN_GROW or (f.pausing and status == RUN_BUDGET):
        return None
    _release(ctx, free)
    return f.small if n <= _CAP else _fresh_bytes(n, 0) + f.rest


def run(occ, walk, ms, start, goal, params, span: float, owner=None, dense: bool = True,
        pause_at: int = 0, keep_going=None, tag=None):
    """Run one search to completion. ``span``: longest sight line (m) the any-angle scratch
    is sized for (0 for lattice A*).

    ``owner``: the object (the world's checker) that holds ``occ`` and ``walk``. With it the
    context keeps their :class:`Bound` for the next search on them, until the owner is
    freed; without, the next search makes it again.

    ``dense=False`` keeps the search off the pooled dense slot array (a short search run
    while another search on the same grid holds it). With ``keep_going``, ``(fn, *args)``
    with ``fn(*args, start_cell, goal_cell)`` returning bool (a tuple, not a closure: it
    is made on every call), a search still going after
    ``pause_at`` expansions pauses once and asks it whether to go on; False stops it with
    :data:`RUN_STOPPED`. Most searches are shorter and never pay for the question.

    ``tag``: an object that stands for every argument but the cells, ``owner`` and
    ``keep_going``: a caller that passes the same tag again passes the same arguments, so
    :func:`repeat` with that tag can skip comparing them.

    Returns
    -------
    out : tuple
        ``(status, cells, cost, expansions, nodes, lookups)``. ``status``: a ``RUN_*`` code
        of :mod:`planner.search.result` (never RUN_GROW; RUN_STOPPED when ``keep_going``
        said stop; RUN_BAD_START / RUN_BAD_GOAL when that end is not free, before any
        expansion); ``cells``: the (K, 3) int64 path cells from start to goal when found
        (else empty); ``cost`` (m, inf when not found); the search's counts.
    peak : int
        Bytes of the search's own arrays at their peak, as grown for this search from the
        initial capacities (the same whatever the thread searched before).
    """
    try:
        free = _LOCAL.free
    except AttributeError:
        free = _LOCAL.free = []
    k = (_ready(free, occ, walk, ms, params, owner, pause_at, keep_going)
         if dense and span <= 0 else -1)
    if k >= 0:
        # the short path (module docstring): the context's arrays, bound and dense slot
        # array are those of its last search, which was like this one
        ctx = free.pop(k)
        f = ctx.fast
        out, peak = _short(ctx, f, free, start, goal)
        if peak is not None:
            return out, peak
        out = _run(ctx, occ, walk, ms, start, goal, params, span, owner, dense, pause_at,
                   keep_going, out, tag)
    else:
        ctx = _free_context(free, occ.grid)
        out = _run(ctx, occ, walk, ms, start, goal, params, span, owner, dense, pause_at,
                   keep_going, None, tag)
    _settle(ctx, owner)
    return out


def _ready(free: list, occ, walk, ms, params, owner, pause_at: int, keep_going) -> int:
    """The index in ``free`` of the context whose last search was like this one (the same
    structs, settings and owner: :func:`run`'s short path repeats it), the most recently
    used first (a query loop's), or -1."""
    oid = id(owner)
    for k in range(len(free) - 1, -1, -1):
        f = free[k].fast
        if (f is not None and f.occ is occ and f.ms is ms and f.params is params
                and f.owner == oid and f.walk is walk and f.pause_at == pause_at
                and (keep_going is None) is f.no_probe):
            return k
    return -1


def _tagged(free: list, owner, tag) -> int:
    """The index in ``free`` of the context whose last search had ``tag`` and ``owner``
    (the most recently used first), or -1."""
    oid = id(owner)
    for k in range(len(free) - 1, -1, -1):
        f = free[k].fast
        if f is not None and f.tag is tag and f.owner == oid:
            return k
    return -1


def repeat(owner, tag, start, goal, keep_going=None):
    """:func:`run` with the arguments of this thread's last search, given by its ``tag``
    and ``owner``, between two other cells: the same answer for less than the comparison
    of every argument that :func:`run`'s short path makes. None, having done nothing, when
    this thread's last search had another tag or owner (the caller then calls
    :func:`run`, with ``tag``, which sets this up for the next call)."""
    free = getattr(_LOCAL, "free", None)
    if not free or tag is None:
        return None
    k = _tagged(free, owner, tag)
    if k < 0:
        return None
    ctx = free.pop(k)  # taken while it searches: a search started meanwhile takes another
    f = ctx.fast
    out, peak = _short(ctx, f, free, start, goal)
    if peak is not None:
        return out, peak
    out = _run(ctx, f.occ, f.walk, f.ms, start, goal, f.params, 0.0, owner, True, f.pause_at,
               keep_going, out, tag)
    _settle(ctx, owner)
    return out


def run_points(occ, walk, ms, params, owner, rounding, pts, pause_at: int = 0,
               keep_going=None):
    """:func:`run` (dense, lattice A* / Dijkstra) between the cells of two points, found in
    the same compiled call (:func:`~planner.search.astar.bound.search_points`): a plan's
    endpoint lookups and search at the cost of one call. ``rounding``: ``(kind, a, b,
    ginv, reach)`` of :meth:`planner.lattice.Lattice.point_rounding`; ``pts``: the two
    points' coordinates ``(x0, x1, x2, y0, y1, y2)`` (m, Python floats).

    Returns :func:`run`'s ``(out, peak)`` (``out``'s status RUN_BAD_START or RUN_BAD_GOAL, and
    nothing searched, when that cell is out of bounds or blocked or a point past
    ``reach``), or None when this
    thread's context did not last run a search like this one (only :func:`run`'s short path
    takes points): the caller then looks the cells up and calls :func:`run`, which sets the
    short path up for the next call."""
    free = getattr(_LOCAL, "free", None)
    if not free:
        return None
    k = _ready(free, occ, walk, ms, params, owner, pause_at, keep_going)
    if k < 0:
        return None
    ctx = free[k]
    f = ctx.fast
    _, _, _, ginv, _ = rounding
    p = ctx.points
    if p is not None and p.search is f.search and p.ginv is ginv:
        call = p.call
    else:  # one search_points per compiled search_bound (its argument types) and rounding
        key = (f.search, id(ginv))
        held, call = _POINTS.get(key, (None, None))
        if held is not ginv:
            if len(_POINTS) >= 256:
                _POINTS.clear()
            call = entry_point(search_points, (f.bound, f.first, f.pausing, *rounding, *pts))
            _POINTS[key] = (ginv, call)  # holds the array: its id stays its own
        ctx.points = _Points(f.search, ginv, call)  # no world's arrays: none outlives a world
    free.pop(k)
    out = call(f.bound, f.first, f.pausing, *rounding, *pts)
    peak = _done(ctx, f, free, out)
    if peak is not None:
        return out, peak
    # it needs room or paused: go on as run does (the cells are in the context's ends)
    out = _run(ctx, occ, walk, ms, None, None, params, 0.0, owner, True, pause_at, keep_going,
               out)
    _settle(ctx, owner)
    return out


#: (a compiled search_bound, id of a rounding's ginv) -> (ginv, its search_points)
_POINTS: dict[tuple, tuple] = {}


def _run(ctx, occ, walk, ms, start, goal, params, span, owner, dense, pause_at, keep_going,
         out=None, tag=None):
    """:func:`run`'s general path; ``out``: the kernel's answer to the short path's call
    (a request for room or a pause) when it started there. Also sets the short path up for
    the next search when this one may take it."""
    if out is None:
        ctx.end0[...] = start
        ctx.end1[...] = goal
    nos = _no_sight()
    sc = _sight(ctx, walk, span) if span > 0 else nos
    nu = len(ms.union)
    if nu > len(ctx.ufree):
        ctx.ufree = np.empty(nu, np.bool_)
        ctx.forget()  # the kept bounds hold the old array
    dslot = _dense(ctx, occ, owner) if dense else None
    first = params
    if keep_going is not None and pause_at > 0 and not 0 < params.max_expansions <= pause_at:
        first = _paused(params, pause_at)
    pausing = first is not params
    out = _loop(ctx, occ, walk, ms, sc, dslot, first, pausing, out)
    status, *_ = out
    if pausing and status == RUN_BUDGET:
        ask, *args = keep_going
        if ask(*args, ctx.end0.copy(), ctx.end1.copy()):
            out = _loop(ctx, occ, walk, ms, sc, dslot, params, False)
        else:
            nodes, state, slots = ctx.nodes, ctx.state, _slots(ctx, occ, dslot)
            out = (RUN_STOPPED, *_helper(finish, nodes, slots, state, False)(
                nodes, slots, state, False))
    _, _, _, _, n, _ = out
    # finish cleared the touched cells of the dense array (the context keeps it for reuse)
    # and zeroed the state's page count: the paged map's bytes are those of _PCAP pages
    rest = (0 if dslot is None else dslot.nbytes) + max(nu, 64) + _STATE_BYTES
    rest += 0 if sc is nos else _fresh_scratch_bytes(walk, span)
    if len(ctx.nodes.key) > KEEP_NODES or len(ctx.slots.bkeys) > KEEP_NODES // 8:
        ctx.keep(0 if dslot is None else dslot.nbytes)
    bd = ctx.bound
    if bd is not None and owner is not None and sc is nos and dense and bd.params is first:
        ctx.fast = _Fast(occ, ms, params, id(owner), walk, pause_at, keep_going is None,
                         bd.bound, bd.search, first, pausing, _fresh_bytes(0, 0) + rest, rest,
                         bd.cells, tag)
    else:
        ctx.fast = None
    return out, _fresh_bytes(n, 0) + rest


_PAUSED: dict[tuple, tuple] = {}


def _paused(params, pause_at: int):
    """``params`` stopping at ``pause_at`` expansions (remembered: made once per settings
    object; keyed by identity, since hashing the settings costs more than the lookup)."""
    hit = _PAUSED.get((id(params), pause_at))
    if hit is not None:
        held, paused = hit
        if held is params:
            return paused
    if len(_PAUSED) >= 256:
        _PAUSED.clear()
    p = params._replace(max_expansions=pause_at)
    _PAUSED[(id(params), pause_at)] = (params, p)  # holds params: its id stays its own
    return p


def _fresh_bytes(n: int, npg: int) -> int:
    """Bytes of the node table, heap and paged slot map as this search alone would have grown
    them from the initial capacities (``n`` nodes, ``npg`` pages): the arrays it ran in may
    be larger, kept from an earlier search on the thread, and a search's reported memory
    must not depend on what ran before it."""
    cap = _CAP if n <= _CAP else 1 << (n - 1).bit_length()
    pcap = _PCAP if npg <= _PCAP else 1 << (npg - 1).bit_length()
    return cap * _ROW_BYTES + pcap * _PAGE_BYTES


# Compiled entry points (planner._entry): the kernel's per Bound type and parameter types,
# and the helpers, whose arguments the driver alone builds.
_HELPERS: dict[object, object] = {}
_NO_DENSE = new_slots(1).dense  # the paged slot map's placeholder dense array
#: (Bound type, params' field types) -> (search_bound, search_cells)
_CALLS: dict[object, tuple] = {}


def _bound(ctx: _Context, occ, walk, ms, sc, dslot, params):
    """``(b, f)``: the context's :class:`Bound` of these structs and its arrays, and ``f``
    the compiled :func:`search_bound` for its type and ``params``'s field types. Made again
    only when none of the context's kept bounds is of these objects (another world or move
    set than the last :data:`~planner.search.astar._context.BOUNDS_KEPT`, grown arrays)."""
    dense = _NO_DENSE if dslot is None else dslot
    bd = ctx.bound
    if bd is None or not bd.made_of(occ, walk, ms, sc, dense, ctx.nodes, ctx.slots,
                                    ctx.ufree):
        bd = ctx.recall(occ, walk, ms, sc, dense)
    if bd is not None:
        ctx.bound = bd
        if bd.params is params:  # the same settings object: no need to compare their types
            return bd.bound, bd.search
        ptypes = tuple(map(type, params))  # the entry point takes exactly these
        if bd.ptypes == ptypes:
            bd.params = params
            return bd.bound, bd.search
    else:
        ptypes = tuple(map(type, params))
    b = new_bound(occ, walk, ms, ctx.nodes, ctx.heap, _slots(ctx, occ, dslot), sc, ctx.ufree,
                  ctx.ends, ctx.state)
    key = (b._type, ptypes)
    calls = _CALLS.get(key)
    if calls is None:
        calls = _CALLS[key] = (entry_point(search_bound, (b, params, False)),
                               raw_entry_point(search_cells, (b, params, False, 0, 0, 0, 0,
                                                              0, 0)))
    search, cells = calls
    ctx.remember(_Memo(occ, walk, ms, sc, dense, ctx.nodes, ctx.slots, ctx.ufree, params,
                       ptypes, b, search, cells))
    return b, search


def _slots(ctx: _Context, occ, dslot) -> SlotMap:
    """The context's slot map, on the dense slot array ``dslot`` of ``occ``'s box when one
    was taken."""
    return ctx.slots if dslot is None else ctx.slots._replace(dense=dslot, lo=occ.lo,
                                                              dims=occ.dims)


def _helper(disp, *args):
    """The compiled ``disp`` (finish) for the driver's argument types."""
    k = _HELPERS.get(disp)
    if k is None:
        k = _HELPERS[disp] = entry_point(disp, args)
    return k


def _loop(ctx: _Context, occ, walk, ms, sc, dslot, params, pausing, out=None):
    """Call the kernel until it stops asking for room, growing the context's arrays; returns
    the kernel's answer (:func:`planner.search.astar.kernel.search_call`). ``out``: its
    answer to a call already made."""
    nm = len(ms.moves)
    while True:
        if out is None:
            b, call = _bound(ctx, occ, walk, ms, sc, dslot, params)
            out = call(b, params, pausing)
        status, *_ = out
        if status != RUN_GROW:
            return out
        out = None
        ctx.forget()  # the arrays grow: every kept bound (and the short path's) is stale
        state, nodes, slots = ctx.state, ctx.nodes, ctx.slots
        n, npg = int(state[0]["nodes"]), int(state[0]["pages"])
        cap, pcap = len(nodes.key), len(slots.bkeys)
        if n + nm > cap:
            cap *= 2
            ctx.nodes = NodeTable(*(grown(a, cap, n) for a in nodes))
            ctx.heap = grown_heap(ctx.heap, cap, n)
        if npg + nm > pcap or 2 * (npg + nm) > len(slots.btab):
            pcap *= 2
            ctx.slots = SlotMap(grown(slots.pages, pcap * PAGE, npg * PAGE),
                                np.full(2 * pcap, -1, np.int64), grown(slots.bkeys, pcap, npg),
                                slots.dense, slots.lo, slots.dims)
            rehash(ctx.slots, npg)
