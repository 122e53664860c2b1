"""Python driver of the resumable search kernel: keeps each thread's kernel arrays between
searches, grows them when the kernel asks, and traces the path.

A search's fixed cost is what it pays outside the expansions, so nothing here is allocated
per call: each thread keeps a :class:`_Context` (node table, heap, paged slot map, state,
scratch) whose arrays the next search on that thread reuses, and a dense grid's cell -> slot
array is pooled per grid. Arrays grown past :data:`KEEP_NODES` for a long search are dropped
afterwards, so an idle thread never holds more than a short search's memory.
"""

from __future__ import annotations

import mmap
import threading
import weakref

import numpy as np

from planner.lattice import Lattice
from planner.occupancy.walk import walk_of
from planner.search._entry import entry_point, struct_key
from planner.search._grow import grown
from planner.search._heap import Heap, new_heap
from planner.search._los import new_scratch
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
from planner.search.astar import kernel as _astar
from planner.search.result import RUN_BUDGET, RUN_FOUND, RUN_GROW, RUN_STOPPED

__all__ = ["run", "DENSE_SLOT_BUDGET", "KEEP_NODES"]

#: largest dense cell -> slot array (bytes, int32 per grid cell); bigger grids use pages.
DENSE_SLOT_BUDGET = 512 * 2**20
#: node capacity a thread keeps between searches (larger arrays are dropped after use)
KEEP_NODES = 1 << 16
_CAP, _PCAP = 4096, 64  # initial node and page capacity

# One dense slot array per dense occupancy grid, reused across searches (cleared after each
# search at the cells it touched, so a search never pays for the whole box). Taken out of
# the pool while a search uses it: concurrent searches on one world get their own.
_POOL: dict[int, np.ndarray] = {}
_LOCK = threading.Lock()
_WATCHED: set[int] = set()


class _Context:
    """One thread's kernel arrays, reused by its next search (module docstring)."""

    __slots__ = ("nodes", "heap", "slots", "state", "ufree", "ends", "sc", "sc_key")

    def __init__(self):
        self.nodes = new_nodes(_CAP)
        self.heap = new_heap(_CAP)
        self.slots = new_slots(_PCAP)
        self.state = new_state(ASTAR_STATE)
        self.ufree = np.empty(64, np.bool_)
        self.ends = np.empty((2, 3), np.int64)
        self.sc = _no_sight()
        self.sc_key = None

    def keep(self, nodes, heap, slots) -> None:
        """Keep the arrays a search grew, up to the kept size (module docstring)."""
        if len(nodes.key) > KEEP_NODES:
            nodes, heap = new_nodes(_CAP), new_heap(_CAP)
        if len(slots.bkeys) > KEEP_NODES // 8:
            slots = new_slots(_PCAP)
        self.nodes, self.heap, self.slots = nodes, heap, SlotMap(*slots[:3], *self.slots[3:])


_LOCAL = threading.local()


def _context() -> _Context:
    """This thread's free context (a new one when a search is already running on it, e.g.
    the goal probe inside a paused search)."""
    free = getattr(_LOCAL, "free", None)
    if free is None:
        free = _LOCAL.free = []
    return free.pop() if free else _Context()


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
    if span <= 0 or np.array_equal(walk.g, walk.g[0, 0] * np.eye(3)):
        return _no_sight()  # cubic sight lines need no scratch
    key = (id(walk), span)
    if ctx.sc_key != key:
        ctx.sc, ctx.sc_key = new_scratch(span, walk), key
    return ctx.sc


def _take_dense(occ) -> np.ndarray | None:
    key = id(occ.grid)
    with _LOCK:
        a = _POOL.pop(key, None)
    if a is not None:
        return a
    cells = int(np.prod(occ.dims))  # the occupancy grid holds one bit per cell
    if occ.mode != 0 or 4 * cells > DENSE_SLOT_BUDGET:
        return None
    return _lazy_zeros(cells)


