"""D* Lite kernels (numba): the optimised version of Koenig & Likhachev (2002, fig. 4), with
``km``, searching from the goal towards a moving start.

Graph: the lattice search's (:mod:`planner.search.moves`). The undirected edge between
``u`` and ``u + moves[m]`` exists iff ``u`` is free and every safe-rule cell of move ``m``
from ``u`` is free; the touched cells of a segment do not depend on its direction, so
``c(u, v) = c(v, u)``. Each node caches its edges as a bit mask over the moves (``mask``,
-1 = not looked up yet): one lookup of the node's own cell plus one per union-stencil
offset, made once and redone only when a changed cell lies in that stencil.

Lazy rhs: each node keeps a move ``sup`` its rhs rests on. A node that loses that move
(looked up or not) may hold an rhs that is too low, never too high; it stays queued
with the key of that rhs, a lower bound of its true key, and :func:`compute_path`
recomputes it when it is popped (or, for the start, before searching). Repairs after a
scan then touch only the nodes whose stencils changed, not both ends of every lost edge.

Priority queue: the indexed binary heap of :mod:`planner.search._heap` ordered by the
first key ``k1`` (on a grid of 1e-9 move lengths), ties broken by ``tb`` descending:
``inf`` for underconsistent nodes, else ``k2 = min(g, rhs)`` (the paper breaks ties the
other way, by the smaller k2; that expands every node of the equal-cost region between goal
and start, which on a lattice is most of it).
Nodes live in a table in creation order, found through a dense slot map over the world's
index box. The kernels never grow arrays: :class:`planner.search.dstar.lite.DStarLite`
makes room before each call (``RUN_GROW`` asks for more). Repair after changed cells, path
extraction and the one call per replan: :mod:`planner.search.dstar.replan`.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from planner._numba import njit_cached
from planner.occupancy.grid import occ_free
from planner.occupancy.keys import pack3, unpack, unpack3
from planner.search import _heap
from planner.search._state import state_dtype
from planner.search.heuristic import gauge
from planner.search.moves import move_allowed
from planner.search.result import RUN_BLOCKED, RUN_FOUND, RUN_GROW

#: the kernel state (:mod:`planner.search._state`): the common counters, then the stored
#: path (:mod:`planner.search.dstar.replan`: its id, whether it is still valid, its length,
#: the start's row in it), the replan's phase, its collected nodes, the room it asks for
#: (nodes, repair scratch), whether the start's own cell is still to be checked, the
#: replan's path: rows [path_from, path_to) of the path buffer
#: the slots of a planner's (2,) float64 ``fs`` array, which the compiled replan reads and
#: writes: the key modifier km (m, the heuristic's drift as the start moves) and the stored
#: path's cost (m)
KM, PATH_COST = 0, 1
REPLAN_STATE = state_dtype("path_id", "path_valid", "path_len", "path_at", "phase",
                           "collected", "need_nodes", "need_scratch", "check_start",
                           "path_from", "path_to")
_TOL = 1e-9  # relative: "rhs(s) = c + g_old" tested with slack (a spare recompute is safe)
_BIAS = 4 * _TOL  # relative: an underconsistent node's key ahead of the ties (_key1)


class DNodes(NamedTuple):
    """One row per node (capacity ``len(key)``): the fields are strided views of one record
    array (:data:`NODE`, 64 bytes, cache-line aligned), so touching a node costs one cache
    line instead of one per field (the repair visits thousands of scattered nodes)."""

    key: np.ndarray  # (cap,) int64 packed cell
    g: np.ndarray  # (cap,) float64 cost-to-goal estimate (m)
    rhs: np.ndarray  # (cap,) float64 one-step lookahead (m)
    mask: np.ndarray  # (cap,) int64 bit m: edge to key + moves[m] exists; -1 unknown
    pos: np.ndarray  # (cap,) int64 heap position, -1 not queued
    stamp: np.ndarray  # (cap,) int32 last update batch that collected the node
    batch: np.ndarray  # (cap,) int32 the node's row in that batch
    near: np.ndarray  # (cap,) int64 -pid: on stored path pid; +pid: next to it; else other
    sup: np.ndarray  # (cap,) int8 a move m with rhs = c(m) + g(key + moves[m]); -1 none
    lazy: np.ndarray  # (cap,) int8 1: rhs may be too low (:func:`update_vertex`)


class DBox(NamedTuple):
    """Dense cell -> node map over the world's index box, and a map of the cells that lie
    in the stencil (or are the own cell) of a node with a cached edge mask: an unmarked
    changed cell touches no cached edge, so :func:`collect` skips it with one bit read
    (a scan's cells mostly lie off the searched region or deep in a blocked blob; bits,
    not bytes: right after a scan the map is out of cache, and a cache line then covers
    512 cells)."""

    slot: np.ndarray  # (prod(dims),) int32 node of each cell, -1 none
    lo: np.ndarray  # (3,) int64
    dims: np.ndarray  # (3,) int64
    reach: np.ndarray  # (prod(dims) / 8,) uint8 bit set: in a cached stencil (only grows)
    ext: np.ndarray  # (3,) int64 largest |union-stencil offset| per axis
    inv: np.ndarray  # (M,) int64 the move back: moves[inv[m]] = -moves[m]
    rest: np.ndarray  # (prod(dims) / 8,) uint8 bit set: a cell the stored path rests on
    # (prod((dims + 3) // 4) / 8,) uint8 bit set: a 4x4x4 block of the box holds a rest
    # cell. A kept replan reads it first for each changed cell: right after a scan both maps
    # are out of cache, and this one is 64 times smaller (rest.py)
    rest_blocks: np.ndarray


def new_box(lo: np.ndarray, dims: np.ndarray, ms) -> DBox:
    """Empty node map over the box ``lo + [0, dims)`` for the move set ``ms``."""
    dims = np.asarray(dims, np.int64).copy()
    union, moves = ms.union, ms.moves
    ext = np.abs(union).max(axis=0).astype(np.int64) if len(union) else np.zeros(3, np.int64)
    back = {tuple(m): i for i, m in enumerate((-moves).tolist())}
    inv = np.array([back[tuple(m)] for m in moves.tolist()], np.int64)
    cells = int(np.prod(dims))
    blocks = int(np.prod((dims + 3) >> 2))
    return DBox(np.full(cells, -1, np.int32), np.asarray(lo, np.int64).copy(), dims,
                np.zeros((cells + 7) // 8, np.uint8), ext, inv,
                np.zeros((cells + 7) // 8, np.uint8), np.zeros((blocks + 7) // 8, np.uint8))


#: one node's record: the fields of :class:`DNodes` and padding to a cache line
NODE = np.dtype([("key", np.int64), ("g", np.float64), ("rhs", np.float64),
                 ("mask", np.int64), ("pos", np.int64), ("near", np.int64),
                 ("stamp", np.int32), ("batch", np.int32), ("sup", np.int8),
                 ("lazy", np.int8), ("pad", np.int8, (6,))])


def new_nodes(cap: int, keep: DNodes | None = None, n: int = 0) -> DNodes:
    """Node table for ``cap`` nodes; the first ``n`` rows copied from ``keep``."""
    raw = np.zeros(cap * NODE.itemsize + 64, np.uint8)
    off = -raw.ctypes.data % 64
    rec = raw[off:off + cap * NODE.itemsize].view(NODE)
    nd = DNodes(*(rec[name] for name in DNodes._fields))
    if keep is not None:
        for a, b in zip(nd, keep, strict=True):
            a[:n] = b[:n]
    return nd


def box_ordered(nd: DNodes, bx: DBox, heap, st) -> tuple[DNodes, int]:
    """The node table renumbered in the order of the nodes' cells in the box, without the
    rows of nodes that left the node map (:func:`planner.search.dstar.replan._settle`);
    the heap's slots, the box's cell -> node map and the state record's ``goal`` and
    ``nodes`` are renumbered in place. Returns the new table and its node count.

    Searches create nodes in expansion order, scattered in memory; a scan's repair then
    reads the rows of the nodes next to its cells, neighbours in space. In box order they
    share pages and neighbouring cache lines. O(n log n) numpy."""
    n = int(st["nodes"])
    d = bx.dims
    a = unpack(nd.key[:n], 3) - bx.lo
    b = (a[:, 0] * d[1] + a[:, 1]) * d[2] + a[:, 2]
    ids = np.arange(n)
    old = ids[bx.slot[b] == ids]  # rows still in the node map
    old = old[np.argsort(b[old], kind="stable")]
    m = len(old)
    new_id = np.full(n, -1, np.int64)
    new_id[old] = np.arange(m)
    table = new_nodes(len(nd.key))
    for dst, src in zip(table, nd, strict=True):
        dst[:m] = src[old]
    hn = int(st["queued"])
    heap.slot[:hn] = new_id[heap.slot[:hn]]
    bx.slot[b[old]] = np.arange(m, dtype=np.int32)
    st["goal"] = new_id[st["goal"]]
    st["nodes"] = m
    return table, m


@njit_cached(_nrt=False)
def _box(bx, v0, v1, v2):  # pragma: no cover - compiled
    a = v0 - bx.lo[0]
    b = v1 - bx.lo[1]
    c = v2 - bx.lo[2]
    if a < 0 or b < 0 or c < 0 or a >= bx.dims[0] or b >= bx.dims[1] or c >= bx.dims[2]:
        return -1
    return (a * bx.dims[1] + b) * bx.dims[2] + c


@njit_cached(_nrt=False)
def node(bx, nd, st, v0, v1, v2, create):  # pragma: no cover - compiled
    """Node of cell (v0, v1, v2); created (g = rhs = inf) when ``create``; -1 if none."""
    b = _box(bx, v0, v1, v2)
    if b < 0:
        return -1
    s = np.int64(bx.slot[b])
    if s >= 0 or not create:
        return s
    s = st.nodes
    st.nodes = s + 1
    bx.slot[b] = s
    nd.key[s] = pack3(v0, v1, v2)
    nd.g[s] = np.inf
    nd.rhs[s] = np.inf
    nd.mask[s] = -1
    nd.pos[s] = -1
    nd.stamp[s] = 0
    nd.near[s] = 0
    nd.sup[s] = -1
    nd.lazy[s] = 0
    return s


@njit_cached(_nrt=False)
def _near_path(nd, st, u):  # pragma: no cover - compiled
    """The stored path's extraction read ``u`` (on the path or next to it)."""
    return nd.near[u] == st.path_id or nd.near[u] == -st.path_id


