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
from planner.search._heap import Heap, new_heap
from planner.search._los import new_scratch
from planner.search._nodes import (
    PAGE,
    ST_EXP,
    ST_GOAL,
    ST_N,
    ST_NP,
    ST_SIZE,
    NodeTable,
    SlotMap,
    clear_dense,
    new_nodes,
    new_slots,
    rehash,
    trace_path,
)
from planner.search.astar import kernel as _astar


def _grown(a: np.ndarray, size: int, keep: int) -> np.ndarray:
    b = np.empty(size, a.dtype)
    b[:keep] = a[:keep]
    return b


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


#: status of a search that ``keep_going`` stopped at its pause (not an ``_astar`` status)
RUN_STOPPED = 5


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
        ``_astar.RUN_*`` (never RUN_GROW), or :data:`RUN_STOPPED`.
    cells : ndarray (K, 3) int64 or None
        Path cells from start to goal when found.
    cost : float
    st : ndarray (ST_SIZE,) int64
        Final kernel state (counts).
    peak : int
        Bytes of the search's own arrays at the end (their peak: they only grow).
    """
    nodes = new_nodes(cap)
    heap = new_heap(cap)
    pcap = 64  # pages of the cell -> node slot map
    dense = _take_dense(occ) if dense else None
    slots = new_slots(pcap) if dense is None else new_slots(pcap, dense, occ.lo, occ.dims)
    st = np.zeros(ST_SIZE, np.int64)
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
    parts = _loop(occ, walk, ms, nodes, heap, slots, sc, ufree, first, ends, st, cap, pcap)
    nodes, heap, slots, status = parts
    if first is not params and status == _astar.RUN_BUDGET:
        if keep_going():
            parts = _loop(occ, walk, ms, nodes, heap, slots, sc, ufree, params, ends, st,
                          len(nodes.key), len(slots.bkeys))
            nodes, heap, slots, status = parts
        else:
            status = RUN_STOPPED
    peak = _nbytes(nodes) + _nbytes(heap) + _nbytes(slots) + _nbytes(sc) + ufree.nbytes
    peak += st.nbytes
    path = None
    if status == _astar.RUN_FOUND:
        gs = int(st[ST_GOAL])
        path, cost = trace_path(nodes, gs), float(nodes.g[gs])
    if dense is not None:  # every touched cell holds a node: clear those, reuse the array
        clear_dense(slots, nodes.key, int(st[ST_N]))
        _give_dense(occ, dense)
    if path is None:
        return status, None, math.inf, st, peak
    return status, path, cost, st, peak


def _nbytes(struct) -> int:
    n = 0
    for a in struct:
        n += a.nbytes
    return n


def _loop(occ, walk, ms, nodes, heap, slots, sc, ufree, params, ends, st, cap, pcap):
    """Call the kernel until it stops asking for room; returns the final structs and
    status."""
    nm = len(ms.moves)
    while True:
        status = _astar.search_run(occ, walk, ms, nodes, heap, slots, sc, ufree, params, ends,
                                   st)
        if status != _astar.RUN_GROW:
            break
        n, npg = int(st[ST_N]), int(st[ST_NP])
        if n + nm > cap:
            cap *= 2
            nodes = NodeTable(*(_grown(a, cap, n) for a in nodes))
            heap = Heap(*(_grown(a, cap, n) for a in heap))
        if npg + nm > pcap or 2 * (npg + nm) > len(slots.btab):
            pcap *= 2
            slots = SlotMap(_grown(slots.pages, pcap * PAGE, npg * PAGE),
                            np.full(2 * pcap, -1, np.int64), _grown(slots.bkeys, pcap, npg),
                            *slots[3:])
            rehash(slots, npg)
    return nodes, heap, slots, status


__all__ = ["run", "ST_EXP", "RUN_STOPPED"]