def _lazy_zeros(n: int) -> np.ndarray:
    """``np.zeros(n, np.int32)`` whose pages the OS zeroes on first touch, 4 KiB at a time.

    numpy asks for transparent huge pages on large arrays; a search touches a few scattered
    cells of the box, and each touch then makes the kernel zero a whole 2 MiB page (the first
    FCC query on a 256^3 box: 1.5 s instead of 0.01 s, and the whole array resident). An
    anonymous mapping without that advice is zeroed per small page, where it is touched."""
    nbytes = 4 * n
    if nbytes < 1 << 22:
        return np.zeros(n, np.int32)
    mm = mmap.mmap(-1, nbytes)
    if hasattr(mmap, "MADV_NOHUGEPAGE"):  # also when the system default is "always"
        mm.madvise(mmap.MADV_NOHUGEPAGE)
    return np.frombuffer(mm, dtype=np.int32)  # keeps the mapping alive; writable, aligned


def _forget(key: int) -> None:
    with _LOCK:
        _POOL.pop(key, None)
        _WATCHED.discard(key)


def _give_dense(occ, a: np.ndarray) -> None:
    """Return a cleared dense slot array to the pool (dropped when the grid is freed)."""
    key = id(occ.grid)
    with _LOCK:
        _POOL[key] = a
        new = key not in _WATCHED
        _WATCHED.add(key)
    if new:
        weakref.finalize(occ.grid, _forget, key)


def run(occ, walk, ms, start, goal, params, span: float, *, dense: bool = True,
        pause_at: int = 0, keep_going=None):
    """Run one search to completion. ``span``: longest sight line (m) the any-angle scratch
    is sized for (0 for lattice A*).

    ``dense=False`` keeps the search off the pooled dense slot array (a short search run
    while another search on the same grid holds it). With ``keep_going`` (a callable
    returning bool), a search still going after ``pause_at`` expansions pauses once and
    asks it whether to go on; False stops it with :data:`RUN_STOPPED`. Most searches are
    shorter and never pay for the question.

    Returns
    -------
    status : int
        A ``RUN_*`` code of :mod:`planner.search.result` (never RUN_GROW; RUN_STOPPED
        when ``keep_going`` said stop; RUN_BAD_START / RUN_BAD_GOAL when that end is not
        free, before any expansion).
    cells : ndarray (K, 3) int64 or None
        Path cells from start to goal when found.
    cost : float
    counts : tuple of int
        ``(expansions, nodes, lookups)`` of the search.
    peak : int
        Bytes of the search's own arrays at their peak, as grown for this search from the
        initial capacities (the same whatever the thread searched before).
    """
    ctx = _context()
    out = _run(ctx, occ, walk, ms, start, goal, params, span, dense, pause_at, keep_going)
    _release(ctx)  # not after an exception: a context left mid-search is dropped
    return out


def _run(ctx, occ, walk, ms, start, goal, params, span, dense, pause_at, keep_going):
    ends = ctx.ends
    ends[0] = start
    ends[1] = goal
    sc = _sight(ctx, walk, span) if span > 0 else _no_sight()
    ufree = ctx.ufree if len(ms.union) <= len(ctx.ufree) else np.empty(len(ms.union), bool)
    dslot = _take_dense(occ) if dense else None
    slots = ctx.slots if dslot is None else SlotMap(*ctx.slots[:3], dslot, occ.lo, occ.dims)
    first = params
    if keep_going is not None and pause_at > 0 and not 0 < params.max_expansions <= pause_at:
        first = params._replace(max_expansions=pause_at)
    nodes, heap, state = ctx.nodes, ctx.heap, ctx.state
    kernel = _kernel(occ, walk, ms, nodes, heap, slots, sc, ufree, params, ends, state, False)
    nodes, heap, slots, out = _loop(kernel, occ, walk, ms, nodes, heap, slots, sc, ufree,
                                    first, ends, state, first is not params)
    if first is not params and out[0] == RUN_BUDGET:
        if keep_going():
            nodes, heap, slots, out = _loop(kernel, occ, walk, ms, nodes, heap, slots, sc,
                                            ufree, params, ends, state, False)
        else:
            out = (RUN_STOPPED, *_helper(finish, nodes, slots, state, False)(
                nodes, slots, state, False))
    status, path, cost, exp, n, look = out
    if dslot is not None:  # finish cleared the touched cells: reuse the array
        _give_dense(occ, dslot)
    peak = _fresh_bytes(n, int(state[0]["pages"]), nodes, heap, slots) + ufree.nbytes
    peak += state.nbytes + (0 if sc is _no_sight() else _nbytes(sc))
    peak += 0 if dslot is None else dslot.nbytes
    if nodes is not ctx.nodes or slots.pages is not ctx.slots.pages:
        ctx.keep(nodes, heap, slots)
    return status, (path if status == RUN_FOUND else None), cost, (exp, n, look), peak