# The search's kernels compile without the runtime's reference counting (as the dense A*
# loop, planner.search.astar.dense): they allocate nothing, and each heap operation they run
# would otherwise incref / decref the arrays it binds (atomic adds, tens per expansion).
@njit_cached(_nrt=False)
def edges(occ, ms, ufree, bx, nd, st, s):  # pragma: no cover - compiled
    """Edge mask of node ``s`` (looked up once, then cached)."""
    if nd.mask[s] >= 0:
        return nd.mask[s]
    u0, u1, u2 = unpack3(nd.key[s])
    st.lookups += 1
    m = np.int64(0)
    reach = bx.reach
    b = _box(bx, u0, u1, u2)
    reach[b >> 3] |= np.uint8(1 << (b & 7))
    if occ_free(occ, u0, u1, u2):
        ust = ms.union
        nu = ust.shape[0]
        for j in range(nu):
            v0, v1, v2 = u0 + ust[j, 0], u1 + ust[j, 1], u2 + ust[j, 2]
            ufree[j] = occ_free(occ, v0, v1, v2)
            b = _box(bx, v0, v1, v2)
            if b >= 0:
                reach[b >> 3] |= np.uint8(1 << (b & 7))
        st.lookups += nu
        for k in range(ms.moves.shape[0]):
            if move_allowed(ufree, ms.ptr, ms.idx, k):
                m |= np.int64(1) << np.int64(k)
    nd.mask[s] = m
    return m


