"""D* Lite per replan (numba): the changed cells' repair, the path, and :func:`replan`, the
one compiled call a replan makes (each call from Python with the planner's structs pays
numba's argument checks, and a replan that reuses its path does little else).

Stored path: the last extraction's cells stay in the path buffer. Extraction reads only the
edge masks of the path's nodes and the g of their neighbours, so until one of those
changes (the kernels clear ``path_valid`` when they write such a mask or g, ``near`` marks
the nodes) the path from a later start on it is the stored one from that start on: the
greedy descent would repeat it step for step.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import types
from numba.experimental import structref

from planner._numba import borrow_fields, njit_cached
from planner.occupancy.keys import unpack3
from planner.search.astar.dense import grid_offsets
from planner.search.dstar.kernel import (
    KM,
    PATH_COST,
    _box,
    _near_path,
    _remove,
    compute_path,
    edges,
    node,
    update_vertex,
)
from planner.search.dstar.rest import keep_path, mark_path
from planner.search.result import RUN_BLOCKED, RUN_EXHAUSTED, RUN_FOUND, RUN_GROW

PH_COLLECT, PH_APPLY, PH_SEARCH, PH_PATH = 0, 1, 2, 3
PHASES = ("collect", "apply", "search", "extract")  # names of the PH_* phases, in order
RUN_NEXT = -1  # replan_phase_state: a phase ran, the next one remains (no RUN_* code)


class DScratch(NamedTuple):
    """Arrays a replan reuses (sized by :class:`planner.search.dstar.lite.DStarLite`)."""

    ufree: np.ndarray  # (U,) bool one node's stencil lookups
    affect: np.ndarray  # (U,) int64 moves whose safe-rule cells include union offset j
    ss: np.ndarray  # (>= K (U + 1),) int64 collected nodes
    old: np.ndarray  # (same,) int64 their masks before the batch
    redo: np.ndarray  # (same,) bool their stencil holds a freed cell
    touched: np.ndarray  # (>= 2 n moves + 1,) int64 repair scratch
    path: np.ndarray  # (>= nodes + 1, 3) int64 cells of the stored path
    step: np.ndarray  # (same,) float64 cost of the move into each path cell (m)


@structref.register
class _StateType(types.StructRef):
    def preprocess_fields(self, fields):
        return tuple((n, types.unliteral(t)) for n, t in fields)


class ReplanState(structref.StructRefProxy):
    """A planner's arrays (:func:`replan`'s first nine arguments) as one object.

    A compiled call unboxes each array argument from its Python object; right after a
    scan those objects are out of cache, and unboxing the ~45 arrays of a replan was much of
    one that repairs nothing. One object is one unboxing. Made by :func:`new_state`
    (cached compilation); remade when an array is replaced."""


# "counts" is the (1,) state array (:data:`planner.search.dstar.kernel.REPLAN_STATE`; a field
# named "st" would clash with the local the generated constructor gives its struct)
structref.define_proxy(ReplanState, _StateType,
                       ["occ", "ms", "bx", "nd", "heap", "sc", "counts", "fs", "start"])


@njit_cached
def new_state(occ, ms, bx, nd, heap, sc, st, fs, start):  # pragma: no cover - compiled
    """:class:`ReplanState` of these arrays (shared, not copied)."""
    return ReplanState(occ, ms, bx, nd, heap, sc, st, fs, start)


@njit_cached(_nrt=False)
def _keep(state, cells):  # pragma: no cover - compiled
    occ, ms, bx, nd, heap, sc, counts, fs, start = borrow_fields(state)
    return keep_path(bx, counts, fs, start, sc.path, sc.step, cells)


@njit_cached
def keep_state(state, cells):  # pragma: no cover - compiled
    """:func:`~planner.search.dstar.rest.keep_path` on the planner's arrays in ``state``
    (:class:`ReplanState`) for the blocked cells ``cells``: a kept replan is this call
    alone. Right after a scan every object is out of cache, and each argument to unbox
    costs about a microsecond (``benchmarks/cold_call.py``): two here instead of nine
    arrays, and the struct's fields read without counting references."""
    return _keep(state, cells)


