"""Line of sight between cell centres (numba): the exact segment walk of the validity
checker (:mod:`planner.occupancy.walk`) on reusable scratch, and path shortcutting.

Two cells see each other iff every cell whose closed Voronoi cell the centre-to-centre
segment touches is free (the same test as a motion check of :class:`planner.world.
ValidityChecker`). On the cubic lattice those cells are enumerated directly, with no walk
search: by nested clipping (:func:`cubic_sight`, the reference) and, faster, by integer
stepping from cell to cell (:func:`cubic_walk`, used by the searches and shortcutting);
on every other lattice by the face walk (:func:`planner.occupancy.facewalk.face_walk`,
from Voronoi cell to cell through the facet the segment leaves by), the generic walk
taking over only at a tie the face walk's table does not know. Tests check that each
accepts and rejects exactly as the generic walk's cells say.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from planner._numba import njit_cached
from planner.occupancy.facewalk import I_SM, face_scratch, face_walk
from planner.occupancy.grid import cell_free, occ_free
from planner.occupancy.walk import SEG_TOL, segment_walk, walk_on, walk_scratch


class SightScratch(NamedTuple):
    """Reusable scratch of the walks: the generic walk's (see ``walk_scratch``), two cell
    buffers and the face walk's."""

    vis: np.ndarray  # (S,) int64 visited keys
    vgen: np.ndarray  # (S,) int64 generation stamp per entry
    queue: np.ndarray  # (Q, 3) int64 BFS queue
    p: np.ndarray  # (3,) int64
    q: np.ndarray  # (3,) int64
    sf: np.ndarray  # float64 the face walk's scratch (facewalk.face_scratch)
    si: np.ndarray  # int64


def new_scratch(span: float, walk) -> SightScratch:
    """Scratch for sight lines up to ``span`` metres (the generic walk, needed only where
    the face walk meets a tie it does not know, falls back to fresh arrays for longer
    ones)."""
    vis, vgen, queue = walk_scratch(span, math.sqrt(2.0 * walk.rhs.min()), len(walk.full))
    sf, si = face_scratch(int(walk.fi[I_SM]))
    return SightScratch(vis, vgen, queue, np.empty(3, np.int64), np.empty(3, np.int64), sf, si)


@njit_cached(_nrt=False)
def _clip(u, dk, h, t0, t1):  # pragma: no cover - compiled
    """[t0, t1] cut to the t where |t dk - u| <= h (one axis of a cubic cell)."""
    if dk > 0:
        return max(t0, (u - h) / dk), min(t1, (u + h) / dk)
    if dk < 0:
        return max(t0, (u + h) / dk), min(t1, (u - h) / dk)
    if abs(u) <= h:
        return t0, t1
    return 1.0, 0.0


@njit_cached(_nrt=False)
def _span(x0, x1, h, dk):  # pragma: no cover - compiled
    """Cells (first, count, step) whose axis interval [c - h, c + h] meets [x0, x1] (either
    order), listed in the segment's direction ``dk``."""
    lo = np.int64(np.ceil(min(x0, x1) - h))
    hi = np.int64(np.floor(max(x0, x1) + h))
    if dk < 0:
        return hi, hi - lo + 1, -1
    return lo, hi - lo + 1, 1


@njit_cached
def cubic_sight(occ, p, q):  # pragma: no cover - compiled
    """:func:`los` on the cubic lattice without the walk's search: the cells whose closed
    cube (widened by the walk's tolerance) meets the centre-to-centre segment, enumerated
    by nested clipping (x cells, then y cells within each x cell's t range, then z), in
    index units with p at the origin. Same cells as the generic walk; each costs a few
    divisions and one lookup. Returns ``(free, lookups)``."""
    h = 0.5 * (1.0 + SEG_TOL)
    d0 = np.float64(q[0] - p[0])
    d1 = np.float64(q[1] - p[1])
    d2 = np.float64(q[2] - p[2])
    lookups = 0
    i, ni, si = _span(0.0, d0, h, d0)
    for _ in range(ni):
        a0, a1 = _clip(i, d0, h, 0.0, 1.0)
        if a0 <= a1:
            j, nj, sj = _span(a0 * d1, a1 * d1, h, d1)
            for _ in range(nj):
                b0, b1 = _clip(j, d1, h, a0, a1)
                if b0 <= b1:
                    k, nk, sk = _span(b0 * d2, b1 * d2, h, d2)
                    for _ in range(nk):
                        c0, c1 = _clip(k, d2, h, b0, b1)
                        if c0 <= c1:
                            lookups += 1
                            if not occ_free(occ, p[0] + i, p[1] + j, p[2] + k):
                                return False, lookups
                        k += sk
                j += sj
        i += si
    return True, lookups