@njit_cached(_nrt=False)
def _h(ms, start, v0, v1, v2):  # pragma: no cover - compiled
    """Heuristic between the start and a cell (symmetric: the move set is)."""
    return gauge(ms.hmat, v0 - start[0], v1 - start[1], v2 - start[2])


@njit_cached(_nrt=False)
def _key1(ms, g, rhs, hv, km, under):  # pragma: no cover - compiled
    """First key of a queued node. An underconsistent node (``under``: g < rhs, or a
    lazy node's rhs that may be too low) goes ahead of every
    key equal to its own up to float noise (``_BIAS``): its stale low g may carry the
    start's path, and two sums of the same moves can round to neighbouring grid steps of
    :func:`_k1`, which would otherwise queue it one step behind an overconsistent tie (or
    the start itself) and let the search stop on a stale value."""
    x = min(g, rhs) + hv + km
    k = _k1(ms, x)
    if under:
        k -= _BIAS * (1.0 + abs(x))
    return k


@njit_cached(_nrt=False)
def _k1(ms, x):  # pragma: no cover - compiled
    """First key on a grid of 1e-9 move lengths: equal sums of the same moves in another
    order (float noise) mostly tie exactly, so the second key orders them."""
    q = 1e-9 * ms.cost[0]
    return np.floor(x / q + 0.5) * q


