"""Python driver of the resumable search kernel: allocates the structs, grows them when the
kernel asks, and traces the path."""

from __future__ import annotations

import math
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
    clear_dense,
    new_nodes,
    new_slots,
    rehash,
    trace_path,
)
from planner.search._state import new_state
from planner.search.astar import kernel as _astar
from planner.search.result import RUN_BUDGET, RUN_FOUND, RUN_GROW, RUN_STOPPED

#: largest dense cell -> slot array (bytes, int32 per grid cell); bigger grids use pages.
DENSE_SLOT_BUDGET = 512 * 2**20

# One dense slot array per dense occupancy grid, reused across searches (cleared after each
# search at the cells it touched, so a search never pays for the whole box). Taken out of
# the pool while a search uses it: concurrent searches on one world get their own.
_POOL: dict[int, np.ndarray] = {}
_LOCK = threading.Lock()


_NO_SIGHT: list = []


def _no_sight():
    """A tiny sight scratch for lattice A* / Dijkstra (they never walk): allocated once."""
    if not _NO_SIGHT:
        _NO_SIGHT.append(new_scratch(0.0, walk_of(Lattice.named("cubic", 1.0))))
    return _NO_SIGHT[0]


def _take_dense(occ) -> np.ndarray | None:
    cells = int(np.prod(occ.dims))  # the occupancy grid holds one bit per cell
    if occ.mode != 0 or 4 * cells > DENSE_SLOT_BUDGET:
        return None
    key = id(occ.grid)
    with _LOCK:
        a = _POOL.pop(key, None)
    if a is None:
        a = _lazy_zeros(cells)
    return a


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


_WATCHED: set[int] = set()


def _give_dense(occ, a: np.ndarray) -> None:
    """Return a cleared dense slot array to the pool (dropped when the grid is freed)."""
    key = id(occ.grid)
    with _LOCK:
        _POOL[key] = a
        new = key not in _WATCHED
        _WATCHED.add(key)
    if new:
        weakref.finalize(occ.grid, _forget, key)


def run(occ, walk, ms, start, goal, params, span: float, cap: int = 4096, *,
        dense: bool = True, pause_at: int = 0, keep_going=None):
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
        when ``keep_going`` said stop).
    cells : ndarray (K, 3) int64 or None
        Path cells from start to goal when found.
    cost : float
    st : numpy record (``planner.search._nodes.ASTAR_STATE``)
        Final kernel state (counts).
    peak : int
        Bytes of the search's own arrays at the end (their peak: they only grow).
    """
    nodes = new_nodes(cap)
    heap = new_heap(cap)
    pcap = 64  # pages of the cell -> node slot map
    dense = _take_dense(occ) if dense else None
    slots = new_slots(pcap) if dense is None else new_slots(pcap, dense, occ.lo, occ.dims)
    state = new_state(ASTAR_STATE)
    # The walk scratch serves the generic line of sight; cubic sight lines need none.
    if span > 0 and not np.array_equal(walk.g, walk.g[0, 0] * np.eye(3)):
        sc = new_scratch(span, walk)
    else:
        sc = _no_sight()
    ufree = np.empty(len(ms.union), np.bool_)
    ends = np.empty((2, 3), np.int64)
    ends[0], ends[1] = start, goal
    first = params
    if keep_going is not None and pause_at > 0 and not 0 < params.max_expansions <= pause_at:
        first = params._replace(max_expansions=pause_at)
    kernel = _kernel(occ, walk, ms, nodes, heap, slots, sc, ufree, params, ends, state)
    parts = _loop(kernel, occ, walk, ms, nodes, heap, slots, sc, ufree, first, ends, state,
                  cap, pcap)
    nodes, heap, slots, status = parts
    if first is not params and status == RUN_BUDGET:
        if keep_going():
            parts = _loop(kernel, occ, walk, ms, nodes, heap, slots, sc, ufree, params, ends,
                          state, len(nodes.key), len(slots.bkeys))
            nodes, heap, slots, status = parts
        else:
            status = RUN_STOPPED
    peak = _nbytes(nodes) + _nbytes(heap) + _nbytes(slots) + _nbytes(sc) + ufree.nbytes
    peak += state.nbytes
    st = state[0]
    path = None
    if status == RUN_FOUND:
        gs = int(st["goal"])
        path, cost = _helper(trace_path, nodes, gs)(nodes, gs), float(nodes.g[gs])
    if dense is not None:  # every touched cell holds a node: clear those, reuse the array
        n = int(st["nodes"])
        _helper(clear_dense, slots, nodes.key, n)(slots, nodes.key, n)
        _give_dense(occ, dense)
    if path is None:
        return status, None, math.inf, st, peak
    return status, path, cost, st, peak


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
    key = (struct_key(occ), struct_key(walk), struct_key(args[-3]))
    k = _KERNELS.get(key)
    if k is None:
        k = _KERNELS[key] = entry_point(_astar.search_run, (occ, walk, *args))
    _LAST[0] = (weakref.ref(occ.grid), walk, k)
    return k


def _helper(disp, *args):
    """The compiled ``disp`` (trace_path, clear_dense) for the driver's argument types."""
    k = _HELPERS.get(disp)
    if k is None:
        k = _HELPERS[disp] = entry_point(disp, args)
    return k


def _loop(kernel, occ, walk, ms, nodes, heap, slots, sc, ufree, params, ends, state, cap,
          pcap):
    """Call the kernel until it stops asking for room; returns the final structs and
    status."""
    nm = len(ms.moves)
    while True:
        status = kernel(occ, walk, ms, nodes, heap, slots, sc, ufree, params, ends, state)
        if status != RUN_GROW:
            break
        n, npg = int(state[0]["nodes"]), int(state[0]["pages"])
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
    return nodes, heap, slots, status


__all__ = ["run", "DENSE_SLOT_BUDGET"]
