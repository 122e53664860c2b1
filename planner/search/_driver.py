"""Python driver of the resumable search kernel: allocates the structs, grows them when the
kernel asks, and traces the path."""

from __future__ import annotations

import math

import numpy as np

from planner.search import _astar
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
    new_nodes,
    new_slots,
    rehash,
    trace_path,
)


def _grown(a: np.ndarray, size: int, keep: int) -> np.ndarray:
    b = np.empty(size, a.dtype)
    b[:keep] = a[:keep]
    return b


def run(occ, walk, ms, start, goal, params, span: float, cap: int = 4096):
    """Run one search to completion. ``span``: longest sight line (m) the any-angle scratch
    is sized for (0 for lattice A*).

    Returns
    -------
    status : int
        ``_astar.RUN_*`` (never RUN_GROW).
    keys : ndarray (K,) int64 or None
        Packed path cells when found.
    cost : float
    st : ndarray (ST_SIZE,) int64
        Final kernel state (counts).
    peak : int
        Bytes of the search's own arrays at the end (their peak: they only grow).
    """
    nodes = new_nodes(cap)
    heap = new_heap(cap)
    pcap = 64  # pages of the cell -> node slot map
    slots = new_slots(pcap)
    st = np.zeros(ST_SIZE, np.int64)
    sc = new_scratch(span, walk)
    ufree = np.empty(len(ms.union), np.bool_)
    nm = len(ms.moves)
    _astar.search_init(start, goal, ms, walk.g, nodes, heap, slots, st)
    while True:
        status = _astar.search_run(occ, walk, ms, nodes, heap, slots, sc, ufree, params, goal,
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
                            np.full(2 * pcap, -1, np.int64), _grown(slots.bkeys, pcap, npg))
            rehash(slots, npg)
    peak = sum(a.nbytes for part in (nodes, heap, slots, sc) for a in part) + ufree.nbytes
    peak += st.nbytes
    if status != _astar.RUN_FOUND:
        return status, None, math.inf, st, peak
    gs = int(st[ST_GOAL])
    return status, trace_path(nodes, gs), float(nodes.g[gs]), st, peak


__all__ = ["run", "ST_EXP"]
