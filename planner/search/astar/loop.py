"""The search loop (numba): one expansion loop for A*, Dijkstra, Theta*, Lazy Theta* and
weighted Lazy Theta* on every lattice and world, dense or hashed, with the dense or the paged
node map (:mod:`planner.search.astar.kernel` runs it).

It is compiled once per *variant*, a compile-time constant (``numba.literally``) that fixes
what the loop would otherwise test on every expansion; the tests then fold away, and each
variant is the code a copy written for its case would be:

- :data:`GENERAL` reads the method, the node map (dense array or pages), the occupancy
  (dense bits or hash set) and the stencil test (bit mask or each move's cell list) from its
  arguments;
- :data:`DENSE_LAZY`: Lazy Theta* on a dense grid with the dense node array and the bit mask
  (the straight-line heuristic);
- :data:`DENSE_ASTAR`: lattice A* / Dijkstra there, which also marks a closed node in the
  dense node array (stores ``-(slot + 1)``), so that a neighbour's one load of it tells
  closed from open without a load of its heap position.

Per expansion the loop reads the union stencil once, into a mask of free cells where it
fits 63 bits (:func:`planner.search.astar.dense.stencil_mask`, or a few bit windows, one per
row of cells along the grid's fastest axis, away from the box faces), verifies Lazy Theta*'s
assumed sight line to the parent (falling back to the best closed lattice neighbour,
SetVertex), and per allowed move finds the target's node, in one load of the dense array
or through the pages. The variants give the same paths, costs, expansions and lookups
(``tests/test_search.py``, ``tests/test_anyangle.py``); ``benchmarks/loop_speed.py``
measures the dense side against the paged one.
"""

from __future__ import annotations

import numba
import numpy as np

from planner._numba import njit_cached
from planner.occupancy.grid import cell_free
from planner.occupancy.keys import mix64, pack3, unpack3
from planner.search import _heap
from planner.search._los import DDA_MAX, cubic_walk, dense_walk, is_cubic, sight
from planner.search._nodes import PAGE, block_key, find_slot, local, new_page
from planner.search.astar.dense import stencil_mask
from planner.search.heuristic import H_GAUGE, half_gauge, length, node_estimate, rows
from planner.search.moves import MAX_BITS, move_open
from planner.search.result import RUN_BUDGET, RUN_EXHAUSTED, RUN_FOUND, RUN_GROW, RUN_LIMIT

__all__ = ["GENERAL", "DENSE_LAZY", "DENSE_ASTAR", "THETA", "LAZY_THETA", "search_loop"]

THETA, LAZY_THETA = 1, 2  # SearchParams.anyangle (0: lattice A* / Dijkstra)
#: :func:`search_loop`'s variants (module docstring)
GENERAL, DENSE_LAZY, DENSE_ASTAR = 0, 1, 2
_EMPTY = -1
#: the most moves for which an expansion lists its moves first (below): FCC's 12, BCC's and
#: MCC's 14 and hex's 20 gain by it; cubic-26 lost 6-10% on the office and on Warframe DA1
#: (`python benchmarks/lattice_sight.py --segments 0 --maps office`, `python
#: benchmarks/cpp_anchor.py --maps DA1 geb079 --queries 100`), and keeps the plain loop
LIST_MOVES = 20
#: the f grid of the open list (planner.search._heap.fkey): lattice A*, Dijkstra and
#: weighted-theta, a fraction of the shortest move's length; Theta* and Lazy Theta*, a
#: fraction of the start's straight-line distance to the goal, with the start's f at the
#: foot of its step. On the lattice, equal-cost paths tie to the bit on a fine grid. Any
#: angle, f = g + |goal - v| grows only quadratically off the straight line of length L
#: (by d^2 / 2 (1/a + 1/b) for a node d beside it, a and b from its ends), so on a fine
#: grid the search expands a thin ellipsoid of nearly straight f around the line before
#: it reaches the goal; on a grid of L / 2000 the nodes up to about L / 60 beside its
#: middle tie with the line's and the larger-g tie-break dives along it. Near the ends (a
#: or b a few moves) the cells a chain of moves must cross lie up to a cell's
#: circumradius beside the line, an excess of a sizable fraction of a move that no grid
#: of L / 2000 covers: the search would flood the whole tied ellipsoid before it steps
#: off the start or onto the goal, and again past each corner a detour turns at (a new
#: line starts at the parent). So the open list files a node under f less an end
#: allowance (END_SLACK): END_SLACK * c^2 / max(min(a, h), c), a the node's straight line
#: from its parent and c the shortest move; at most END_SLACK * c a move from a parent or
#: the goal, it fades as 1/a or 1/h, like the excess. Free lines of 8 to 150 moves then
#: take fewer than two expansions per move on every lattice (tests/test_anyangle.py), and
#: the lengths found match an exact f order's on average (`pytest tests/test_anyangle.py
#: -k plain_python`). Planning maps: `python benchmarks/lattice_sight.py --maps DA1
#: Complex geb079 office --segments 0` ("LT* exp").
F_STEP, F_STEP_ANY_ANGLE, END_SLACK = 1e-9, 5e-4, 0.25