@njit_cached(_nrt=False)
def _remove(heap, pos, st, s):  # pragma: no cover - compiled
    st.queued = _heap.remove(heap, pos, st.queued, s)


@njit_cached(_nrt=False)
def update_vertex(ms, nd, heap, st, km, start, s):  # pragma: no cover - compiled
    """Queue ``s`` with its key when inconsistent, dequeue it when consistent.

    Queue order: first key ascending, then the tie-break ``tb`` descending (module
    docstring): an underconsistent node (g < rhs: its g is stale and low) comes first
    among ties, then the one with the larger ``min(g, rhs)`` (nearest the start, A*'s
    dive).

    A *lazy* node (its rhs may be too low, never too high: it lost a move its rhs rested
    on and was not recomputed) stays queued, as an underconsistent one, until
    :func:`compute_path` pops it and recomputes its rhs: its key is a lower bound of its
    true key, so it is popped no later than it should be."""
    pos = nd.pos
    g, rhs = nd.g[s], nd.rhs[s]
    lazy = nd.lazy[s] != 0
    if g != rhs or lazy:
        gm = min(g, rhs)
        u0, u1, u2 = unpack3(nd.key[s])
        under = g < rhs or lazy
        k1 = _key1(ms, g, rhs, _h(ms, start, u0, u1, u2), km, under)
        tb = np.inf if under else gm
        if pos[s] >= 0:
            _heap.change_key(heap, pos, st.queued, s, k1, tb)
        else:
            st.queued = _heap.push(heap, pos, st.queued, s, k1, tb)
    elif pos[s] >= 0:
        _remove(heap, pos, st, s)


@njit_cached(_nrt=False)
def best_successor(occ, ms, ufree, bx, nd, st, s):  # pragma: no cover - compiled
    """``(min_m c(s, s + m) + g(s + m), node of the argmin or -1, its edge cost, m)``."""
    mk = edges(occ, ms, ufree, bx, nd, st, s)
    u0, u1, u2 = unpack3(nd.key[s])
    best = np.inf
    arg = np.int64(-1)
    bc = np.inf
    bm = -1
    for m in range(ms.moves.shape[0]):
        if (mk >> np.int64(m)) & 1:
            v = node(bx, nd, st, u0 + ms.moves[m, 0], u1 + ms.moves[m, 1], u2 + ms.moves[m, 2],
                     False)
            if v >= 0:
                c = ms.cost[m] + nd.g[v]
                if c < best:
                    best = c
                    arg = v
                    bc = ms.cost[m]
                    bm = m
    return best, arg, bc, bm


@njit_cached(_nrt=False)
def recompute_rhs(occ, ms, ufree, bx, nd, st, s):  # pragma: no cover - compiled
    """rhs(s) = min over its moves of c + g (looks its edges up if needed): exact again."""
    best, _, _, m = best_successor(occ, ms, ufree, bx, nd, st, s)
    nd.rhs[s] = best
    nd.sup[s] = m
    nd.lazy[s] = 0