@njit_cached(_nrt=False)
def _bit(grid, f):  # pragma: no cover - compiled
    """:func:`planner.occupancy.grid.bit_free` for a flat index known to be inside the box:
    an unsigned index spares numba's negative-index fix-up on every load of the walk."""
    return (grid[np.uint64(f) >> np.uint64(3)] >> (f & 7)) & 1 != 0


DDA_MAX = 1 << 19  # longest axis extent (cells) of the integer walk: keys stay < 2**63


@njit_cached(_nrt=False)
def _keys(a0, a1, a2):  # pragma: no cover - compiled
    """The first crossing key per axis and its increment (:func:`cubic_walk`), for axis
    extents ``a`` (cells)."""
    b0, b1, b2 = max(a0, 1), max(a1, 1), max(a2, 1)
    big = np.int64(1) << np.int64(62)
    k0 = b1 * b2 if a0 else big
    k1 = b0 * b2 if a1 else big
    k2 = b0 * b1 if a2 else big
    return k0, k1, k2, 2 * k0, 2 * k1, 2 * k2


@njit_cached(_nrt=False)
def dense_walk(grid, lo, dims, p0, p1, p2, q0, q1, q2):  # pragma: no cover - compiled
    """:func:`cubic_walk` on a dense grid (``grid``, ``lo``, ``dims`` of the
    :class:`~planner.occupancy.grid.Occupancy`) between two cells inside its box, no axis
    extent above ``DDA_MAX``. Takes the arrays themselves: an inlined walk that unpacks
    the struct pays reference counting on its arrays per call, a third of a short walk.
    Returns ``(free, lookups)``."""
    d0, d1, d2 = q0 - p0, q1 - p1, q2 - p2
    k0, k1, k2, i0, i1, i2 = _keys(abs(d0), abs(d1), abs(d2))
    t1, t2 = dims[2], dims[1] * dims[2]
    # flat index steps
    e0 = t2 if d0 > 0 else -t2
    e1 = t1 if d1 > 0 else -t1
    e2 = 1 if d2 > 0 else -1
    idx = ((p0 - lo[0]) * dims[1] + (p1 - lo[1])) * dims[2] + (p2 - lo[2])
    lookups = 1
    if not _bit(grid, idx):
        return False, lookups
    left = abs(d0) + abs(d1) + abs(d2)
    # Without branches on the step axis, which changes unpredictably from step to step
    # (x is 0 or 1, so -x is a mask): no mispredicted branch per cell.
    while left > 0:
        m = min(k0, min(k1, k2))
        x0 = np.int64(k0 == m)
        x1 = np.int64(k1 == m)
        x2 = np.int64(k2 == m)
        n = x0 + x1 + x2
        if n > 1:  # an edge or a corner: the side cells first (every proper subset)
            for sub in range(1, 7):
                u0 = sub & 1
                u1 = (sub >> 1) & 1
                u2 = sub >> 2
                if u0 > x0 or u1 > x1 or u2 > x2 or u0 + u1 + u2 == n:
                    continue
                lookups += 1
                if not _bit(grid, idx + e0 * u0 + e1 * u1 + e2 * u2):
                    return False, lookups
        idx += (e0 & -x0) + (e1 & -x1) + (e2 & -x2)
        k0 += i0 & -x0
        k1 += i1 & -x1
        k2 += i2 & -x2
        left -= n
        lookups += 1
        if not _bit(grid, idx):
            return False, lookups
    return True, lookups


