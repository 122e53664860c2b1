"""The exact segment walk (numba): every cell whose closed Voronoi cell a segment touches.

:class:`Walk` holds a lattice's data for the walk (generator, Voronoi-relevant vectors, full
adjacency), as C-contiguous arrays of one dtype each so that every lattice shares one
compiled kernel; :func:`walk_of` builds it once per lattice. :func:`segment_walk` and
:func:`walk_on` (on caller-owned scratch) find the touched cells, optionally stopping at
the first one the :class:`~planner.occupancy.grid.Occupancy` says is not free.
"""

from __future__ import annotations

from functools import lru_cache
from typing import NamedTuple

import numpy as np

from planner._numba import njit_cached
from planner.errors import PlanError
from planner.lattice import Lattice
from planner.lattice import quantize as qk
from planner.occupancy.facewalk import SEG_TOL, face_table  # SEG_TOL: boundary contact counts
from planner.occupancy.grid import cell_free
from planner.occupancy.keys import mix64, pack3

__all__ = ["SEG_TOL", "Walk", "as_cells", "c_array", "motion_free", "segment_walk", "walk_of",
           "walk_on", "walk_scratch"]

_FWD_SLACK = 1e-6  # cosine below which a full offset counts as backward (walk_on)


class Walk(NamedTuple):
    """Lattice data of the exact segment walk. Arrays C-contiguous and writable."""

    g: np.ndarray  # (3, 3) float64 generator (m)
    rel: np.ndarray  # (R, 3) float64 Voronoi-relevant vectors (m)
    rhs: np.ndarray  # (R,) float64 |v|^2 / 2
    full: np.ndarray  # (F, 3) int64 full-adjacency offsets
    wv: np.ndarray  # (R, 3) float64 rel @ g: c_u . v = wv . u for the cell at offset u
    fd: np.ndarray  # float64 the sight walk's face table, packed (facewalk.FaceTable)
    fi: np.ndarray  # int64 its integer part


# -- kernels --------------------------------------------------------------------
@njit_cached(_nrt=False)
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