@njit_cached(_nrt=False)
def compute_path(occ, ms, ufree, bx, nd, heap, st, km, start, check_start):
    # pragma: no cover - compiled
    """ComputeShortestPath: expand until the start is consistent and no queued key is
    smaller than its key (ties, up to float noise, are expanded too). Returns RUN_FOUND
    (settled), RUN_GROW when a new node might not fit, or RUN_BLOCKED when ``check_start``
    and the start's own cell is blocked (one lookup, as A*'s endpoint check)."""
    if check_start:
        st.lookups += 1
        if not occ_free(occ, start[0], start[1], start[2]):
            return RUN_BLOCKED
    cap = nd.key.shape[0]
    nm = ms.moves.shape[0]
    goal = st.goal
    heap_f, heap_g, heap_s = heap.f, heap.g, heap.slot
    ss = node(bx, nd, st, start[0], start[1], start[2], False)
    if ss >= 0 and ss != goal and (nd.mask[ss] < 0 or nd.lazy[ss]):  # rhs may be low
        recompute_rhs(occ, ms, ufree, bx, nd, st, ss)
        update_vertex(ms, nd, heap, st, km, start, ss)
    while st.queued > 0:
        if st.nodes + nm > cap:
            return RUN_GROW
        ss = node(bx, nd, st, start[0], start[1], start[2], False)
        if ss >= 0:
            sg, srhs = nd.g[ss], nd.rhs[ss]
            ks2 = min(sg, srhs)
            ks1 = _k1(ms, ks2 + km)  # h(start, start) = 0
        else:
            sg = srhs = ks1 = ks2 = np.inf
        k1o, tbo = heap_f[0], heap_g[0]
        # Fig. 4 runs while TopKey < key(start) or rhs(start) > g(start). With first keys
        # equal up to float noise (sums of the same moves in another order), a queued node
        # still goes first if it is underconsistent (its stale low g may sit on the
        # start's path). An overconsistent tie cannot make the start cheaper (its rhs +
        # c(start, u) >= its rhs + h(start, u) = g(start)), nor can its stale high g
        # mislead the path: the descent takes a neighbour w with c + g(w) = g(start), and
        # an underconsistent w or a w resting on one would have a key below the start's.
        # So the search stops before it, as A* stops at the goal among equal f. (A tie
        # with a larger min(g, rhs) than the start's is a key from an earlier start, not
        # refreshed: refreshing raises it, and refreshing them costs extra pops per replan.)
        e1 = _TOL * (1.0 + abs(ks1)) if ks1 < np.inf else 0.0
        if not (srhs > sg or k1o < ks1 - e1 or (k1o <= ks1 + e1 and tbo == np.inf)):
            break
        u = heap_s[0]
        st.expansions += 1
        u0, u1, u2 = unpack3(nd.key[u])
        k1n = _key1(ms, nd.g[u], nd.rhs[u], _h(ms, start, u0, u1, u2), km,
                    nd.g[u] < nd.rhs[u] or nd.lazy[u] != 0)
        if k1o < k1n:  # a key from an earlier start: requeue (the tie-break is current)
            update_vertex(ms, nd, heap, st, km, start, u)
            continue
        if nd.lazy[u] and u != goal:
            # lazy: its rhs may be too low; requeue it exact (a node never looked up has
            # the rhs its expanded neighbour gave it, exact unless a scan since blocked
            # that edge: then collect flagged it lazy)
            recompute_rhs(occ, ms, ufree, bx, nd, st, u)
            update_vertex(ms, nd, heap, st, km, start, u)
            continue
        mk = edges(occ, ms, ufree, bx, nd, st, u)
        if _near_path(nd, st, u):  # its g changes: the stored path may not hold
            st.path_valid = 0
        if nd.g[u] > nd.rhs[u]:
            gu = nd.rhs[u]
            nd.g[u] = gu
            _remove(heap, nd.pos, st, u)
            for m in range(nm):
                if (mk >> np.int64(m)) & 1:
                    s = node(bx, nd, st, u0 + ms.moves[m, 0], u1 + ms.moves[m, 1],
                             u2 + ms.moves[m, 2], True)
                    if nd.near[s] == -st.path_id:  # u (maybe new) is next to the path
                        st.path_valid = 0
                    c = ms.cost[m] + gu
                    if s != goal and c < nd.rhs[s]:
                        nd.rhs[s] = c
                        nd.sup[s] = bx.inv[m]
                        update_vertex(ms, nd, heap, st, km, start, s)
        else:
            g_old = nd.g[u]
            nd.g[u] = np.inf
            for m in range(nm):
                if (mk >> np.int64(m)) & 1:
                    s = node(bx, nd, st, u0 + ms.moves[m, 0], u1 + ms.moves[m, 1],
                             u2 + ms.moves[m, 2], False)
                    if s < 0 or s == goal:
                        continue
                    c = ms.cost[m] + g_old
                    if abs(nd.rhs[s] - c) <= _TOL * c:
                        recompute_rhs(occ, ms, ufree, bx, nd, st, s)
                        update_vertex(ms, nd, heap, st, km, start, s)
            update_vertex(ms, nd, heap, st, km, start, u)
    return RUN_FOUND
