"""Compiled (numba) kernels of the search engine: occupancy lookup, exact segment walk, A*.

Everything here works on plain numpy arrays and small tuples so that it compiles once and
caches on disk (``cache=True``). The occupancy structure is a tuple

``occ = (mode, grid, lo, dims, table, tmask, gmat, blo, bhi)``

* ``mode`` 0 (dense): ``grid`` is a flat uint8 array over the index box ``lo + [0, dims)``
  holding 1 for every cell that is in bounds and not blocked; any index outside the box is
  out of bounds. One byte load per lookup.
* ``mode`` 1 (hash): ``table`` is an open-addressing set (size ``tmask + 1``, a power of
  two, load <= 0.5, empty slots -1) of packed keys of blocked cells; a cell is free iff its
  centre ``gmat @ w`` lies in ``[blo, bhi]`` (bounds already widened by the tolerance) and
  its key is not in the table.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from planner.keys import pack3, unpack3

_EMPTY = -1
_SEG_TOL = 1e-9  # relative slack on each Voronoi half-space: boundary contact counts


# -- hashing -------------------------------------------------------------------------------
@njit(cache=True, inline="always")
def mix64(key):  # pragma: no cover - compiled
    """splitmix64 finaliser: packed keys of neighbouring cells differ in few low bits."""
    x = np.uint64(key)
    x = (x ^ (x >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
    x = (x ^ (x >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
    x = x ^ (x >> np.uint64(31))
    return np.int64(x >> np.uint64(1))


@njit(cache=True)
def build_key_set(keys, size):  # pragma: no cover - compiled
    """Open-addressing set of non-negative int64 keys; ``size`` a power of two >= 2 len."""
    table = np.full(size, _EMPTY, dtype=np.int64)
    mask = size - 1
    for i in range(keys.shape[0]):
        k = keys[i]
        p = mix64(k) & mask
        while table[p] != _EMPTY and table[p] != k:
            p = (p + 1) & mask
        table[p] = k
    return table


@njit(cache=True, inline="always")
def _in_set(table, mask, k):  # pragma: no cover - compiled
    p = mix64(k) & mask
    while True:
        t = table[p]
        if t == k:
            return True
        if t == _EMPTY:
            return False
        p = (p + 1) & mask


# -- occupancy -----------------------------------------------------------------------------
@njit(cache=True, inline="always")
def _free(mode, grid, lo, dims, table, tmask, g, blo, bhi, i, j, k):  # pragma: no cover
    """True iff cell (i, j, k) is in bounds and not blocked (one occupancy lookup).

    Takes the occupancy tuple's members (unpacked once by the caller) and is inlined:
    a non-inlined call with array arguments costs ~50 ns of reference counting."""
    if mode == 0:
        a = i - lo[0]
        b = j - lo[1]
        c = k - lo[2]
        if a < 0 or b < 0 or c < 0 or a >= dims[0] or b >= dims[1] or c >= dims[2]:
            return False
        return grid[(a * dims[1] + b) * dims[2] + c] != 0
    for r in range(3):
        x = g[r, 0] * i + g[r, 1] * j + g[r, 2] * k
        if x < blo[r] or x > bhi[r]:
            return False
    return not _in_set(table, tmask, pack3(i, j, k))


@njit(cache=True)
def cell_free(occ, i, j, k):  # pragma: no cover - compiled
    """One lookup through the occupancy tuple (for cold paths)."""
    mode, grid, lo, dims, table, tmask, g, blo, bhi = occ
    return _free(mode, grid, lo, dims, table, tmask, g, blo, bhi, i, j, k)


@njit(cache=True)
def free_many(occ, w, out):  # pragma: no cover - compiled
    mode, grid, lo, dims, table, tmask, g, blo, bhi = occ
    for n in range(w.shape[0]):
        out[n] = _free(mode, grid, lo, dims, table, tmask, g, blo, bhi, w[n, 0], w[n, 1], w[n, 2])


@njit(cache=True)
def fill_in_bounds(grid, lo, dims, g, blo, bhi):  # pragma: no cover - compiled
    """grid[cell] = 1 iff the cell centre lies in [blo, bhi] (dense mode construction)."""
    for a in range(dims[0]):
        i = lo[0] + a
        for b in range(dims[1]):
            j = lo[1] + b
            base = (a * dims[1] + b) * dims[2]
            for c in range(dims[2]):
                k = lo[2] + c
                ok = True
                for r in range(3):
                    x = g[r, 0] * i + g[r, 1] * j + g[r, 2] * k
                    if x < blo[r] or x > bhi[r]:
                        ok = False
                        break
                grid[base + c] = 1 if ok else 0


@njit(cache=True)
def clear_cells(grid, lo, dims, w):  # pragma: no cover - compiled
    """Mark the listed cells (N, 3) not free in a dense grid (cells outside are ignored)."""
    for n in range(w.shape[0]):
        a = w[n, 0] - lo[0]
        b = w[n, 1] - lo[1]
        c = w[n, 2] - lo[2]
        if 0 <= a < dims[0] and 0 <= b < dims[1] and 0 <= c < dims[2]:
            grid[(a * dims[1] + b) * dims[2] + c] = 0


# -- exact segment walk --------------------------------------------------------------------
@njit(cache=True, inline="always")
def _touches(u0, u1, u2, lim0, idq, wv, rhs):  # pragma: no cover - compiled
    """Does the segment a + t (b - a), t in [0, 1], meet the closed Voronoi cell of the cell
    at index offset u (relative to the walk's start cell)? Clip t against each half-space
    ``(x - c_u) . v <= |v|^2 / 2``. Precomputed per walk (no division here):
    ``lim0 = |v|^2 / 2 (1 + tol) - (a - c_start) . v``, ``idq = 1 / ((b - a) . v)`` (0 when
    the segment is parallel to the facet), ``wv = rel @ G`` (so ``c_u . v = wv . u``)."""
    lo = 0.0
    hi = 1.0
    for r in range(rhs.shape[0]):
        lim = lim0[r] + (wv[r, 0] * u0 + wv[r, 1] * u1 + wv[r, 2] * u2)
        q = idq[r]
        if q > 0.0:
            t = lim * q
            if t < hi:
                hi = t
        elif q < 0.0:
            t = lim * q
            if t > lo:
                lo = t
        elif lim < 0.0:
            return False
        if lo > hi:
            return False
    return True


@njit(cache=True)
def walk_scratch(length, step, nfull):  # pragma: no cover - compiled
    """Scratch for :func:`_walk` sized for segments up to ``length`` (m): visited-set keys,
    their generation stamps (an entry is live iff its stamp is the walk's generation, so a
    reused table needs no clearing) and the BFS queue. ``step``: shortest relevant vector."""
    est = (int(length / step) + 4) * (nfull + 1)
    size = 64
    while size < 2 * est:
        size *= 2
    return (np.empty(size, dtype=np.int64), np.zeros(size, dtype=np.int64),
            np.empty((max(64, est // 4), 3), dtype=np.int64))


@njit(cache=True)
def _walk(occ, a, b, s, rel, rhs, full, wv, check, vis, vgen, gen, queue):
    # pragma: no cover - compiled
    """Core of :func:`segment_walk` on caller-owned scratch (see :func:`walk_scratch`;
    ``gen`` must differ from every stamp already in ``vgen``). Returns ``(n, all_free,
    lookups, ok)`` with the touched cells' offsets from ``s`` in ``queue[:n]``; ``ok`` is
    False when the scratch was too small (retry with more). No array is reassigned in the
    loop: numba then keeps reference counting out of it (measured ~10x)."""
    mode, grid, lo, dims, table, tmask, gg, blo, bhi = occ
    nrel = rel.shape[0]
    c0 = gg @ s.astype(np.float64)
    av = np.empty(nrel)
    dq = np.empty(nrel)
    for r in range(nrel):
        x = (a[0] - c0[0]) * rel[r, 0] + (a[1] - c0[1]) * rel[r, 1] + (a[2] - c0[2]) * rel[r, 2]
        av[r] = rhs[r] * (1.0 + _SEG_TOL) - x
        y = (b[0] - a[0]) * rel[r, 0] + (b[1] - a[1]) * rel[r, 1] + (b[2] - a[2]) * rel[r, 2]
        dq[r] = 1.0 / y if y != 0.0 else 0.0
    size = vis.shape[0]
    mask = size - 1
    qcap = queue.shape[0]
    lookups = 0
    free = True
    k0 = pack3(0, 0, 0)
    p = mix64(k0) & mask
    vis[p] = k0
    vgen[p] = gen
    nvis = 1
    queue[0, 0] = 0
    queue[0, 1] = 0
    queue[0, 2] = 0
    qh = 0
    qt = 1
    if check:
        lookups += 1
        if not _free(mode, grid, lo, dims, table, tmask, gg, blo, bhi, s[0], s[1], s[2]):
            free = False
    while qh < qt and free:
        u0 = queue[qh, 0]
        u1 = queue[qh, 1]
        u2 = queue[qh, 2]
        qh += 1
        for f in range(full.shape[0]):
            v0 = u0 + full[f, 0]
            v1 = u1 + full[f, 1]
            v2 = u2 + full[f, 2]
            kk = pack3(v0, v1, v2)
            p = mix64(kk) & mask
            seen = False
            while vgen[p] == gen:
                if vis[p] == kk:
                    seen = True
                    break
                p = (p + 1) & mask
            if seen:
                continue
            vis[p] = kk
            vgen[p] = gen
            nvis += 1
            if 2 * nvis > size:  # keep load <= 0.5
                return qt, free, lookups, False
            if not _touches(v0, v1, v2, av, dq, wv, rhs):
                continue
            if qt == qcap:
                return qt, free, lookups, False
            queue[qt, 0] = v0
            queue[qt, 1] = v1
            queue[qt, 2] = v2
            qt += 1
            if check:
                lookups += 1
                if not _free(mode, grid, lo, dims, table, tmask, gg, blo, bhi,
                             s[0] + v0, s[1] + v1, s[2] + v2):
                    free = False
                    break
    return qt, free, lookups, True


@njit(cache=True)
def segment_walk(occ, a, b, s, g, rel, rhs, full, check):  # pragma: no cover - compiled
    """Cells whose closed Voronoi cell the segment [a, b] touches, by BFS from cell ``s``
    (the cell containing ``a``) over full adjacency, keeping only touched cells (the touched
    set is connected under full adjacency, so the BFS finds all of it).

    With ``check`` each touched cell is looked up and the walk stops at the first blocked
    one. Returns ``(cells (K, 3) int64, all_free, lookups)``.
    """
    length = np.sqrt(((b - a) ** 2).sum())
    wv = rel @ g
    while True:
        vis, vgen, queue = walk_scratch(length, np.sqrt(2.0 * rhs.min()), full.shape[0])
        qt, free, lookups, ok = _walk(occ, a, b, s, rel, rhs, full, wv, check, vis, vgen, 1,
                                      queue)
        if ok:
            break
        length = 2.0 * length + 1.0
    out = queue[:qt].copy()
    for n in range(qt):
        out[n, 0] += s[0]
        out[n, 1] += s[1]
        out[n, 2] += s[2]
    return out, free, lookups


@njit(cache=True)
def _los(occ, p, q, g, rel, rhs, full, wv, vis, vgen, gen, queue):
    # pragma: no cover - compiled
    """Line of sight between the centres of cells p and q (both (3,) int64), on scratch."""
    a = g @ p.astype(np.float64)
    b = g @ q.astype(np.float64)
    _, free, n, ok = _walk(occ, a, b, p, rel, rhs, full, wv, True, vis, vgen, gen, queue)
    if not ok:  # longer than the scratch was sized for: walk again on fresh arrays
        _, free, n = segment_walk(occ, a, b, p, g, rel, rhs, full, True)
    return free, n


@njit(cache=True)
def shortcut_kernel(occ, cells, g, rel, rhs, full):  # pragma: no cover - compiled
    """Greedy shortcutting: from each kept cell go to the farthest later cell still in
    sight (scanning forward, stopping at the first cell out of sight). Consecutive input
    cells that are not in sight of each other (corner-cutting paths) are kept as they are.
    Returns ``(kept indices into cells, lookups)``."""
    n = cells.shape[0]
    keep = np.empty(n, dtype=np.int64)
    nk = 0
    lookups = 0
    wv = rel @ g
    span = 0.0
    for x in range(1, n):  # longest possible sight line: first cell to the farthest one
        d = g @ (cells[x] - cells[0]).astype(np.float64)
        span = max(span, np.sqrt((d * d).sum()))
    vis, vgen, queue = walk_scratch(2.0 * span, np.sqrt(2.0 * rhs.min()), full.shape[0])
    gen = 0
    i = 0
    keep[nk] = 0
    nk += 1
    while i < n - 1:
        j = i + 1
        while j + 1 < n:
            gen += 1
            ok, c = _los(occ, cells[i], cells[j + 1], g, rel, rhs, full, wv, vis, vgen, gen,
                         queue)
            lookups += c
            if not ok:
                break
            j += 1
        keep[nk] = j
        nk += 1
        i = j
    return keep[:nk].copy(), lookups


# -- A* family -----------------------------------------------------------------------------
@njit(cache=True, inline="always")
def _better(hf, hg, i, j):  # pragma: no cover - compiled
    # Lower f first; among equal f the deeper node (larger g) first: fewer expansions.
    return hf[i] < hf[j] or (hf[i] == hf[j] and hg[i] > hg[j])


# The heap keeps each entry's f and g next to its slot (hf, hg): sifting then compares
# contiguous memory instead of chasing slots into the node table (a cache miss per level).
@njit(cache=True, inline="always")
def _put(heap, hf, hg, pos, i, x, xf, xg):  # pragma: no cover - compiled
    heap[i] = x
    hf[i] = xf
    hg[i] = xg
    pos[x] = i


@njit(cache=True, inline="always")
def _sift_up(heap, hf, hg, pos, i):  # pragma: no cover - compiled
    x, xf, xg = heap[i], hf[i], hg[i]
    while i > 0:
        parent = (i - 1) >> 1
        if not (xf < hf[parent] or (xf == hf[parent] and xg > hg[parent])):
            break
        _put(heap, hf, hg, pos, i, heap[parent], hf[parent], hg[parent])
        i = parent
    _put(heap, hf, hg, pos, i, x, xf, xg)


@njit(cache=True, inline="always")
def _sift_down(heap, hf, hg, pos, i, n):  # pragma: no cover - compiled
    x, xf, xg = heap[i], hf[i], hg[i]
    while True:
        c = 2 * i + 1
        if c >= n:
            break
        if c + 1 < n and _better(hf, hg, c + 1, c):
            c += 1
        if not (hf[c] < xf or (hf[c] == xf and hg[c] > xg)):
            break
        _put(heap, hf, hg, pos, i, heap[c], hf[c], hg[c])
        i = c
    _put(heap, hf, hg, pos, i, x, xf, xg)


@njit(cache=True, inline="always")
def _heuristic(hkind, hmat, g, d0, d1, d2):  # pragma: no cover - compiled
    """h of the index difference d = goal - w: 0 (Dijkstra), the move-set gauge
    max_f hmat[f] . d (A*), or the Euclidean length |G d| (any-angle)."""
    if hkind == 0:
        return 0.0
    if hkind == 1:
        best = 0.0
        for f in range(hmat.shape[0]):
            v = hmat[f, 0] * d0 + hmat[f, 1] * d1 + hmat[f, 2] * d2
            if v > best:
                best = v
        return best
    x = g[0, 0] * d0 + g[0, 1] * d1 + g[0, 2] * d2
    y = g[1, 0] * d0 + g[1, 1] * d1 + g[1, 2] * d2
    z = g[2, 0] * d0 + g[2, 1] * d1 + g[2, 2] * d2
    return np.sqrt(x * x + y * y + z * z)


@njit(cache=True, inline="always")
def _dist(g, p0, p1, p2, q0, q1, q2):  # pragma: no cover - compiled
    return _heuristic(2, g, g, q0 - p0, q1 - p1, q2 - p2)


# Slots of the int64 state vector shared by the resumable search kernel and its driver.
ST_N, ST_HN, ST_EXP, ST_LOOK, ST_GOAL, ST_NP, ST_WGEN = 0, 1, 2, 3, 4, 5, 6

# Cell -> node slot map: pages of PAGE int32 slots, one per touched PB x PB x PB block of
# cells, found through a small open-addressing table of block keys. Neighbouring cells share
# a page, so a lookup is usually a cached-page hit plus one nearby load: memory stays
# proportional to the region the search touches, with near-dense-array locality.
PB_SHIFT = 2
PB_MASK = (1 << PB_SHIFT) - 1
PAGE = 1 << (3 * PB_SHIFT)


@njit(cache=True, inline="always")
def _local(v0, v1, v2):  # pragma: no cover - compiled
    return ((v0 & PB_MASK) << (2 * PB_SHIFT)) | ((v1 & PB_MASK) << PB_SHIFT) | (v2 & PB_MASK)


@njit(cache=True, inline="always")
def _block_key(v0, v1, v2):  # pragma: no cover - compiled
    return pack3(v0 >> PB_SHIFT, v1 >> PB_SHIFT, v2 >> PB_SHIFT)


@njit(cache=True)
def _find_slot(pages, btab, bkeys, v0, v1, v2):  # pragma: no cover - compiled
    """Node slot of cell (v0, v1, v2), or -1 when the search has not generated it."""
    bmask = btab.shape[0] - 1
    bk = _block_key(v0, v1, v2)
    p = mix64(bk) & bmask
    while True:
        q = btab[p]
        if q == _EMPTY:
            return _EMPTY
        if bkeys[q] == bk:
            return np.int64(pages[q * PAGE + _local(v0, v1, v2)])
        p = (p + 1) & bmask


@njit(cache=True)
def _new_page(pages, btab, bkeys, st, bk, p):  # pragma: no cover - compiled
    q = st[ST_NP]
    st[ST_NP] = q + 1
    btab[p] = q
    bkeys[q] = bk
    for i in range(q * PAGE, (q + 1) * PAGE):
        pages[i] = _EMPTY
    return q
RUN_EXHAUSTED, RUN_FOUND, RUN_LIMIT, RUN_GROW = 0, 1, 2, 3


@njit(cache=True)
def search_init(start, goal, nkey, ng, nf, nh, npar, npos, heap, hf, hg, pages, btab, bkeys,
                hmat, hkind, g, st):  # pragma: no cover - compiled
    """Put the start node in empty node arrays (slot 0), the slot map and the heap."""
    bmask = btab.shape[0] - 1
    sk = pack3(start[0], start[1], start[2])
    nkey[0] = sk
    ng[0] = 0.0
    nh[0] = _heuristic(hkind, hmat, g, goal[0] - start[0], goal[1] - start[1],
                       goal[2] - start[2])
    nf[0] = nh[0]
    npar[0] = 0
    heap[0] = 0
    hf[0] = nf[0]
    hg[0] = 0.0
    npos[0] = 0
    st[ST_NP] = 0
    bk = _block_key(start[0], start[1], start[2])
    q = _new_page(pages, btab, bkeys, st, bk, mix64(bk) & bmask)
    pages[q * PAGE + _local(start[0], start[1], start[2])] = 0
    st[ST_N] = 1
    st[ST_HN] = 1


@njit(cache=True)
def rehash(btab, bkeys, npages):  # pragma: no cover - compiled
    """Insert pages 0..npages-1 (by their block keys) into an empty block table."""
    bmask = btab.shape[0] - 1
    for x in range(npages):
        q = mix64(bkeys[x]) & bmask
        while btab[q] != _EMPTY:
            q = (q + 1) & bmask
        btab[q] = x


@njit(cache=True, inline="always")
def _sight(occ, st, pt, qt, p0, p1, p2, q0, q1, q2, g, rel, rhs, full, wv, wvis, wgen, wq):
    # pragma: no cover - compiled
    """Line of sight between cells p and q inside the search, on its scratch (pt, qt and
    the walk's visited set, with a fresh generation from ``st[ST_WGEN]``)."""
    pt[0] = p0
    pt[1] = p1
    pt[2] = p2
    qt[0] = q0
    qt[1] = q1
    qt[2] = q2
    st[ST_WGEN] += 1
    return _los(occ, pt, qt, g, rel, rhs, full, wv, wvis, wgen, st[ST_WGEN], wq)


@njit(cache=True)
def search_run(
    occ, goal, st, nkey, ng, nf, nh, npar, npos, heap, hf, hg, pages, btab, bkeys, ufree,
    moves, mcost, ust, mptr, midx, hmat, hkind, anyangle, g, rel, rhs, full, max_nodes,
    wv, wvis, wgen, wq,
):  # pragma: no cover - compiled
    """A* / Dijkstra / Theta* / Lazy Theta* over lattice cells, resumable.

    The node arrays are fixed-size inside the kernel: before each expansion it checks that
    the arrays and the hash table (load <= 0.5) can take every possible new node, else it
    returns ``RUN_GROW`` and the driver doubles them and calls again. Not reassigning arrays
    inside the loop lets numba drop per-iteration reference counting (measured ~10x).

    Parameters
    ----------
    occ : tuple
        Occupancy structure (module docstring).
    goal : (3,) int64
    st : (5,) int64
        State: node count, heap size, expansions, lookups, goal slot.
    nkey, ng, nf, nh, npar, npos, heap : (cap,) arrays
        Node table (packed key, g, f, h, parent slot, heap position or -1 closed / -2 new)
        and the binary heap of slots.
    hf, hg : (cap,) float64
        f and g of each heap entry, kept beside it.
    pages : (P * PAGE,) int32, btab : (T,) int64, bkeys : (P,) int64
        Cell -> node slot map (-1 none): pages of one block of cells each, and the
        open-addressing table (T a power of two, -1 empty) from block key to page.
    ufree : (U,) bool
        Scratch for the union stencil lookups.
    moves : (M, 3) int64, mcost : (M,) float64
        Move offsets and their world lengths.
    ust : (U, 3) int64
        Union stencil: every cell offset some move needs free (looked up once per expansion).
    mptr : (M + 1,) int64, midx : (nnz,) int64
        CSR lists: move m needs ``ust[midx[mptr[m]:mptr[m + 1]]]`` free.
    hmat : (F, 3) float64
        Heuristic facets in index coordinates; ``hkind`` 0 zero, 1 facets, 2 Euclidean.
    anyangle : int
        0 lattice A*, 1 Theta*, 2 Lazy Theta*.
    g, rel, rhs, full
        Generator, relevant vectors (world), ``|v|^2/2``, full-adjacency offsets (for the
        line-of-sight walk).
    max_nodes : int
        Stop once this many nodes exist (<= 0: no limit).
    wv, wvis, wgen, wq
        ``rel @ g`` and line-of-sight scratch (:func:`walk_scratch`); the generation
        counter lives in ``st[ST_WGEN]``.

    Returns
    -------
    int
        RUN_FOUND, RUN_EXHAUSTED, RUN_LIMIT or RUN_GROW.
    """
    mode, grid, lo, dims, otable, otmask, gg, blo, bhi = occ
    lo0, lo1, lo2 = lo[0], lo[1], lo[2]
    d0, d1, d2 = dims[0], dims[1], dims[2]
    gl0, gl1, gl2 = goal[0], goal[1], goal[2]
    g00, g01, g02 = g[0, 0], g[0, 1], g[0, 2]
    g10, g11, g12 = g[1, 0], g[1, 1], g[1, 2]
    g20, g21, g22 = g[2, 0], g[2, 1], g[2, 2]
    nfac = hmat.shape[0]
    cap = nkey.shape[0]
    pcap = bkeys.shape[0]
    bsize = btab.shape[0]
    bmask = bsize - 1
    last_bk = np.int64(-1)
    last_pg = np.int64(0)
    nu = ust.shape[0]
    nm = moves.shape[0]
    pt = np.empty(3, dtype=np.int64)
    qt = np.empty(3, dtype=np.int64)
    gk = pack3(goal[0], goal[1], goal[2])
    fq = 1e-9 * mcost.min()
    fq_inv = 1.0 / fq
    n = st[ST_N]
    hn = st[ST_HN]
    expansions = st[ST_EXP]
    lookups = st[ST_LOOK]
    status = RUN_EXHAUSTED
    while hn > 0:
        if n + nm > cap or st[ST_NP] + nm > pcap or 2 * (st[ST_NP] + nm) > bsize:
            status = RUN_GROW
            break
        s = heap[0]
        hn -= 1
        if hn > 0:
            heap[0] = heap[hn]
            hf[0] = hf[hn]
            hg[0] = hg[hn]
            npos[heap[0]] = 0
            _sift_down(heap, hf, hg, npos, 0, hn)
        npos[s] = -1
        expansions += 1
        u0, u1, u2 = unpack3(nkey[s])
        if mode == 0:
            # Dense grid lookups written out here: numba does not reliably inline the
            # helper inside this large loop and a call costs ~50 ns of refcounting.
            for j in range(nu):
                a = u0 + ust[j, 0] - lo0
                b = u1 + ust[j, 1] - lo1
                c = u2 + ust[j, 2] - lo2
                ufree[j] = (a >= 0 and b >= 0 and c >= 0 and a < d0 and b < d1 and c < d2
                            and grid[(a * d1 + b) * d2 + c] != 0)
        else:
            for j in range(nu):
                ufree[j] = _free(mode, grid, lo, dims, otable, otmask, gg, blo, bhi,
                                 u0 + ust[j, 0], u1 + ust[j, 1], u2 + ust[j, 2])
        lookups += nu
        if anyangle == 2 and npar[s] != s:
            # Lazy Theta* SetVertex: verify the assumed line of sight to the parent; else
            # take the best closed neighbour (one exists: the node that generated s).
            p0, p1, p2 = unpack3(nkey[npar[s]])
            ok, c = _sight(occ, st, pt, qt, p0, p1, p2, u0, u1, u2, g, rel, rhs, full, wv,
                           wvis, wgen, wq)
            lookups += c
            if not ok:
                best = np.inf
                bp = -1
                for m in range(nm):
                    allowed = True
                    for e in range(mptr[m], mptr[m + 1]):
                        if not ufree[midx[e]]:
                            allowed = False
                            break
                    if not allowed:
                        continue
                    t = _find_slot(pages, btab, bkeys, u0 + moves[m, 0], u1 + moves[m, 1],
                                   u2 + moves[m, 2])
                    if t == _EMPTY or npos[t] != -1:
                        continue
                    v = ng[t] + mcost[m]
                    if v < best:
                        best = v
                        bp = t
                npar[s] = bp
                ng[s] = best
        if nkey[s] == gk:
            status = RUN_FOUND
            st[ST_GOAL] = s
            break
        if max_nodes > 0 and n >= max_nodes:
            status = RUN_LIMIT
            break
        ps = npar[s]
        if anyangle != 0 and ps != s:
            p0, p1, p2 = unpack3(nkey[ps])
        else:
            p0, p1, p2 = u0, u1, u2
        for m in range(nm):
            v0 = u0 + moves[m, 0]
            v1 = u1 + moves[m, 1]
            v2 = u2 + moves[m, 2]
            bk = _block_key(v0, v1, v2)
            if bk != last_bk:
                p = mix64(bk) & bmask
                while True:
                    q = btab[p]
                    if q == _EMPTY or bkeys[q] == bk:
                        break
                    p = (p + 1) & bmask
                if q == _EMPTY:
                    q = _new_page(pages, btab, bkeys, st, bk, p)
                last_bk = bk
                last_pg = q
            loc = last_pg * PAGE + _local(v0, v1, v2)
            t = np.int64(pages[loc])
            if t != _EMPTY and npos[t] == -1:
                continue  # closed: a consistent heuristic never improves it
            # Safe rule after the closed test: most neighbours of an expanded cell are closed.
            allowed = True
            for e in range(mptr[m], mptr[m + 1]):
                if not ufree[midx[e]]:
                    allowed = False
                    break
            if not allowed:
                continue
            if t == _EMPTY:
                t = n
                n += 1
                pages[loc] = t
                nkey[t] = pack3(v0, v1, v2)
                ng[t] = np.inf
                e0 = gl0 - v0
                e1 = gl1 - v1
                e2 = gl2 - v2
                hv = 0.0
                if hkind == 1:  # written out for the same reason as the lookups
                    for f in range(nfac):
                        x = hmat[f, 0] * e0 + hmat[f, 1] * e1 + hmat[f, 2] * e2
                        if x > hv:
                            hv = x
                elif hkind == 2:
                    x = g00 * e0 + g01 * e1 + g02 * e2
                    y = g10 * e0 + g11 * e1 + g12 * e2
                    z = g20 * e0 + g21 * e1 + g22 * e2
                    hv = np.sqrt(x * x + y * y + z * z)
                nh[t] = hv
                npos[t] = -2
            if anyangle == 0:
                gt = ng[s] + mcost[m]
                par = s
            elif anyangle == 2 or ps == s:
                gt = ng[ps] + _dist(g, p0, p1, p2, v0, v1, v2)
                par = ps
            else:
                ok, c = _sight(occ, st, pt, qt, p0, p1, p2, v0, v1, v2, g, rel, rhs, full, wv,
                               wvis, wgen, wq)
                lookups += c
                if ok:
                    gt = ng[ps] + _dist(g, p0, p1, p2, v0, v1, v2)
                    par = ps
                else:
                    gt = ng[s] + mcost[m]
                    par = s
            if gt < ng[t]:
                ng[t] = gt
                # f on a 1e-9-cell grid: equal-cost paths tie exactly (float noise would
                # otherwise decide), so the larger-g tie-break can dive; costs stay exact.
                nf[t] = np.floor((gt + nh[t]) * fq_inv + 0.5) * fq
                npar[t] = par
                if npos[t] == -2:
                    heap[hn] = t
                    hf[hn] = nf[t]
                    hg[hn] = gt
                    hn += 1
                    _sift_up(heap, hf, hg, npos, hn - 1)
                else:
                    i = npos[t]
                    hf[i] = nf[t]
                    hg[i] = gt
                    _sift_up(heap, hf, hg, npos, i)
    st[ST_N] = n
    st[ST_HN] = hn
    st[ST_EXP] = expansions
    st[ST_LOOK] = lookups
    return status


@njit(cache=True)
def trace_path(nkey, npar, goal_slot):  # pragma: no cover - compiled
    """Packed keys from the start (its own parent) to ``goal_slot``."""
    k = 1
    x = goal_slot
    while npar[x] != x:
        x = npar[x]
        k += 1
    path = np.empty(k, dtype=np.int64)
    x = goal_slot
    for i in range(k - 1, -1, -1):
        path[i] = nkey[x]
        x = npar[x]
    return path