@njit_cached
def walk_scratch(length, step, nfull):  # pragma: no cover - compiled
    """Scratch for :func:`walk_on` sized for segments up to ``length`` (m): visited-set keys,
    their generation stamps (an entry is live iff its stamp is the walk's generation, so a
    reused table needs no clearing) and the BFS queue. ``step``: shortest relevant vector."""
    est = (int(length / step) + 4) * (nfull + 1)
    size = 64
    while size < 2 * est:
        size *= 2
    return (np.empty(size, dtype=np.int64), np.zeros(size, dtype=np.int64),
            np.empty((max(64, est // 4), 3), dtype=np.int64))


@njit_cached
def walk_on(occ, walk, a, b, s, check, vis, vgen, gen, queue):
    # pragma: no cover - compiled
    """Core of :func:`segment_walk` on caller-owned scratch (see :func:`walk_scratch`;
    ``gen`` must differ from every stamp already in ``vgen``). Returns ``(n, all_free,
    lookups, ok)`` with the touched cells' offsets from ``s`` in ``queue[:n]``; ``ok`` is
    False when the scratch was too small (retry with more). No array is reassigned in the
    loop: numba then keeps reference counting out of it."""
    mode, grid, lo, dims, table, tmask, gg, blo, bhi = occ
    rel, rhs, full, wv = walk.rel, walk.rhs, walk.full, walk.wv
    nrel = rel.shape[0]
    c0 = gg @ s.astype(np.float64)
    av = np.empty(nrel)
    dq = np.empty(nrel)
    for r in range(nrel):
        x = (a[0] - c0[0]) * rel[r, 0] + (a[1] - c0[1]) * rel[r, 1] + (a[2] - c0[2]) * rel[r, 2]
        av[r] = rhs[r] * (1.0 + SEG_TOL) - x
        y = (b[0] - a[0]) * rel[r, 0] + (b[1] - a[1]) * rel[r, 1] + (b[2] - a[2]) * rel[r, 2]
        dq[r] = 1.0 / y if y != 0.0 else 0.0
    # Forward offsets only: every touched cell but the start has a touched full neighbour
    # it is entered from, at an offset f with (b - a) . (G f) >= 0 (the segment crosses
    # their shared boundary moving away from that neighbour's centre). Backward offsets
    # (beyond a small angular slack for the boundary tolerance) are skipped: about half
    # of the candidates, each a hash probe and a clip.
    nf = full.shape[0]
    fwd = np.int64(-1)
    if nf <= 63:
        fwd = np.int64(0)
        dn = np.sqrt((b[0] - a[0]) ** 2 + (b[1] - a[1]) ** 2 + (b[2] - a[2]) ** 2)
        for f in range(nf):
            x0 = gg[0, 0] * full[f, 0] + gg[0, 1] * full[f, 1] + gg[0, 2] * full[f, 2]
            x1 = gg[1, 0] * full[f, 0] + gg[1, 1] * full[f, 1] + gg[1, 2] * full[f, 2]
            x2 = gg[2, 0] * full[f, 0] + gg[2, 1] * full[f, 1] + gg[2, 2] * full[f, 2]
            dot = (b[0] - a[0]) * x0 + (b[1] - a[1]) * x1 + (b[2] - a[2]) * x2
            if dot >= -_FWD_SLACK * dn * np.sqrt(x0 * x0 + x1 * x1 + x2 * x2):
                fwd |= np.int64(1) << f
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
        if not cell_free(mode, grid, lo, dims, table, tmask, gg, blo, bhi, s[0], s[1], s[2]):
            free = False
    while qh < qt and free:
        u0 = queue[qh, 0]
        u1 = queue[qh, 1]
        u2 = queue[qh, 2]
        qh += 1
        for f in range(nf):
            if not (fwd >> f) & 1:
                continue
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
                if not cell_free(mode, grid, lo, dims, table, tmask, gg, blo, bhi,
                             s[0] + v0, s[1] + v1, s[2] + v2):
                    free = False
                    break
    return qt, free, lookups, True


@njit_cached
def segment_walk(occ, walk, a, b, s, check):  # pragma: no cover - compiled
    """Cells whose closed Voronoi cell the segment [a, b] touches, by BFS from cell ``s``
    (the cell containing ``a``) over full adjacency, keeping only touched cells (the touched
    set is connected under full adjacency, so the BFS finds all of it).

    With ``check`` each touched cell is looked up and the walk stops at the first blocked
    one. Returns ``(cells (K, 3) int64, all_free, lookups)``.
    """
    length = np.sqrt(((b - a) ** 2).sum())
    while True:
        vis, vgen, queue = walk_scratch(length, np.sqrt(2.0 * walk.rhs.min()),
                                        walk.full.shape[0])
        # np.int64(1), not 1: a literal would compile walk_on once more for Literal[int](1)
        qt, free, lookups, ok = walk_on(occ, walk, a, b, s, check, vis, vgen, np.int64(1),
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


@njit_cached
def motion_free(occ, walk, quant, a0, a1, a2, b0, b1, b2, buf, out):  # pragma: no cover
    """Exact segment test a -> b (m): ``(all touched cells free, lookups made)``."""
    buf[0, 0] = a0
    buf[0, 1] = a1
    buf[0, 2] = a2
    buf[1, 0] = b0
    buf[1, 1] = b1
    buf[1, 2] = b2
    qk.quantize_generic3(buf[:1], quant.basis, quant.basis_inv, quant.cand, quant.cand_z,
                         quant.counts, quant.reduction, out)
    _, free, n = segment_walk(occ, walk, buf[0], buf[1], out[0], True)
    return free, n


# -- Python side ---------------------------------------------------------------------------
_INT64 = np.dtype(np.int64)


def as_cells(indices) -> np.ndarray:
    """``indices`` as C-contiguous int64 cells (N, 3); PlanError for another shape or dtype."""
    if (type(indices) is np.ndarray and indices.dtype == _INT64 and indices.ndim == 2
            and indices.shape[1] == 3 and indices.flags.c_contiguous):
        return indices  # a search's path: the checks below cost a microsecond
    w = np.asarray(indices)
    if w.ndim == 1 and w.shape[0] == 3:
        w = w[None]
    if w.ndim != 2 or w.shape[1] != 3:
        raise PlanError(f"cells must have shape (N, 3), got {w.shape}")
    if w.size and not np.issubdtype(w.dtype, np.integer):
        raise PlanError(f"cells must be integer lattice indices, got dtype {w.dtype}")
    return np.ascontiguousarray(w, dtype=np.int64)


def c_array(a, dtype) -> np.ndarray:
    """A fresh C-contiguous writable copy: one numba type for every lattice (MCC's generator
    is not C-contiguous, cached lattice arrays are read-only)."""
    return np.array(a, dtype=dtype, order="C", copy=True)


@lru_cache(maxsize=64)
def _walk_cached(gen: bytes, lattice: Lattice) -> Walk:
    g = c_array(lattice.generator, float)
    rel = c_array(lattice.relevant_vectors, float)
    ft = face_table(lattice)
    return Walk(g, rel, c_array(0.5 * np.einsum("ij,ij->i", rel, rel), float),
                c_array(lattice.neighbors("full"), np.int64), c_array(rel @ g, float),
                *(c_array(a, a.dtype) for a in ft))


def walk_of(lattice: Lattice) -> Walk:
    """The segment-walk struct of a lattice (cached; shared, do not write)."""
    return _walk_cached(lattice.generator.tobytes(), lattice)