# The runtime asked for explicitly (a callee otherwise inherits its caller's setting): it
# allocates, and cubic_walk, compiled without reference counting (which cannot allocate),
# calls it.
@njit_cached(_nrt=True)
def _far_sight(occ, p0, p1, p2, q0, q1, q2):  # pragma: no cover - compiled
    """:func:`cubic_sight` between cells given by components (:func:`cubic_walk`'s lines
    too long for its integer keys)."""
    p = np.empty(3, np.int64)
    q = np.empty(3, np.int64)
    p[0], p[1], p[2] = p0, p1, p2
    q[0], q[1], q[2] = q0, q1, q2
    return cubic_sight(occ, p, q)


@njit_cached(_nrt=False)
def cubic_walk(occ, p0, p1, p2, q0, q1, q2):  # pragma: no cover - compiled
    """:func:`cubic_sight` by integer stepping (a 3D DDA), cell by cell from p to q,
    stopping at the first blocked cell. Returns ``(free, lookups)``.

    Between integer centres the segment crosses the plane between cells ``n`` and ``n + 1``
    of axis k (|d_k| crossings in all) at t = (2n + 1) / (2 |d_k|); comparing these times
    as integers (``key_k`` = t times 2 |d_0 d_1 d_2|, the zero extents taken as 1) orders
    the crossings exactly. The walk's tolerance only matters where crossings of several
    axes coincide exactly (two distinct crossing times differ by at least
    1 / (2 |d_i d_j|), far above the tolerance window of ~1e-9 / |d|): there the segment
    passes through an edge or corner and touches every cell around it, so all
    2**k - 1 cells beyond the current one are looked up. Same cells as the clipping.
    Inside a dense grid's box: :func:`dense_walk`."""
    d0, d1, d2 = q0 - p0, q1 - p1, q2 - p2
    a0, a1, a2 = abs(d0), abs(d1), abs(d2)
    if max(a0, max(a1, a2)) > DDA_MAX:  # keys would overflow: the float clipping
        return _far_sight(occ, p0, p1, p2, q0, q1, q2)
    # Unpacked once: the lookups below take the arrays themselves.
    mode, grid, lo, dims, table, tmask, gg, blo, bhi = occ
    dense = mode == 0
    if dense:
        for r in range(3):
            x = (p0, p1, p2)[r] - lo[r]
            y = (q0, q1, q2)[r] - lo[r]
            if x < 0 or y < 0 or x >= dims[r] or y >= dims[r]:
                dense = False  # a box outside the grid: the general lookup
    if dense:
        return dense_walk(grid, lo, dims, p0, p1, p2, q0, q1, q2)
    s0 = 1 if d0 > 0 else -1
    s1 = 1 if d1 > 0 else -1
    s2 = 1 if d2 > 0 else -1
    k0, k1, k2, i0, i1, i2 = _keys(a0, a1, a2)
    c0, c1, c2 = p0, p1, p2
    lookups = 1
    if not cell_free(mode, grid, lo, dims, table, tmask, gg, blo, bhi, c0, c1, c2):
        return False, lookups
    left = a0 + a1 + a2
    while left > 0:
        m = min(k0, min(k1, k2))
        x0, x1, x2 = k0 == m, k1 == m, k2 == m
        n = np.int64(x0) + np.int64(x1) + np.int64(x2)
        if n > 1:  # an edge or a corner: the side cells first (every proper subset)
            for sub in range(1, 7):
                u0 = (sub & 1) != 0
                u1 = (sub & 2) != 0
                u2 = (sub & 4) != 0
                if (u0 and not x0) or (u1 and not x1) or (u2 and not x2):
                    continue
                if np.int64(u0) + np.int64(u1) + np.int64(u2) == n:
                    continue
                lookups += 1
                if not cell_free(mode, grid, lo, dims, table, tmask, gg, blo, bhi,
                                 c0 + s0 * u0, c1 + s1 * u1, c2 + s2 * u2):
                    return False, lookups
        if x0:
            c0 += s0
            k0 += i0
        if x1:
            c1 += s1
            k1 += i1
        if x2:
            c2 += s2
            k2 += i2
        left -= n
        lookups += 1
        if not cell_free(mode, grid, lo, dims, table, tmask, gg, blo, bhi, c0, c1, c2):
            return False, lookups
    return True, lookups