@njit_cached
def replan_state(state, cells, blocked):  # pragma: no cover - compiled
    """:func:`replan` with the planner's arrays from ``state`` (:class:`ReplanState`)."""
    return replan(state.occ, state.ms, state.bx, state.nd, state.heap, state.sc,
                  state.counts[0], state.fs, state.start, cells, blocked)


@njit_cached
def replan(occ, ms, bx, nd, heap, sc, st, fs, start, cells, blocked):
    # pragma: no cover - compiled
    """One replan, resumable: collect the changed cells' nodes (``cells`` (K, 3),
    ``blocked`` (K,) what each became), repair their edges, ComputeShortestPath, extract
    the path. ``st``: the planner's state record
    (:data:`~planner.search.dstar.kernel.REPLAN_STATE`); ``fs``: (2,) km and the path's
    cost (slots :data:`~planner.search.dstar.kernel.KM` and ``PATH_COST``). The caller
    sets ``st.phase`` (PH_COLLECT, or PH_SEARCH without changes) and ``st.check_start``;
    on RUN_GROW it makes room for ``st.need_nodes`` nodes, ``st.need_scratch`` repair scratch
    and a path of every node, and calls again.
    RUN_FOUND: the path is ``sc.path[st.path_from:st.path_to]``; RUN_EXHAUSTED: no path;
    RUN_BLOCKED: the start's own cell is blocked. The code is also left in ``st.status``."""
    st.status = _replan(occ, ms, bx, nd, heap, sc, st, fs, start, cells, blocked)
    return st.status


@njit_cached
def replan_phase_state(state, cells, blocked):  # pragma: no cover - compiled
    """One phase of :func:`replan` on the planner's arrays in ``state``
    (:class:`ReplanState`): the phase ``st.phase`` names, which it then advances. Returns
    :data:`RUN_NEXT` when a phase remains, else what :func:`replan` returns (RUN_GROW
    leaves ``st.phase`` where it was, for the call after growing). The same phase code as
    :func:`replan` runs: a caller that times each call sees where a replan's time goes
    (:meth:`planner.search.dstar.lite.DStarLite.plan_phases`)."""
    st = state.counts[0]
    st.need_nodes = 0
    st.need_scratch = 0
    st.status = _phase(state.occ, state.ms, state.bx, state.nd, state.heap, state.sc, st,
                       state.fs, state.start, cells, blocked)
    return st.status


@njit_cached
def _replan(occ, ms, bx, nd, heap, sc, st, fs, start, cells, blocked):
    # pragma: no cover - compiled
    st.need_nodes = 0
    st.need_scratch = 0
    while True:
        r = _phase(occ, ms, bx, nd, heap, sc, st, fs, start, cells, blocked)
        if r != RUN_NEXT:
            return r


@njit_cached
def _phase(occ, ms, bx, nd, heap, sc, st, fs, start, cells, blocked):
    # pragma: no cover - compiled
    """Run the phase ``st.phase`` (PH_*) and advance it: RUN_NEXT, or the replan's code."""
    nm = ms.moves.shape[0]
    if st.phase == PH_COLLECT:
        off = grid_offsets(ms.union, ms.moves, bx.dims[1], bx.dims[2])[0]
        st.collected = collect(occ, ms, sc.affect, bx, nd, st, cells, blocked, sc.ss, sc.old,
                               sc.redo, off)
        st.phase = PH_APPLY
        return RUN_NEXT
    if st.phase == PH_APPLY:
        n = st.collected
        if st.nodes + n * nm + 1 > nd.key.shape[0] or sc.touched.shape[0] < 2 * n * nm + 1:
            st.need_nodes = n * nm + 1
            st.need_scratch = 2 * n * nm + 1
            return RUN_GROW
        apply_changes(occ, ms, sc.ufree, bx, nd, heap, st, fs[KM], start, sc.ss, sc.old,
                      sc.redo, n, sc.touched)
        st.phase = PH_SEARCH
        return RUN_NEXT
    if st.phase == PH_SEARCH:
        r = compute_path(occ, ms, sc.ufree, bx, nd, heap, st, fs[KM], start, st.check_start == 1)
        st.check_start = 0
        if r == RUN_GROW:
            st.need_nodes = nm + 1
            return RUN_GROW
        if r == RUN_BLOCKED:
            return RUN_BLOCKED
        st.phase = PH_PATH
        return RUN_NEXT
    if sc.path.shape[0] < st.nodes + 1:
        return RUN_GROW
    j, k, cost = extract(occ, ms, sc.ufree, bx, nd, st, start, sc.path, sc.step)
    st.path_from = j
    st.path_to = k
    fs[PATH_COST] = cost
    return RUN_FOUND if k > j else RUN_EXHAUSTED