@njit_cached(_nrt=False, inline="always")
def filed_f(g, h, hop, ends, cmin):  # pragma: no cover - compiled
    """The f (m) the open list files a node of cost ``g``, estimate ``h`` and straight
    line ``hop`` (m) from its parent under: f less the end allowance ``ends / max(min(hop,
    h), cmin)`` (:data:`END_SLACK`; ``ends`` 0 but any angle)."""
    if ends > 0.0:
        return g + h - ends / max(min(hop, h), cmin)
    return g + h


# Without the runtime's reference counting: the loop allocates nothing, and each heap
# operation it runs would otherwise incref / decref the heap arrays it binds (an atomic add
# each, tens per expansion: about 45% of the loop's time on cubic-26). Its rare allocating
# paths (the sight walk on fresh arrays, the float clipping of very long cubic lines) are
# separate compiled functions, which keep theirs.
@njit_cached(_nrt=False)
def search_loop(occ, walk, ms, nodes, heap, slots, sc, ufree, params, goal, st, dt, variant):
    # pragma: no cover - compiled
    """Run the search from the state ``st`` (the start node in place) until it ends or needs
    room.

    Parameters
    ----------
    occ, walk, ms, nodes, heap, slots, sc, ufree, params
        As :func:`planner.search.astar.kernel.search_run`'s.
    goal : (3,) int64
    st : ``ASTAR_STATE`` record
        The search's counters.
    dt : planner.search.astar.dense.DenseTables
        ``ms``'s stencil and moves on ``occ``'s grid (and the gauge's scratch).
    variant : int
        :data:`GENERAL`, :data:`DENSE_LAZY` or :data:`DENSE_ASTAR`, a compile-time constant;
        the caller makes sure the world and search are of the variant's case.

    Returns
    -------
    int
        RUN_FOUND, RUN_EXHAUSTED, RUN_LIMIT, RUN_BUDGET or RUN_GROW.
    """
    numba.literally(variant)
    lazy_v = variant == DENSE_LAZY
    astar_v = variant == DENSE_ASTAR
    fixed = lazy_v or astar_v  # a dense grid, the dense node array, the bit mask
    mode, grid, lo, dims = occ.mode, occ.grid, occ.lo, occ.dims
    lo0, lo1, lo2 = lo[0], lo[1], lo[2]
    d0, d1, d2 = dims[0], dims[1], dims[2]
    moves, mcost, ust, hmat = ms.moves, ms.cost, ms.union, ms.hmat
    hkind, oct_s = ms.hkind, ms.octile
    nkey, ng, nh, npar, npos = nodes.key, nodes.g, nodes.h, nodes.par, nodes.pos
    pages, btab, bkeys, dsl = slots.pages, slots.btab, slots.bkeys, slots.dense
    uoff, moff, reach, mkey = dt.uoff, dt.moff, dt.reach, dt.mkey
    roff, rshift, rmask, ubit, need = dt.roff, dt.rshift, dt.rmask, dt.ubit, dt.need2
    hhalf, habs, todo = dt.hhalf, dt.habs, dt.todo
    gridded = fixed or mode == 0
    dense = fixed or (dsl.shape[0] > 1 and mode == 0)  # the dense slot box is the grid's box
    marks = astar_v  # closed nodes marked in the dense node array
    anyangle, max_nodes, max_exp, hw = (params.anyangle, params.max_nodes,
                                        params.max_expansions, params.h_weight)
    if lazy_v:
        anyangle = LAZY_THETA
    if astar_v:
        anyangle = 0
    lazy = anyangle == LAZY_THETA
    theta = anyangle == THETA
    # The f plateau's side heap (planner.search._heap) for lattice A* / Dijkstra; the
    # any-angle methods keep the one heap (fcur stays NaN: nothing equals it, the side heap
    # stays empty). DENSE_LAZY calls the one heap's own operations, the others the pq_*
    # ones for both cases: one heap's code in each variant.
    plateau = anyangle == 0
    plain = lazy_v
    gauge = hkind == H_GAUGE and oct_s <= 0.0
    g = walk.g
    cubic = is_cubic(g)
    # sight lines between free cells of a dense grid stay inside its box: the walk on the
    # grid's arrays
    cubic_dense = cubic and gridded and max(d0, max(d1, d2)) <= DDA_MAX
    gl0, gl1, gl2 = goal[0], goal[1], goal[2]
    gk = pack3(gl0, gl1, gl2)
    gm = rows(g)
    cap = nkey.shape[0]
    pcap = bkeys.shape[0]
    bsize = btab.shape[0]
    bmask = bsize - 1
    last_bk = np.int64(-1)
    last_pg = np.int64(0)
    nu = ust.shape[0]
    nm = moves.shape[0]
    nr = roff.shape[0]
    last = np.uint64(grid.shape[0] - 1)
    bits = fixed or nu <= MAX_BITS  # one mask test per move instead of its cell list
    windows = bits and dt.rows
    all_u = dt.all_u if bits else np.int64(0)
    cmin = np.inf
    for m in range(nm):  # not mcost.min(): it needs the runtime
        cmin = min(cmin, mcost[m])
    fq = F_STEP * cmin  # the f grid (F_STEP)
    f0 = 0.0
    ends = 0.0  # END_SLACK * cmin^2: the end allowance's scale (m^2)
    if anyangle != 0 and hw == 1.0:  # (weighted-theta's inflated heuristic dives already)
        fq = max(fq, F_STEP_ANY_ANGLE * nh[0])  # the start's estimate (slot 0)
        f0 = nh[0] + (0.5 - 1e-6) * fq  # its f at the foot of its step, within float noise
        ends = END_SLACK * cmin * cmin
    fq_inv = 1.0 / fq
    base = np.int64(0)
    n = st.nodes
    hn = st.queued
    sn = 0  # the side heap: empty between runs
    fcur = np.nan
    expansions = st.expansions
    lookups = st.lookups
    status = RUN_EXHAUSTED
    while hn + sn > 0:
        if n + nm > cap or (not dense and (st.pages + nm > pcap
                                            or 2 * (st.pages + nm) > bsize)):
            status = RUN_GROW
            break
        if max_exp > 0 and expansions >= max_exp:
            status = RUN_BUDGET
            break
        sg = 0.0
        if plain:
            s, hn = _heap.pop(heap, npos, hn)
        else:
            s, sg, hn, sn, fc = _heap.pq_pop(heap, npos, hn, sn, fcur)
            if plateau:
                fcur = fc
        su = np.uint64(s)  # unsigned node indices: no negative-index fix-up on each access
        if not marks:
            # (with marks the dense node array tells closed from open, and nothing reads
            # a closed node's pos: no store to a line of pos per expansion)
            npos[su] = -1
        expansions += 1
        ks = nkey[su]
        u0, u1, u2 = unpack3(ks)
        blocked = np.int64(0)
        inner = False
        if gridded:
            a0, b0, c0 = u0 - lo0, u1 - lo1, u2 - lo2
            base = (a0 * d1 + b0) * d2 + c0
            if marks:
                dsl[np.uint64(base)] = -(s + 1)
            inner = (a0 >= reach and b0 >= reach and c0 >= reach and a0 < d0 - reach
                     and b0 < d1 - reach and c0 < d2 - reach)
            if windows and inner:
                # each row of stencil cells along the fastest axis as one window of the
                # bit grid: two byte loads instead of a load per cell
                free = np.int64(0)
                for r in range(nr):
                    f = np.uint64(base + roff[r])
                    i = f >> np.uint64(3)
                    w = np.int64(grid[i]) | (np.int64(grid[min(i + np.uint64(1), last)]) << 8)
                    free |= ((w >> np.int64(f & np.uint64(7))) & rmask[r]) << rshift[r]
                blocked = all_u & ~free
            elif bits:  # straight into the mask of free cells
                free = stencil_mask(grid, a0, b0, c0, d0, d1, d2, base, reach, ust, uoff,
                                    ubit)
                blocked = all_u & ~free
            elif inner:
                for j in range(nu):
                    f = base + uoff[j]
                    ufree[j] = (grid[f >> 3] >> (f & 7)) & 1 != 0
            else:
                for j in range(nu):
                    a = a0 + ust[j, 0]
                    b = b0 + ust[j, 1]
                    c = c0 + ust[j, 2]
                    f = (a * d1 + b) * d2 + c
                    ufree[j] = (a >= 0 and b >= 0 and c >= 0 and a < d0 and b < d1
                                and c < d2 and (grid[f >> 3] >> (f & 7)) & 1 != 0)
        else:
            for j in range(nu):
                ufree[j] = cell_free(mode, grid, lo, dims, occ.table, occ.tmask, occ.gmat,
                                     occ.blo, occ.bhi, u0 + ust[j, 0], u1 + ust[j, 1],
                                     u2 + ust[j, 2])
            if bits:
                for j in range(nu):
                    if not ufree[j]:
                        blocked |= np.int64(1) << ubit[j]
        lookups += nu
        ps = npar[su]
        p0, p1, p2 = u0, u1, u2
        if anyangle != 0 and ps != s:
            p0, p1, p2 = unpack3(nkey[ps])
        # Verify the assumed sight line, walked from s: a blocked cell is likelier near s
        # (its parent saw s's generator), so the walk stops sooner.
        if lazy and ps != s:
            if cubic_dense:
                ok, c = dense_walk(grid, lo, dims, u0, u1, u2, p0, p1, p2)
            elif cubic and not fixed:  # (a box too long for it: the face walk)
                ok, c = cubic_walk(occ, u0, u1, u2, p0, p1, p2)
            else:
                ok, c = sight(occ, walk, sc, st, u0, u1, u2, p0, p1, p2)
            lookups += c
            if not ok:
                # SetVertex: the best closed neighbour that an allowed move reaches (one
                # exists: the node that generated s)
                best = np.inf
                bp = np.int64(-1)
                for m in range(nm):
                    if not move_open(bits, need, blocked, ufree, ms.ptr, ms.idx, m):
                        continue
                    if dense:  # an allowed move's target is free, hence inside the box
                        t = np.int64(dsl[np.uint64(base + moff[m])]) - 1
                    else:
                        t = find_slot(slots, u0 + moves[m, 0], u1 + moves[m, 1],
                                      u2 + moves[m, 2])
                    if t < 0 or npos[t] != -1:
                        continue
                    gv = ng[t] + mcost[m]
                    if gv < best:
                        best = gv
                        bp = t
                npar[su] = bp
                ng[su] = best
                ps = bp
                p0, p1, p2 = unpack3(nkey[ps])
        if ks == gk:
            status = RUN_FOUND
            st.goal = s
            break
        if max_nodes > 0 and n >= max_nodes:
            status = RUN_LIMIT
            break
        # lattice A* keys its entries by g: the popped entry's g is the node's
        gs = sg if astar_v else ng[su]
        gp = ng[ps]
        # Lattice A* away from the box faces: the moves that are allowed and reach a node
        # not closed, listed with the target's slot map entry and without a branch per
        # move (every target is inside the box; a branch on open or closed is a coin toss,
        # mispredicted about every other move), so that the loop below runs only over
        # them and tests nothing more before the target's g. (A move set of the dense
        # variant has at most MAX_BITS moves: the index fits the entry's low byte.)
        nt = nm
        listed = astar_v and inner and nm <= LIST_MOVES
        if listed:
            nt = 0
            for m in range(nm):
                v = np.int64(dsl[np.uint64(base + moff[m])])
                todo[nt] = (v << 8) | m
                nt += ((need[m] & blocked) == 0) & (v >= 0)
        for i in range(nt):
            if listed:
                e = todo[i]
                m = e & 255
                loc = np.uint64(base + moff[m])
                t = (e >> 8) - 1
            elif not move_open(bits, need, blocked, ufree, ms.ptr, ms.idx, i):
                # Safe rule first: with the bitmask it is one test, and an allowed move's
                # target is free, hence inside the dense box.
                continue
            elif dense:
                m = i
                loc = np.uint64(base + moff[m])
                v = dsl[loc]  # slot + 1, 0 none (-(slot + 1) closed, with marks)
                if marks and v < 0:
                    continue  # closed: a consistent heuristic never improves it
                t = np.int64(v) - 1
            else:
                m = i
                v0 = u0 + moves[m, 0]
                v1 = u1 + moves[m, 1]
                v2 = u2 + moves[m, 2]
                bk = block_key(v0, v1, v2)
                if bk != last_bk:
                    p = mix64(bk) & bmask
                    while True:
                        q = btab[p]
                        if q == _EMPTY or bkeys[q] == bk:
                            break
                        p = (p + 1) & bmask
                    if q == _EMPTY:
                        q = new_page(slots, st, bk, p)
                    last_bk = bk
                    last_pg = q
                loc = np.uint64(last_pg * PAGE + local(v0, v1, v2))
                t = np.int64(pages[loc])
            tu = np.uint64(t)
            if t >= 0:
                if not marks and npos[tu] == -1:
                    continue  # closed: a consistent heuristic never improves it
                if lazy and npar[tu] == ps:
                    # its g came through this parent, the sum below to the bit (a closed
                    # node's g stays): not less, so no square root
                    continue
            v0 = u0 + moves[m, 0]  # (after the tests above: most moves stop there)
            v1 = u1 + moves[m, 1]
            v2 = u2 + moves[m, 2]
            if anyangle == 0:
                gt = gs + mcost[m]
                par = s
                hop = 0.0  # (unread: no end allowance)
            else:
                hop = length(gm, v0 - p0, v1 - p1, v2 - p2)
                gt = gp + hop  # through s's parent
                par = ps
                if theta and ps != s:
                    g1 = gs + mcost[m]
                    if t >= 0 and gt >= ng[tu] and g1 >= ng[tu]:
                        continue  # neither parent improves t: its sight line is moot
                    if cubic_dense:
                        ok, c = dense_walk(grid, lo, dims, v0, v1, v2, p0, p1, p2)
                    elif cubic:
                        ok, c = cubic_walk(occ, v0, v1, v2, p0, p1, p2)
                    else:
                        ok, c = sight(occ, walk, sc, st, p0, p1, p2, v0, v1, v2)
                    lookups += c
                    if not ok:
                        gt = g1
                        par = s
                        hop = mcost[m]
            if t >= 0:
                if gt < ng[tu]:
                    ng[tu] = gt
                    fv = _heap.fkey(filed_f(gt, nh[tu], hop, ends, cmin), f0, fq, fq_inv)
                    npar[tu] = par
                    if plain:
                        _heap.decrease_key(heap, npos, t, fv, gt)
                    else:
                        hn, sn = _heap.pq_decrease(heap, npos, hn, sn, fcur, t, fv, gt)
                continue
            t = n  # a new node
            tn = np.uint64(t)
            n += 1
            if dense:
                dsl[loc] = t + 1
                nkey[tn] = ks + mkey[m]  # packed keys are linear inside the grid's box
            else:
                pages[loc] = t
                nkey[tn] = pack3(v0, v1, v2)
            x0, x1, x2 = gl0 - v0, gl1 - v1, gl2 - v2
            if lazy_v:  # its move set's heuristic is the straight line (kernel.search_run)
                hv = hw * length(gm, x0, x1, x2)
            elif gauge:  # over one facet of each antipodal pair (DenseTables.hhalf)
                hv = half_gauge(hhalf, habs, x0, x1, x2)
            else:
                hv = node_estimate(oct_s, hkind, hmat, hw, gm, x0, x1, x2)
            nh[tn] = hv
            ng[tn] = gt
            npar[tn] = par
            fv = _heap.fkey(filed_f(gt, hv, hop, ends, cmin), f0, fq, fq_inv)
            if plain:
                hn = _heap.push(heap, npos, hn, t, fv, gt)
            else:
                hn, sn = _heap.pq_push(heap, npos, hn, sn, fcur, t, fv, gt)
    if status != RUN_FOUND:  # the arrays may be copied or the search resumed
        hn = _heap.pq_flush(heap, npos, hn, sn, fcur)
    st.nodes = n
    st.queued = hn
    st.expansions = expansions
    st.lookups = lookups
    return status