@njit_cached(_nrt=False)
def is_cubic(g):  # pragma: no cover - compiled
    """The generator is a cubic lattice's: orthogonal columns of one length, so a multiple
    of the identity, possibly turned (the benchmark suite's rotated worlds) or reflected.
    A similarity maps each cube Voronoi cell onto its image, so a segment between cell
    centres touches the same cells in index space as on the unturned lattice, and the
    integer walk applies. Tolerance: 1e-12 of the squared cell edge (rounding of a turned
    generator)."""
    e = g[0, 0] * g[0, 0] + g[1, 0] * g[1, 0] + g[2, 0] * g[2, 0]
    tol = 1e-12 * e
    for i in range(3):
        for j in range(i, 3):
            d = g[0, i] * g[0, j] + g[1, i] * g[1, j] + g[2, i] * g[2, j]
            if abs(d - (e if i == j else 0.0)) > tol:
                return False
    return True


@njit_cached(_nrt=False)
def cubic_edge(g):  # pragma: no cover - compiled
    """A cubic generator's cell edge (m): the length of its first column (``|g[0, 0]|``
    exactly when it is unturned)."""
    return math.sqrt(g[0, 0] * g[0, 0] + g[1, 0] * g[1, 0] + g[2, 0] * g[2, 0])


@njit_cached(_nrt=True)  # it allocates: as _far_sight, for loops without the runtime
def _generic_los(occ, walk, p, q, sc, gen):  # pragma: no cover - compiled
    """:func:`los` by the generic walk (the face walk's unknown ties)."""
    g = walk.g
    a = g @ p.astype(np.float64)
    b = g @ q.astype(np.float64)
    # np.bool_, not a literal True: the callers' other call sites pass a bool value, and a
    # literal would compile a second specialisation
    stop = np.bool_(True)
    _, free, n, ok = walk_on(occ, walk, a, b, p, stop, sc.vis, sc.vgen, gen, sc.queue)
    if not ok:  # longer than the scratch was sized for: walk again on fresh arrays
        _, free, n = segment_walk(occ, walk, a, b, p, stop)
    return free, n


# Without the runtime: one that counted references would pay an atomic increment and
# decrement per array of the three structs on every sight line, more than a short walk.
# The face walk is inlined here, with its error model (no zero-division checks).
@njit_cached(_nrt=False, error_model="numpy")
def los(occ, walk, p, q, sc, gen):  # pragma: no cover - compiled
    """Line of sight between the centres of cells p and q ((3,) int64 each) on scratch ``sc``
    with a fresh generation ``gen``: the cubic integer walk, else the face walk (else, at a
    tie its table does not know, the generic walk). Returns ``(free, lookups)``."""
    if is_cubic(walk.g):
        return cubic_walk(occ, p[0], p[1], p[2], q[0], q[1], q[2])
    free, n, ok = face_walk(occ, walk.fd, walk.fi, sc.sf, sc.si, p[0], p[1], p[2], q[0], q[1],
                            q[2])
    if ok:
        return free, n
    return _generic_los(occ, walk, p, q, sc, gen)


# Inlined into the search loop with the face walk: a call of either would pass the
# arrays of its structs (some 90 words or more) on every sight test of the loop.
@njit_cached(_nrt=False, error_model="numpy", inline="always")
def sight(occ, walk, sc, st, p0, p1, p2, q0, q1, q2):  # pragma: no cover - compiled
    """:func:`los` between cells p and q given by components, inside a search: the
    generation counter is the search state's ``stamp`` (:mod:`planner.search._state`)."""
    if is_cubic(walk.g):
        return cubic_walk(occ, p0, p1, p2, q0, q1, q2)
    free, n, ok = face_walk(occ, walk.fd, walk.fi, sc.sf, sc.si, p0, p1, p2, q0, q1, q2)
    if ok:
        return free, n
    sc.p[0] = p0
    sc.p[1] = p1
    sc.p[2] = p2
    sc.q[0] = q0
    sc.q[1] = q1
    sc.q[2] = q2
    st.stamp += 1
    return los(occ, walk, sc.p, sc.q, sc, st.stamp)