@njit_cached(_nrt=False)
def extract(occ, ms, ufree, bx, nd, st, start, out, step):  # pragma: no cover - compiled
    """Greedy descent from the start: next = argmin c(s, s') + g(s'), to the goal, or the
    stored path from the start on while it holds (module docstring). Returns
    ``(j, k, cost)``: the path is ``out[j:k]`` (none when ``j == k``: unreachable, or the
    descent does not reach the goal within ``len(out)`` steps); ``step[i]`` is the cost of
    the move into ``out[i]``."""
    if st.path_valid == 1:
        k = st.path_len
        for j in range(st.path_at, k):
            if out[j, 0] == start[0] and out[j, 1] == start[1] and out[j, 2] == start[2]:
                st.path_at = j
                cost = 0.0
                for i in range(j + 1, k):
                    cost += step[i]
                return j, k, cost
    st.path_id += 1  # a new path: marks of older ones no longer count
    pid = st.path_id
    st.path_valid = 0
    mark_path(ms, bx, out, st.path_len, False)  # the old path's cells (rest.py)
    st.path_len = 0
    s = node(bx, nd, st, start[0], start[1], start[2], False)
    if s < 0 or nd.rhs[s] == np.inf:  # the start may stay overconsistent (fig. 4)
        return 0, 0, np.inf
    goal = st.goal
    cost = 0.0
    out[0, 0], out[0, 1], out[0, 2] = start[0], start[1], start[2]
    step[0] = 0.0
    nd.near[s] = -pid
    k = 1
    while s != goal:
        if k >= out.shape[0]:
            return 0, 0, np.inf
        v, c = _descend(occ, ms, ufree, bx, nd, st, s, pid)
        if v < 0:
            return 0, 0, np.inf
        cost += c
        out[k, 0], out[k, 1], out[k, 2] = unpack3(nd.key[v])
        step[k] = c
        nd.near[v] = -pid
        k += 1
        s = v
    st.path_valid = 1
    st.path_len = k
    st.path_at = 0
    mark_path(ms, bx, out, k, True)
    return 0, k, cost


@njit_cached(_nrt=False)
def _descend(occ, ms, ufree, bx, nd, st, s, pid):  # pragma: no cover - compiled
    """:func:`best_successor` of a path node, marking each neighbour it reads as next to
    path ``pid``. Returns (the argmin or -1, its edge cost)."""
    mk = edges(occ, ms, ufree, bx, nd, st, s)
    u0, u1, u2 = unpack3(nd.key[s])
    best = np.inf
    arg = np.int64(-1)
    bc = np.inf
    for m in range(ms.moves.shape[0]):
        if (mk >> np.int64(m)) & 1:
            v = node(bx, nd, st, u0 + ms.moves[m, 0], u1 + ms.moves[m, 1], u2 + ms.moves[m, 2],
                     False)
            if v >= 0:
                if nd.near[v] != -pid:
                    nd.near[v] = pid
                c = ms.cost[m] + nd.g[v]
                if c < best:
                    best = c
                    arg = v
                    bc = ms.cost[m]
    if best == np.inf:
        return -1, np.inf
    return arg, bc