def _fresh_bytes(n: int, npg: int, nodes, heap, slots) -> int:
    """Bytes of the node table, heap and paged slot map as this search alone would have grown
    them from the initial capacities (``n`` nodes, ``npg`` pages): the arrays it ran in may
    be larger, kept from an earlier search on the thread, and a search's reported memory
    must not depend on what ran before it."""
    cap, pcap = _CAP, _PCAP
    while cap < n:
        cap *= 2
    while pcap < npg:
        pcap *= 2
    row = sum(a.itemsize for a in nodes) + sum(a.itemsize for a in heap)
    page = PAGE * slots.pages.itemsize + 2 * slots.btab.itemsize + slots.bkeys.itemsize
    return cap * row + pcap * page


def _nbytes(struct) -> int:
    n = 0
    for a in struct:
        n += a.nbytes
    return n


# Compiled entry points (planner.search._entry): the kernel's per world struct types, and
# the helpers, whose arguments the driver alone builds.
_KERNELS: dict[tuple, object] = {}
_HELPERS: dict[object, object] = {}


_LAST: list = [(lambda: None, None, None)]  # (grid ref, walk, kernel) of the last search


def _kernel(occ, walk, *args):
    """The compiled search kernel for these arguments. The driver builds all but the
    world's structs ``occ`` and ``walk`` (and ``params``, of Python ints), always of the same
    types; the last world's are remembered by identity (its occupancy grid by a weak
    reference: a dropped world is not kept alive)."""
    grid, w, k = _LAST[0]  # one tuple, replaced whole: threads never see a mixed one
    if grid() is occ.grid and w is walk:
        return k
    key = (struct_key(occ), struct_key(walk), struct_key(args[-4]))
    k = _KERNELS.get(key)
    if k is None:
        k = _KERNELS[key] = entry_point(_astar.search_call, (occ, walk, *args))
    _LAST[0] = (weakref.ref(occ.grid), walk, k)
    return k


def _helper(disp, *args):
    """The compiled ``disp`` (finish) for the driver's argument types."""
    k = _HELPERS.get(disp)
    if k is None:
        k = _HELPERS[disp] = entry_point(disp, args)
    return k


def _loop(kernel, occ, walk, ms, nodes, heap, slots, sc, ufree, params, ends, state,
          pausing):
    """Call the kernel until it stops asking for room; returns the final structs and the
    kernel's answer (:func:`planner.search.astar.kernel.search_call`)."""
    nm = len(ms.moves)
    while True:
        out = kernel(occ, walk, ms, nodes, heap, slots, sc, ufree, params, ends, state,
                     pausing)
        if out[0] != RUN_GROW:
            break
        n, npg = int(state[0]["nodes"]), int(state[0]["pages"])
        cap, pcap = len(nodes.key), len(slots.bkeys)
        if n + nm > cap:
            cap *= 2
            nodes = NodeTable(*(grown(a, cap, n) for a in nodes))
            heap = Heap(*(grown(a, cap, n) for a in heap))
        if npg + nm > pcap or 2 * (npg + nm) > len(slots.btab):
            pcap *= 2
            slots = SlotMap(grown(slots.pages, pcap * PAGE, npg * PAGE),
                            np.full(2 * pcap, -1, np.int64), grown(slots.bkeys, pcap, npg),
                            *slots[3:])
            rehash(slots, npg)
    return nodes, heap, slots, out