@njit_cached
def shortcut_kernel(occ, walk, cells, sc, gen):  # pragma: no cover - compiled
    """Shortcutting by galloping, then one pass dropping kept cells. O(log k) sight tests
    for a jump of k cells (a forward scan, one test per later cell, walks O(k^2) cells).

    Gallop from each kept cell i: test sight to i + 2, i + 4, i + 8, ... (capped at the last
    cell) until a test fails or the last cell is in sight; then bisect between the last
    cell found in sight (``lo``; at first i + 1, kept untested: consecutive input cells
    not in sight of each other, a corner-cutting path's, stay) and the first out of sight
    (``hi``) until they are neighbours, and keep ``lo``. Sight along a path is not
    monotone, so ``lo`` need not be the farthest cell in sight; it is never nearer than
    the forward scan's (``hi`` is out of sight: at or past the first cell that is).
    Drop pass: a kept cell goes when the last cell kept before it sees the next one.
    Every kept pair is in sight (or consecutive in the input): the path is as free as a
    sight line, and no longer than the input (triangle inequality).

    ``gen``: the last generation stamped in ``sc`` (0 when new). Returns ``(kept indices
    into cells, lookups, last generation stamped)``."""
    n = cells.shape[0]
    keep = np.empty(n, dtype=np.int64)
    keep[0] = 0
    nk, lookups, i = 1, 0, 0
    while i < n - 1:
        lo, hi, d = i + 1, n, 2  # lo in sight of i (or next to it); hi: first not (n: none)
        while lo < n - 1:  # gallop
            j = min(i + d, n - 1)
            gen += 1
            ok, c = los(occ, walk, cells[i], cells[j], sc, gen)
            lookups += c
            if not ok:
                hi = j
                break
            lo, d = j, 2 * d
        while hi - lo > 1:  # bisect (hi < n here)
            m = (lo + hi) // 2
            gen += 1
            ok, c = los(occ, walk, cells[i], cells[m], sc, gen)
            lookups += c
            if ok:
                lo = m
            else:
                hi = m
        keep[nk] = lo
        nk += 1
        i = lo
    out = 1  # drop pass, in place: keep[:out] is decided
    for k in range(1, nk - 1):
        gen += 1
        ok, c = los(occ, walk, cells[keep[out - 1]], cells[keep[k + 1]], sc, gen)
        lookups += c
        if not ok:
            keep[out] = keep[k]
            out += 1
    if nk > 1:
        keep[out] = keep[nk - 1]
        out += 1
    return keep[:out].copy(), lookups, gen


@njit_cached(_nrt=False)
def sight_batch(occ, walk, ps, qs, sc, free, lookups):  # pragma: no cover - compiled
    """:func:`los` between the centres of ``ps[i]`` and ``qs[i]`` for every i ((N, 3)
    int64 each), into ``free`` ((N,) bool) and ``lookups`` ((N,) int64, the cells looked
    up for that line). Returns the total lookups."""
    total = 0
    for i in range(ps.shape[0]):
        ok, n = los(occ, walk, ps[i], qs[i], sc, np.int64(i + 1))
        free[i] = ok
        lookups[i] = n
        total += n
    return total


@njit_cached(_nrt=False)
def longest_segment(g, ps, qs):  # pragma: no cover - compiled
    """The longest centre-to-centre segment ``ps[i]`` -> ``qs[i]`` (m; ``g`` the (3, 3)
    generator): sizes :func:`new_scratch` for :func:`sight_batch` in one pass, with no
    temporary arrays."""
    best = 0.0
    for i in range(ps.shape[0]):
        d0 = qs[i, 0] - ps[i, 0]
        d1 = qs[i, 1] - ps[i, 1]
        d2 = qs[i, 2] - ps[i, 2]
        s = 0.0
        for r in range(3):
            x = g[r, 0] * d0 + g[r, 1] * d1 + g[r, 2] * d2
            s += x * x
        best = max(best, s)
    return math.sqrt(best)


@njit_cached(_nrt=False)
def reach(g, cells):  # pragma: no cover - compiled
    """Twice the farthest centre of ``cells`` ((K, 3) int64) from the first's (m; ``g`` the
    (3, 3) generator): no sight line between two of them is longer. Sizes
    :func:`new_scratch` for :func:`shortcut_kernel` in one pass."""
    best = 0.0
    for i in range(1, cells.shape[0]):
        s = 0.0
        for r in range(3):
            x = 0.0
            for k in range(3):
                x += g[r, k] * (cells[i, k] - cells[0, k])
            s += x * x
        best = max(best, s)
    return 2.0 * math.sqrt(best)