@njit_cached(_nrt=False)
def collect(occ, ms, affect, bx, nd, st, cells, blocked, out_s, out_old, out_redo, off):
    # pragma: no cover - compiled
    """Nodes with a cached edge mask whose stencil holds a changed cell, each once, in
    ``out_s[:n]`` with their old masks (``out_old``); returns n. A newly blocked cell at
    union offset j clears the moves ``affect[j]`` needs (all moves when it is the node's
    own cell): no lookup. A newly freed cell marks the node for a fresh lookup
    (``out_redo``). A node never looked up whose rhs rests on a move a newly blocked cell
    serves turns lazy (it is not collected). A stencil node whose own cell is blocked has
    no edges to lose
    (blocked in this batch: its own cell's visit kills it; earlier: it died then), so
    away from the box faces one bit of the dense occupancy grid (``occ``, the node
    map's box) skips it without touching its row. ``off`` (U,): each stencil cell's
    slot-map offset (:func:`~planner.search.astar.dense.grid_offsets`, made by the caller:
    a kernel without the runtime cannot allocate)."""
    st.stamp += 1
    stamp = st.stamp
    ust = ms.union
    nu = ust.shape[0]
    pid = st.path_id
    lo0, lo1, lo2 = bx.lo[0], bx.lo[1], bx.lo[2]
    d0, d1, d2 = bx.dims[0], bx.dims[1], bx.dims[2]
    e0, e1, e2 = bx.ext[0], bx.ext[1], bx.ext[2]
    reach, slot, grid = bx.reach, bx.slot, occ.grid
    n = 0
    for i in range(cells.shape[0]):
        c0, c1, c2 = cells[i, 0], cells[i, 1], cells[i, 2]
        a, b, c = c0 - lo0, c1 - lo1, c2 - lo2
        base = (a * d1 + b) * d2 + c
        if (a >= 0 and b >= 0 and c >= 0 and a < d0 and b < d1 and c < d2
                and (reach[base >> 3] >> (base & 7)) & 1 == 0):
            continue  # in no cached stencil
        inner = (a >= e0 and b >= e1 and c >= e2 and a < d0 - e0 and b < d1 - e1
                 and c < d2 - e2)
        for j in range(-1, nu):
            if inner:
                if j < 0:
                    s = np.int64(slot[base])
                elif (grid[(base - off[j]) >> 3] >> ((base - off[j]) & 7)) & 1 == 0:
                    continue
                else:
                    s = np.int64(slot[base - off[j]])
            elif j < 0:
                s = node(bx, nd, st, c0, c1, c2, False)
            else:
                s = node(bx, nd, st, c0 - ust[j, 0], c1 - ust[j, 1], c2 - ust[j, 2], False)
            if s < 0:
                continue
            if nd.mask[s] < 0:
                # Never looked up (g = inf): nothing reads its rhs until it is expanded,
                # but that rhs may rest on an edge this cell blocks; flagged, it is
                # recomputed when popped (compute_path), as a lazy node.
                if (blocked[i] and nd.rhs[s] < np.inf and s != st.goal
                        and (j < 0 or nd.sup[s] < 0 or (affect[j] >> nd.sup[s]) & 1)):
                    nd.lazy[s] = 1
                continue
            if nd.stamp[s] != stamp:
                nd.stamp[s] = stamp
                out_s[n] = s
                out_old[n] = nd.mask[s]
                out_redo[n] = False
                nd.batch[s] = n
                n += 1
            if blocked[i]:
                mk = 0 if j < 0 else nd.mask[s] & ~affect[j]
                if mk != nd.mask[s] and nd.near[s] == -pid:
                    st.path_valid = 0  # a node on the stored path lost a move
                nd.mask[s] = mk
            else:
                out_redo[nd.batch[s]] = True
                if nd.near[s] == -pid:
                    st.path_valid = 0
    return n


@njit_cached(_nrt=False)
def _touch(nd, u, stamp, touched, nt):  # pragma: no cover - compiled
    """List node ``u`` once per repair (its queue entry is updated after all flips)."""
    if nd.stamp[u] != stamp:
        nd.stamp[u] = stamp
        touched[nt] = u
        nt += 1
    return nt


