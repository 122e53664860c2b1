"""The search's node table and its cell -> node slot map (numba kernels and their structs).

Node slots are dense integers in creation order; :class:`NodeTable` holds one row per slot.
The slot map (:class:`SlotMap`) finds a cell's slot: pages of ``PAGE`` int32 slots, one per
touched ``PB x PB x PB`` block of cells, found through a small open-addressing table of block
keys. Neighbouring cells share a page, so a lookup is usually a cached-page hit plus one
nearby load: memory stays proportional to the region the search touches, with near-dense
locality.

On a dense occupancy grid whose box fits ``planner.search.astar.driver.DENSE_SLOT_BUDGET`` the
map is instead one int32 per grid cell (``SlotMap.dense``, one load per lookup), reused
across the searches on that grid and cleared at the touched cells after each (:func:`finish`).

Both are fixed-size inside the kernels; the driver (:func:`planner.search.astar.driver.run`)
doubles them when a kernel asks (``RUN_GROW``).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from planner._numba import njit_cached
from planner.occupancy.keys import mix64, pack3, unpack3
from planner.search._state import state_dtype

_EMPTY = -1

#: the A* family's kernel state (:mod:`planner.search._state`): the common counters and the
#: pages of the paged slot map in use
ASTAR_STATE = state_dtype("pages")

PB_SHIFT = 2
PB_MASK = (1 << PB_SHIFT) - 1
PAGE = 1 << (3 * PB_SHIFT)

#: bytes per node of the node table and heap (8 eight-byte fields) plus the slot map's share
#: (a page of int32 per block, pages about 1/4 full) and the x2 of array doubling.
BYTES_PER_NODE = 2 * (8 * 8 + 16)


class NodeTable(NamedTuple):
    """One row per node slot (capacity ``len(key)``)."""

    key: np.ndarray  # (cap,) int64 packed cell
    g: np.ndarray  # (cap,) float64 cost from the start (m)
    h: np.ndarray  # (cap,) float64 heuristic to the goal (m)
    par: np.ndarray  # (cap,) int64 parent slot (the start is its own parent)
    pos: np.ndarray  # (cap,) int64 heap position, -1 closed, -2 generated but not queued


class SlotMap(NamedTuple):
    """Cell -> node slot map (module docstring). With a dense occupancy grid that fits the
    slot budget, ``dense`` holds one slot per grid cell instead (same box ``lo``, ``dims``
    as the grid) and the pages stay unused: one load per lookup."""

    pages: np.ndarray  # (P * PAGE,) int32 node slot per cell of each page, -1 none
    btab: np.ndarray  # (T,) int64 open-addressing table block key -> page, -1 empty
    bkeys: np.ndarray  # (P,) int64 block key of each page
    dense: np.ndarray  # (prod(dims),) int32 slot + 1 per cell, 0 none; (1,) when paged
    lo: np.ndarray  # (3,) int64 lowest index of the dense box
    dims: np.ndarray  # (3,) int64 dense box size


def new_nodes(cap: int) -> NodeTable:
    f8, i8 = np.float64, np.int64
    return NodeTable(np.empty(cap, i8), np.empty(cap, f8), np.empty(cap, f8),
                     np.empty(cap, i8), np.empty(cap, i8))


_NO_DENSE = np.zeros(1, np.int32)
_ZERO3 = np.zeros(3, np.int64)


def new_slots(pcap: int, dense: np.ndarray | None = None, lo: np.ndarray | None = None,
              dims: np.ndarray | None = None) -> SlotMap:
    """Paged slot map with ``pcap`` pages, or dense over the box ``lo``, ``dims`` when
    ``dense`` (all 0: it stores slot + 1, so a fresh array is ``np.zeros``, whose pages the
    OS supplies zeroed on first touch instead of a fill of the whole box) is given."""
    if dense is None:
        dense, lo, dims = _NO_DENSE, _ZERO3, _ZERO3
    return SlotMap(np.empty(pcap * PAGE, np.int32), np.full(2 * pcap, _EMPTY, np.int64),
                   np.empty(pcap, np.int64), dense, lo, dims)


@njit_cached(_nrt=False)
def dense_index(sm, v0, v1, v2):  # pragma: no cover - compiled
    """Index of cell v in the dense slot array (the caller knows v is in the box)."""
    return ((v0 - sm.lo[0]) * sm.dims[1] + (v1 - sm.lo[1])) * sm.dims[2] + (v2 - sm.lo[2])


@njit_cached(_nrt=False)
def local(v0, v1, v2):  # pragma: no cover - compiled
    """Index of a cell inside its page."""
    return ((v0 & PB_MASK) << (2 * PB_SHIFT)) | ((v1 & PB_MASK) << PB_SHIFT) | (v2 & PB_MASK)


@njit_cached(_nrt=False)
def block_key(v0, v1, v2):  # pragma: no cover - compiled
    return pack3(v0 >> PB_SHIFT, v1 >> PB_SHIFT, v2 >> PB_SHIFT)


@njit_cached
def find_slot(sm, v0, v1, v2):  # pragma: no cover - compiled
    """Node slot of cell (v0, v1, v2), or -1 when the search has not generated it."""
    if sm.dense.shape[0] > 1:
        a, b, c = v0 - sm.lo[0], v1 - sm.lo[1], v2 - sm.lo[2]
        if a < 0 or b < 0 or c < 0 or a >= sm.dims[0] or b >= sm.dims[1] or c >= sm.dims[2]:
            return _EMPTY
        return np.int64(sm.dense[(a * sm.dims[1] + b) * sm.dims[2] + c]) - 1
    btab, bkeys = sm.btab, sm.bkeys
    bmask = btab.shape[0] - 1
    bk = block_key(v0, v1, v2)
    p = mix64(bk) & bmask
    while True:
        q = btab[p]
        if q == _EMPTY:
            return _EMPTY
        if bkeys[q] == bk:
            return np.int64(sm.pages[q * PAGE + local(v0, v1, v2)])
        p = (p + 1) & bmask


@njit_cached(_nrt=False)
def new_page(sm, st, bk, p):  # pragma: no cover - compiled
    """Open a page for block ``bk`` at free table position ``p``; returns its number."""
    q = st.pages
    st.pages = q + 1
    sm.btab[p] = q
    sm.bkeys[q] = bk
    for i in range(q * PAGE, (q + 1) * PAGE):
        sm.pages[i] = _EMPTY
    return q


@njit_cached
def rehash(sm, npages):  # pragma: no cover - compiled
    """Insert pages 0..npages-1 (by their block keys) into an empty block table."""
    btab, bkeys = sm.btab, sm.bkeys
    bmask = btab.shape[0] - 1
    for x in range(npages):
        q = mix64(bkeys[x]) & bmask
        while btab[q] != _EMPTY:
            q = (q + 1) & bmask
        btab[q] = x


@njit_cached
def finish(nodes, sm, state, found):  # pragma: no cover - compiled
    """End a search: its path and counts, and everything ready for the next search.

    Returns ``(path, cost, expansions, nodes, lookups)``: the (K, 3) int64 cells from the
    start to the goal node (``state``'s ``goal``; (0, 3) unless ``found``) and its cost
    (m, inf unless ``found``); then as :func:`end_search`. Only the path's allocation
    needs the runtime: the rest runs in the helpers, which count no references."""
    k = path_length(nodes, state[0].goal) if found else 0
    path = np.empty((k, 3), np.int64)
    cost, exp, n, look = end_search(nodes, sm, state, path)
    return path, cost, exp, n, look


@njit_cached(_nrt=False)
def path_length(nodes, goal_slot):  # pragma: no cover - compiled
    """Cells on the path from the start (its own parent) to ``goal_slot``."""
    par = nodes.par
    k = 1
    x = goal_slot
    while par[x] != x:
        x = par[x]
        k += 1
    return k


@njit_cached(_nrt=False)
def end_search(nodes, sm, state, path):  # pragma: no cover - compiled
    """End a search: write the path to ``state``'s goal node into ``path`` ((K, 3) int64,
    K from :func:`path_length`; (0, 3) when none was found) and return ``(cost,
    expansions, nodes, lookups)`` (cost in m, inf when ``path`` is empty). Then the dense
    slots of the search's nodes are reset to none (0), or the paged map's block table
    emptied, and the counters of ``state`` (an ``ASTAR_STATE`` (1,) array) zeroed but its
    ``stamp``, which keeps counting so that stamped scratch needs no clearing."""
    st = state[0]
    n = st.nodes
    cost = np.inf
    if path.shape[0] > 0:
        key, par = nodes.key, nodes.par
        x = st.goal
        cost = nodes.g[x]
        for i in range(path.shape[0] - 1, -1, -1):
            path[i, 0], path[i, 1], path[i, 2] = unpack3(key[x])
            x = par[x]
    dense = sm.dense
    if dense.shape[0] > 1:
        # the box's numbers read once, before the loop: a store to ``dense`` may alias
        # them for all the compiler knows, so read in the loop they were read per node
        key = nodes.key
        d1, d2 = sm.dims[1], sm.dims[2]
        at = (sm.lo[0] * d1 + sm.lo[1]) * d2 + sm.lo[2]
        for i in range(n):
            v0, v1, v2 = unpack3(key[np.uint64(i)])
            dense[np.uint64((v0 * d1 + v1) * d2 + v2 - at)] = 0
    else:
        btab = sm.btab
        for i in range(btab.shape[0]):
            btab[i] = _EMPTY
    exp, look = st.expansions, st.lookups
    st.nodes = 0
    st.queued = 0
    st.expansions = 0
    st.lookups = 0
    st.goal = 0
    st.status = 0
    st.pages = 0
    return cost, exp, n, look