@njit_cached(_nrt=False)
def apply_changes(occ, ms, ufree, bx, nd, heap, st, km, start, ss, old, redo, n, touched):
    # pragma: no cover - compiled
    """Look up the edge masks of the collected nodes marked ``redo``, then repair every
    edge whose state flipped, recomputing each affected rhs once.
    Needs room for ``n * len(moves)`` new nodes; ``touched``: scratch of 2 n len(moves).

    A collected node left without edges (its own cell blocked, or walled in) is *dead*:
    no rhs can read its g any more (edges are symmetric), so it settles at inf at once and
    its flipped edges are seen from the live end only. Inside a newly blocked region (most
    of a scan's cells) that skips every edge between two dead nodes.

    Lazy rhs: a node never looked up (mask -1: generated, never expanded, g = inf) is not
    repaired when an edge it may rest on is lost; its rhs can then be too low, never too
    high, until :func:`planner.search.dstar.kernel.compute_path` recomputes it before expanding
    it (and the start's before searching). Each queued node's key is a lower bound of its
    true one, so the search stops no earlier than it should.
    """
    for i in range(n):
        if redo[i]:
            nd.mask[ss[i]] = -1
            edges(occ, ms, ufree, bx, nd, st, ss[i])
    # Each flipped edge x <-> v with a live x (fig. 4, lines 31-36): a freed edge lowers
    # rhs at once (both ends); a node that lost the move its rhs rests on (``sup``)
    # turns lazy: queued with its old, lower, key until the search pops it and
    # recomputes (the other end of a lost edge, when it has a cached mask, is collected
    # too and checks its own support; a dead one has nothing to repair).
    st.stamp += 1
    stamp = st.stamp
    goal = st.goal
    nt = 0
    for i in range(n):
        x = ss[i]
        mx = nd.mask[x]
        diff = old[i] ^ mx
        if diff == 0:
            continue
        if mx == 0 and x != goal:
            # Dead: each live end with a cached mask is collected too and sees the edge;
            # an end never looked up (mask -1) keeps its rhs, stale, until it is
            # expanded (compute_path recomputes it first).
            continue
        lost = diff & old[i]
        if lost and x != goal and nd.rhs[x] < np.inf and (
                nd.sup[x] < 0 or (lost >> np.int64(nd.sup[x])) & 1):
            nd.lazy[x] = 1
            nt = _touch(nd, x, stamp, touched, nt)
        gained = diff & mx
        if gained == 0:
            continue
        x0, x1, x2 = unpack3(nd.key[x])
        gx = nd.g[x]
        for m in range(ms.moves.shape[0]):
            if not (gained >> np.int64(m)) & 1:
                continue
            c = ms.cost[m]
            v0, v1, v2 = x0 + ms.moves[m, 0], x1 + ms.moves[m, 1], x2 + ms.moves[m, 2]
            v = node(bx, nd, st, v0, v1, v2, False)
            gv = nd.g[v] if v >= 0 else np.inf
            if gv < np.inf and x != goal and c + gv < nd.rhs[x]:
                nd.rhs[x] = c + gv
                nd.sup[x] = m
                nt = _touch(nd, x, stamp, touched, nt)
            if gx < np.inf:
                if v < 0:
                    v = node(bx, nd, st, v0, v1, v2, True)
                if v != goal and c + gx < nd.rhs[v]:
                    nd.rhs[v] = c + gx
                    nd.sup[v] = bx.inv[m]
                    nt = _touch(nd, v, stamp, touched, nt)
    for i in range(n):  # after the live ends read their g
        x = ss[i]
        if nd.mask[x] == 0 and x != goal:
            _settle(bx, nd, heap, st, x)
    for i in range(nt):
        u = touched[i]
        if nd.mask[u] == 0:
            _settle(bx, nd, heap, st, u)
            continue
        update_vertex(ms, nd, heap, st, km, start, u)


@njit_cached(_nrt=False)
def _settle(bx, nd, heap, st, u):  # pragma: no cover - compiled
    """A node without edges: no rhs reads its g any more, so it is consistent at inf
    without queueing it, and it leaves the node map (later changes near it need not
    visit it; a cell freed again gets a fresh node when a search reaches it)."""
    if nd.g[u] < np.inf and _near_path(nd, st, u):
        st.path_valid = 0
    nd.g[u] = np.inf
    nd.rhs[u] = np.inf
    nd.lazy[u] = 0
    if nd.pos[u] >= 0:
        _remove(heap, nd.pos, st, u)
    u0, u1, u2 = unpack3(nd.key[u])
    bx.slot[_box(bx, u0, u1, u2)] = -1
