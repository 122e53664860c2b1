"""The strongest compiled A* floor we can build, called in this process: what our engine's
A* is measured against.

Usage::

    python benchmarks/cpp_anchor.py                      # every map: ours / the floor
    python benchmarks/cpp_anchor.py --queries 200 --repeat 3 --maps DA1
    python benchmarks/cpp_anchor.py --check-all          # the floor on all Warframe costs
    python benchmarks/cpp_anchor.py --axes natural       # both sides in the map's own order
    python benchmarks/cpp_anchor.py --variants           # the floor with each trick off
    python benchmarks/cpp_anchor.py --floor "children in turn"   # against one variant
    python benchmarks/cpp_anchor.py --smoke              # a small synthetic map, seconds

The floor: cubic lattice, 26 neighbours with MovingAI's no-corner-cutting rule (a move is
allowed only when every voxel of its bounding box is free), step costs 1, sqrt(2), sqrt(3),
the exact octile heuristic and the project's tie-break (lower f first, f rounded to 1e-9 so
that equal-cost paths tie exactly, then larger g). Written with every trick we know for a
grid A* of this kind:

* a bit grid padded by one blocked voxel (no bounds tests; 1/8 of a byte grid's cache
  footprint): the 27-cell neighbourhood is nine 3-bit reads, one per row, into a mask,
  and each move's required cells are one AND and compare against it;
* an int32 slot map (cell -> node record, -1 untouched, negative again once closed, so a
  closed neighbour costs no record read; reset per query by walking the records made, so
  nothing proportional to the map is cleared) and compact 24-byte node
  records (g, cell, heap position, coordinates: the heuristic needs no division);
* a 4-ary heap with decrease-key for nodes above the current f, and a side heap (larger g
  first) for the current f plateau: on a grid with an octile heuristic most generated nodes
  keep their parent's f, so they never enter the main heap; a sift-down picks the best of
  four children as a tournament without branches (the two pairs at once, then their
  winners: two compares deep instead of three, and no mispredicted branch);
* a byte grid built beside the bit grid: each query's floor time is the faster of the two
  (they win on different maps by a few per cent; ``--variants`` measures each trick);
* the map's longest axis made the fastest-varying one (``--axes longest``, the default):
  the floor and our planner get the same permutation of the map (our planner by permuted
  coordinates: the same world, turned), so neither side pays for a badly ordered map.

Built with the system compiler (``g++ -O3 -march=native``) into a shared library and called
through ctypes: no separate process. The query loop is a library function (not ``main``).
Both sides are timed the same way, by this thread's CPU time around one call (ours:
``planner.search.search``; the floor: one ctypes call), taking turns per query, the fastest
of ``--repeat`` rounds each. It must reproduce the MovingAI Warframe optimal costs
(``../shared/data/warframe/*.3dmap`` and ``.3dscen``): mismatches are printed and make the
exit status 1. geb079 is read by the package's OctoMap reader at 0.08 m.

Also the floor behind ``search_speed.py`` (:func:`run`) and ``scaling.py``
(:func:`run_measured`). Skipped with one line when there is no C++ compiler.
"""

from __future__ import annotations

import argparse
import ctypes
import functools
import math
import shutil
import subprocess
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import harness  # noqa: E402  (the sibling module)

SOURCE = r"""
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <ctime>

// Each trick can be switched off (benchmarks/cpp_anchor.py --variants measures each one):
// ARITY 2 (a binary heap), SIDE_HEAP 0 (no plateau heap), BIT_GRID 0 (a byte grid),
// SLOT_CLOSED 0 (a closed node is known by its record, not by its slot map entry),
// TOURNAMENT 0 (a sift-down scans the four children in turn instead of comparing the two
// pairs at once, then their winners, without branches). SPLIT_NODES 1 is no trick but our
// engine's layout: each node field in an array of its own instead of one 24-byte record.
#ifndef ARITY
#define ARITY 4
#endif
#ifndef TOURNAMENT
#define TOURNAMENT 1
#endif
#ifndef SIDE_HEAP
#define SIDE_HEAP 1
#endif
#ifndef BIT_GRID
#define BIT_GRID 1
#endif
#ifndef SLOT_CLOSED
#define SLOT_CLOSED 1
#endif
#ifndef SPLIT_NODES
#define SPLIT_NODES 0
#endif
#if BIT_GRID
#define FREE(v) ((F->bits[(v) >> 3] >> ((v) & 7)) & 1)
#else
#define FREE(v) (F->bits[v])
#endif

// One map: a padded bit grid in C order (the last axis fastest) and the per-query arrays.
struct Node { double g; int32_t v; int32_t pos; int16_t x, y, z, pad; };  // 24 bytes
struct Entry { double f, g; int32_t n, pad; };                               // 24 bytes
static const int32_t CLOSED = -1, SIDE = -2;

struct Floor {
    int64_t A, B, C;            // padded dims; cell v = (a * B + b) * C + c
    uint8_t* bits;              // bit (byte) v set = free (8 bytes of slack at the end)
    int32_t* slot;              // cell -> node index, -1 untouched, -2 - index when closed
    Node* nodes; int64_t nn, ncap;
    double* ng; int32_t* nv; int32_t* npos; int16_t *nx, *ny, *nz;   // SPLIT_NODES
    Entry* heap; int64_t hn, hcap;   // main heap: f above the plateau (4-ary)
    Entry* side; int64_t sn, scap;   // plateau heap: f == the current f (binary, larger g)
    int64_t roff[9];            // row offsets of the neighbourhood's 9 rows, minus 1
    int64_t mv[26]; int mda[26], mdb[26], mdc[26]; double mc[26]; uint32_t need[26];
    int64_t bytes;
};

// A node's fields: one 24-byte record, or (SPLIT_NODES) one array per field.
#if SPLIT_NODES
#define NG(n) (F->ng[n])
#define NV(n) (F->nv[n])
#define NPOS(n) (F->npos[n])
#define NX(n) (F->nx[n])
#define NY(n) (F->ny[n])
#define NZ(n) (F->nz[n])
#else
#define NG(n) (F->nodes[n].g)
#define NV(n) (F->nodes[n].v)
#define NPOS(n) (F->nodes[n].pos)
#define NX(n) (F->nodes[n].x)
#define NY(n) (F->nodes[n].y)
#define NZ(n) (F->nodes[n].z)
#endif

static inline bool before(const Entry& a, const Entry& b) {   // lower f, then larger g
    return a.f < b.f || (a.f == b.f && a.g > b.g);
}

static inline bool before_nb(const Entry& a, const Entry& b) {   // before(), no branches
    return (a.f < b.f) | ((a.f == b.f) & (a.g > b.g));
}

template <class T> static T* grow(T* p, int64_t& cap, Floor* F) {
    int64_t n = cap ? 2 * cap : 1024;
    F->bytes += (n - cap) * (int64_t)sizeof(T);
    cap = n;
    return (T*)std::realloc(p, n * sizeof(T));
}

// Room for twice the nodes (the first call: 1024), in the layout SPLIT_NODES picks.
static void grow_nodes(Floor* F) {
#if SPLIT_NODES
    int64_t c = F->ncap, c2;
    c2 = c; F->ng = grow(F->ng, c2, F);
    c2 = c; F->nv = grow(F->nv, c2, F);
    c2 = c; F->npos = grow(F->npos, c2, F);
    c2 = c; F->nx = grow(F->nx, c2, F);
    c2 = c; F->ny = grow(F->ny, c2, F);
    c2 = c; F->nz = grow(F->nz, c2, F);
    F->ncap = c2;
#else
    F->nodes = grow(F->nodes, F->ncap, F);
#endif
}
static inline void set_node(Floor* F, int64_t j, double g, int32_t v, int16_t x, int16_t y,
                            int16_t z) {
    NG(j) = g; NV(j) = v; NPOS(j) = SIDE; NX(j) = x; NY(j) = y; NZ(j) = z;
}

// 4-ary main heap with decrease-key (positions in Node::pos).
static inline void h_up(Floor* F, int64_t i, const Entry& e) {
    Entry* a = F->heap;
    while (i > 0) {
        int64_t p = (int64_t)((uint64_t)(i - 1) / ARITY);
        if (!before(e, a[p])) break;
        a[i] = a[p]; NPOS(a[i].n) = (int32_t)i; i = p;
    }
    a[i] = e; NPOS(e.n) = (int32_t)i;
}
static inline void h_down(Floor* F, int64_t i, const Entry& e) {
    Entry* a = F->heap; const int64_t n = F->hn;
    for (;;) {
        int64_t c = ARITY * i + 1;
        if (c >= n) break;
        int64_t best = c, end = c + ARITY < n ? c + ARITY : n;
#if TOURNAMENT && ARITY == 4
        if (end == c + 4) {   // branch-free; the earlier child wins a tie, as in the scan
            int64_t x = c + (int64_t)before_nb(a[c + 1], a[c]);
            int64_t y = c + 2 + (int64_t)before_nb(a[c + 3], a[c + 2]);
            best = before_nb(a[y], a[x]) ? y : x;
        } else
#endif
        for (int64_t k = c + 1; k < end; ++k) if (before(a[k], a[best])) best = k;
        if (!before(a[best], e)) break;
        a[i] = a[best]; NPOS(a[i].n) = (int32_t)i; i = best;
    }
    a[i] = e; NPOS(e.n) = (int32_t)i;
}
static inline void h_push(Floor* F, const Entry& e) {
    if (F->hn == F->hcap) F->heap = grow(F->heap, F->hcap, F);
    h_up(F, F->hn++, e);
}
static inline Entry h_pop(Floor* F) {
    Entry top = F->heap[0];
    Entry last = F->heap[--F->hn];
    if (F->hn) h_down(F, 0, last);
    return top;
}
static inline void h_remove(Floor* F, int64_t i) {   // take out the entry at i
    Entry last = F->heap[--F->hn];
    if (i == F->hn) return;
    if (before(last, F->heap[i])) h_up(F, i, last); else h_down(F, i, last);
}
// Side heap: the plateau, larger g first; lazy (a better g pushes again, stale skipped).
static inline void s_push(Floor* F, const Entry& e) {
    if (F->sn == F->scap) F->side = grow(F->side, F->scap, F);
    Entry* a = F->side; int64_t i = F->sn++;
    while (i > 0) { int64_t p = (i - 1) >> 1; if (a[p].g >= e.g) break; a[i] = a[p]; i = p; }
    a[i] = e;
}
static inline Entry s_pop(Floor* F) {
    Entry* a = F->side; Entry top = a[0], last = a[--F->sn];
    int64_t n = F->sn, i = 0;
    for (;;) {
        int64_t c = 2 * i + 1;
        if (c >= n) break;
        if (c + 1 < n && a[c + 1].g > a[c].g) ++c;
        if (a[c].g <= last.g) break;
        a[i] = a[c]; i = c;
    }
    if (n) a[i] = last;
    return top;
}

extern "C" {

// free: uint8 (na, nb, nc) C order, nonzero = free. Returns NULL when the map is too large.
Floor* floor_new(const uint8_t* free, int64_t na, int64_t nb, int64_t nc) {
    if (na > 32000 || nb > 32000 || nc > 32000) return nullptr;
    Floor* F = (Floor*)std::calloc(1, sizeof(Floor));
    F->A = na + 2; F->B = nb + 2; F->C = nc + 2;
    const int64_t cells = F->A * F->B * F->C;
    if (cells >= (int64_t)1 << 31) { std::free(F); return nullptr; }
    const int64_t nbytes = (BIT_GRID ? (cells + 7) / 8 : cells) + 8;
    F->bits = (uint8_t*)std::calloc(nbytes, 1);
    for (int64_t a = 0; a < na; ++a)
        for (int64_t b = 0; b < nb; ++b) {
            const uint8_t* row = free + (a * nb + b) * nc;
            int64_t v = ((a + 1) * F->B + (b + 1)) * F->C + 1;
            for (int64_t c = 0; c < nc; ++c, ++v)
                if (row[c]) {
#if BIT_GRID
                    F->bits[v >> 3] |= (uint8_t)(1u << (v & 7));
#else
                    F->bits[v] = 1;
#endif
                }
        }
    F->slot = (int32_t*)std::malloc(cells * sizeof(int32_t));
    std::memset(F->slot, 0xff, cells * sizeof(int32_t));
    F->bytes = nbytes + cells * (int64_t)sizeof(int32_t) + (int64_t)sizeof(Floor);
    // Mask bit (da + 1) * 9 + (db + 1) * 3 + (dc + 1) is the cell at offset (da, db, dc).
    for (int r = 0; r < 9; ++r) F->roff[r] = ((r / 3 - 1) * F->B + (r % 3 - 1)) * F->C - 1;
    int m = 0;
    for (int da = -1; da <= 1; ++da)
    for (int db = -1; db <= 1; ++db)
    for (int dc = -1; dc <= 1; ++dc) {
        if (!da && !db && !dc) continue;
        uint32_t need = 0;
        for (int ca = (da < 0 ? da : 0); ca <= (da > 0 ? da : 0); ++ca)
        for (int cb = (db < 0 ? db : 0); cb <= (db > 0 ? db : 0); ++cb)
        for (int cc = (dc < 0 ? dc : 0); cc <= (dc > 0 ? dc : 0); ++cc)
            if (ca || cb || cc) need |= 1u << ((ca + 1) * 9 + (cb + 1) * 3 + cc + 1);
        F->need[m] = need; F->mda[m] = da; F->mdb[m] = db; F->mdc[m] = dc;
        F->mv[m] = (da * F->B + db) * F->C + dc;
        F->mc[m] = std::sqrt((double)(da * da + db * db + dc * dc));
        ++m;
    }
    return F;
}

void floor_free(Floor* F) {
    if (!F) return;
    std::free(F->bits); std::free(F->slot); std::free(F->nodes); std::free(F->heap);
    std::free(F->side); std::free(F->ng); std::free(F->nv); std::free(F->npos);
    std::free(F->nx); std::free(F->ny); std::free(F->nz); std::free(F);
}

int64_t floor_bytes(const Floor* F) { return F->bytes; }

// One query, cells in the unpadded box. Returns expansions; *cost = path cost in cells
// (-1 when unreachable or an end is blocked or outside).
int64_t floor_search(Floor* F, int64_t sa, int64_t sb, int64_t sc,
                     int64_t ga, int64_t gb, int64_t gc, double* cost) {
    *cost = -1.0;
    const int64_t B = F->B, C = F->C;
    if (sa < 0 || sb < 0 || sc < 0 || ga < 0 || gb < 0 || gc < 0 || sa >= F->A - 2 ||
        ga >= F->A - 2 || sb >= B - 2 || gb >= B - 2 || sc >= C - 2 || gc >= C - 2) return 0;
    const int32_t s = (int32_t)(((sa + 1) * B + sb + 1) * C + sc + 1);
    const int32_t t = (int32_t)(((ga + 1) * B + gb + 1) * C + gc + 1);
    const uint8_t* bits = F->bits;
    if (!FREE(s) || !FREE(t)) return 0;
    const int32_t tx = (int32_t)ga + 1, ty = (int32_t)gb + 1, tz = (int32_t)gc + 1;
    const double s2m1 = std::sqrt(2.0) - 1.0, s3m2 = std::sqrt(3.0) - std::sqrt(2.0);
    auto h = [&](int32_t x, int32_t y, int32_t z) {   // octile: hi + (r2-1) mid + (r3-r2) lo
        int32_t a = std::abs(x - tx), b = std::abs(y - ty), c = std::abs(z - tz);
        int32_t hi = a > b ? a : b; hi = hi > c ? hi : c;
        int32_t lo = a < b ? a : b; lo = lo < c ? lo : c;
        return (double)hi + s2m1 * (double)(a + b + c - hi - lo) + s3m2 * (double)lo;
    };
    // f on a 1e-9 grid, as ours: equal-cost paths tie exactly.
    auto fkey = [](double f) { return std::floor(f * 1e9 + 0.5) * 1e-9; };
    F->nn = 0; F->hn = 0; F->sn = 0;
    if (F->ncap == 0) grow_nodes(F);
    set_node(F, 0, 0.0, s, (int16_t)(sa + 1), (int16_t)(sb + 1), (int16_t)(sc + 1));
    F->slot[s] = 0; F->nn = 1;
    double fcur = fkey(h((int32_t)sa + 1, (int32_t)sb + 1, (int32_t)sc + 1));
    if (SIDE_HEAP) s_push(F, {fcur, 0.0, 0, 0}); else h_push(F, {fcur, 0.0, 0, 0});
    int64_t exp = 0;
    int32_t* slot = F->slot;
    for (;;) {
        int32_t n;
        if (SIDE_HEAP && F->sn &&
            (F->hn == 0 || F->heap[0].f > fcur || F->side[0].g >= F->heap[0].g)) {
            const Entry e = s_pop(F);
            if (NPOS(e.n) != SIDE || e.g != NG(e.n)) continue;   // stale: closed or bettered
            n = e.n;
        } else if (F->hn) {
            const Entry e = h_pop(F);
            fcur = e.f; n = e.n;
        } else break;
        const int32_t cur_v = NV(n);
        const double cur_g = NG(n);
        const int16_t cur_x = NX(n), cur_y = NY(n), cur_z = NZ(n);
        NPOS(n) = CLOSED; ++exp;
        if (SLOT_CLOSED) slot[cur_v] = -2 - n;   // a closed neighbour costs no record read
        if (cur_v == t) { *cost = cur_g; break; }
        uint32_t nb = 0;
        for (int r = 0; r < 9; ++r) {
            const int64_t i = cur_v + F->roff[r];
#if BIT_GRID
            uint32_t w; std::memcpy(&w, bits + (i >> 3), 4);
            nb |= ((w >> (i & 7)) & 7u) << (3 * r);
#else   // three bytes of 0/1 to three bits: one multiply gathers them at bits 14-16
            uint32_t w; std::memcpy(&w, bits + i, 4);
            nb |= ((((w & 0x010101u) * 0x4081u) >> 14) & 7u) << (3 * r);
#endif
        }
        for (int m = 0; m < 26; ++m) {
            if ((nb & F->need[m]) != F->need[m]) continue;
            const int32_t w = cur_v + (int32_t)F->mv[m];
            const double ng = cur_g + F->mc[m];
            const int32_t k = slot[w];
            if (SLOT_CLOSED && k < -1) continue;
            if (k < 0) {
                if (F->nn == F->ncap) grow_nodes(F);
                const int16_t x = cur_x + F->mda[m], y = cur_y + F->mdb[m], z = cur_z + F->mdc[m];
                const int32_t j = (int32_t)F->nn++;
                slot[w] = j;
                const double f = fkey(ng + h(x, y, z));
                set_node(F, j, ng, w, x, y, z);
                if (SIDE_HEAP && f <= fcur) s_push(F, {f, ng, j, 0});
                else h_push(F, {f, ng, j, 0});
                continue;
            }
            const int32_t kpos = NPOS(k);
            if (kpos == CLOSED || ng >= NG(k)) continue;
            NG(k) = ng;
            const double f = fkey(ng + h(NX(k), NY(k), NZ(k)));
            if (kpos == SIDE) { s_push(F, {f, ng, k, 0}); continue; }
            if (SIDE_HEAP && f <= fcur) {
                h_remove(F, kpos);
                NPOS(k) = SIDE;
                s_push(F, {f, ng, k, 0});
            } else {
                h_up(F, kpos, {f, ng, k, 0});
            }
        }
    }
    for (int64_t i = 0; i < F->nn; ++i) slot[NV(i)] = -1;
    return exp;
}

// Queries (nq, 6) int64 cells; out (nq, 3): cost (cells, -1 unreachable), expansions,
// this thread's CPU seconds of the search.
void floor_batch(Floor* F, const int64_t* q, int64_t nq, double* out) {
    for (int64_t k = 0; k < nq; ++k) {
        timespec t0, t1;
        clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t0);
        const int64_t* p = q + 6 * k;
        double cost;
        int64_t e = floor_search(F, p[0], p[1], p[2], p[3], p[4], p[5], &cost);
        clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t1);
        out[3 * k] = cost; out[3 * k + 1] = (double)e;
        out[3 * k + 2] = (double)(t1.tv_sec - t0.tv_sec) + 1e-9 * (double)(t1.tv_nsec - t0.tv_nsec);
    }
}

}  // extern "C"
"""


def _compiler() -> str | None:
    return shutil.which("g++") or shutil.which("c++")


def available() -> bool:
    """True when a C++ compiler (``g++`` or ``c++``) is on PATH."""
    return _compiler() is not None


# The floor with one trick switched off each (the macros at the top of SOURCE).
VARIANTS = {"strongest": (), "binary heap": ("ARITY=2",), "no side heap": ("SIDE_HEAP=0",),
            "byte grid": ("BIT_GRID=0",), "closed in records": ("SLOT_CLOSED=0",),
            "children in turn": ("TOURNAMENT=0",),
            "nodes in arrays": ("SPLIT_NODES=1",),
            "none of the five": ("ARITY=2", "SIDE_HEAP=0", "BIT_GRID=0", "SLOT_CLOSED=0",
                                 "TOURNAMENT=0")}


@functools.cache
def library(defines: tuple[str, ...] = ()) -> ctypes.CDLL:
    """Compile the floor once per process (per set of ``-D`` macros, :data:`VARIANTS`) into
    a shared library and load it."""
    cxx = _compiler()
    if cxx is None:
        raise RuntimeError("no C++ compiler (g++) on PATH: the C++ floor is skipped")
    tmp = Path(tempfile.mkdtemp(prefix="cpp_floor_"))
    src, lib = tmp / "floor.cpp", tmp / "libfloor.so"
    src.write_text(SOURCE)
    subprocess.run([cxx, "-O3", "-march=native", "-std=c++17", "-shared", "-fPIC",
                    *(f"-D{d}" for d in defines), "-o", str(lib), str(src)], check=True,
                   capture_output=True)
    dll = ctypes.CDLL(str(lib))
    i64, vp = ctypes.c_int64, ctypes.c_void_p
    dll.floor_new.restype = vp
    dll.floor_new.argtypes = [vp, i64, i64, i64]
    dll.floor_free.restype = None
    dll.floor_free.argtypes = [vp]
    dll.floor_bytes.restype = i64
    dll.floor_bytes.argtypes = [vp]
    dll.floor_search.restype = i64
    dll.floor_search.argtypes = [vp] + [i64] * 6 + [ctypes.POINTER(ctypes.c_double)]
    dll.floor_batch.restype = None
    dll.floor_batch.argtypes = [vp, vp, i64, vp]
    return dll


class Floor:
    """The floor on one map, held in this process.

    Parameters
    ----------
    free : ndarray of bool, shape (na, nb, nc)
        True where a voxel is free, in the order the floor should store it (the last axis
        varies fastest; :func:`longest_last` gives the order that puts the map's longest
        axis there).
    variant : str
        A key of :data:`VARIANTS` (default: every trick on).
    """

    def __init__(self, free: np.ndarray, variant: str = "strongest"):
        self._dll = library(VARIANTS[variant])
        grid = np.ascontiguousarray(free, dtype=np.uint8)
        self.shape = grid.shape
        self._h = self._dll.floor_new(grid.ctypes.data, *grid.shape)
        if not self._h:
            raise ValueError(f"map of {grid.shape} voxels is too large for the floor")
        self._cost = ctypes.c_double()
        self._ref = ctypes.byref(self._cost)
        self._search = self._dll.floor_search

    def search(self, s, g) -> tuple[float, int]:
        """(cost in cells, -1 when unreachable; expansions) of one query (cells (3,))."""
        e = self._search(self._h, int(s[0]), int(s[1]), int(s[2]), int(g[0]), int(g[1]),
                         int(g[2]), self._ref)
        return self._cost.value, int(e)

    def batch(self, queries: np.ndarray) -> np.ndarray:
        """(Q, 3): cost (cells, -1 unreachable), expansions, thread CPU seconds per query
        (measured inside the library, around the search alone)."""
        q = np.ascontiguousarray(queries, dtype=np.int64).reshape(-1, 6)
        out = np.empty((len(q), 3))
        self._dll.floor_batch(self._h, q.ctypes.data, len(q), out.ctypes.data)
        return out

    @property
    def nbytes(self) -> int:
        """Bytes the floor holds: bit grid, slot map, node records and heaps."""
        return int(self._dll.floor_bytes(self._h))

    def close(self) -> None:
        if self._h:
            self._dll.floor_free(self._h)
            self._h = None

    def __del__(self):
        self.close()


def run(free: np.ndarray, queries: np.ndarray) -> np.ndarray:
    """The floor on a dense grid, every query once.

    Parameters
    ----------
    free : ndarray of bool, shape (nx, ny, nz)
        True where a voxel is free (index order x, y, z).
    queries : ndarray of int, shape (Q, 6)
        ``sx sy sz gx gy gz`` voxel indices.

    Returns
    -------
    ndarray, shape (Q, 3)
        Per query: path cost (-1 when unreachable), expansions, thread CPU seconds of the
        search (the map's loading outside it). The map is stored with its longest axis
        fastest (:func:`longest_last`).
    """
    return run_measured(free, queries)[0]


def run_measured(free: np.ndarray, queries: np.ndarray) -> tuple[np.ndarray, int]:
    """:func:`run`, and the bytes the floor held at the end (bit grid, slot map, node
    records and heaps)."""
    free = np.asarray(free, dtype=bool)
    perm = longest_last(free.shape)
    q = np.asarray(queries, dtype=np.int64).reshape(-1, 6)
    fl = Floor(free.transpose(perm))
    try:
        res = fl.batch(np.concatenate([q[:, :3][:, perm], q[:, 3:6][:, perm]], axis=1))
        return res, fl.nbytes
    finally:
        fl.close()


def longest_last(shape) -> tuple[int, int, int]:
    """The axis order (a permutation of 0, 1, 2) that puts the longest axis last (fastest
    in C order), the others in their own order."""
    k = int(np.argmax(shape))
    return tuple([i for i in range(3) if i != k] + [k])


# ----------------------------------------------------------------------------------------
# Ours against the floor on the Warframe maps and geb079.

WARFRAME_MAPS = ("Simple", "Complex", "DA1", "A1", "BC1", "DA2")
LONG = 10_000  # expansions: the long queries, where the fixed cost per call no longer counts


@dataclass
class Map:
    """One benchmark map: a free grid, its queries and (MovingAI) their optimal costs."""

    name: str
    free: np.ndarray       # (nx, ny, nz) bool, True = free
    queries: np.ndarray    # (Q, 6) int64 cells
    optimal: np.ndarray | None  # (Q,) cost in cells, or None


def read_warframe(path: Path) -> tuple[np.ndarray, np.ndarray]:
    """A MovingAI ``.3dmap`` as a free grid (nx, ny, nz) and its ``.3dscen`` as (Q, 7)."""
    dims = np.loadtxt(path, max_rows=1, usecols=(1, 2, 3), dtype=np.int64)
    blocked = np.loadtxt(path, skiprows=1, dtype=np.int64, ndmin=2)
    free = np.ones(dims, dtype=bool)
    free[tuple(blocked.T)] = False
    scen = np.loadtxt(f"{path}.3dscen", skiprows=2, ndmin=2)
    return free, scen


def warframe(path: Path, n: int | None) -> Map:
    """``n`` queries spread evenly over the scenario file (all when None)."""
    free, scen = read_warframe(path)
    if n is not None:
        scen = scen[:: max(1, len(scen) // n)][:n]
    return Map(path.stem, free, scen[:, :6].astype(np.int64), scen[:, 6])


def geb079(path: Path, n: int, seed: int = 0) -> Map:
    """geb079 on the cubic lattice at 0.08 m (the package's OctoMap reader and world build,
    radius 0), its free cells as a grid over the world's index box, and ``n`` random free
    start/goal pairs at least 10 m apart."""
    from planner import build_world

    w = build_world(path, "cubic", cell_volume=0.08**3, radius=0.0)
    lo = np.ceil(w.bounds[0] / 0.08 - 1e-9).astype(np.int64)
    hi = np.floor(w.bounds[1] / 0.08 + 1e-9).astype(np.int64)
    dims = hi - lo + 1
    idx = np.indices(dims).reshape(3, -1).T + lo
    free = w.is_free(idx).reshape(tuple(dims))
    rng = np.random.default_rng(seed)
    q = []
    while len(q) < n:
        c = rng.integers(0, dims, size=(2, 3))
        if free[tuple(c.T)].all() and np.linalg.norm(c[0] - c[1]) * 0.08 >= 10.0:
            q.append(np.r_[c[0], c[1]])
    return Map("geb079", free, np.array(q, np.int64).reshape(-1, 6), None)


def synthetic(n: int = 40, seed: int = 0, queries: int = 12) -> Map:
    """A seeded field of boxes in an (n, n/2, n/4) box map (its longest axis first, so the
    axis order matters), ``queries`` random free pairs (smoke runs; no optimal costs)."""
    rng = np.random.default_rng(seed)
    dims = np.array([n, max(4, n // 2), max(4, n // 4)])
    free = np.ones(dims, dtype=bool)
    for _ in range(n):
        c = rng.integers(0, dims)
        e = rng.integers(1, np.maximum(2, dims // 4) + 1)
        free[tuple(slice(a, a + b) for a, b in zip(c, e, strict=True))] = False
    q = []
    while len(q) < queries:
        c = rng.integers(0, dims, size=(2, 3))
        if free[tuple(c.T)].all():
            q.append(np.r_[c[0], c[1]])
    return Map("synthetic", free, np.array(q, np.int64), None)


def our_world(free: np.ndarray):
    """Our cubic world (1 m cells) on the free grid: blocked cells and the grid's box."""
    from planner.lattice import Lattice
    from planner.world import World

    blocked = np.argwhere(~free)
    return World(Lattice.named("cubic", 1.0), blocked,
                 np.array([[0.0, 0.0, 0.0], np.array(free.shape) - 1.0]))


@dataclass
class Row:
    """Ours against the floor on one map."""

    name: str
    perm: tuple
    ours: np.ndarray       # (Q,) thread CPU s per query, fastest round
    floor: np.ndarray      # (Q,) the same for the floor
    exp_ours: np.ndarray   # (Q,) expansions
    exp_floor: np.ndarray
    mismatches: int        # ours vs floor, and each vs the listed optimal cost
    checked: int


def compare(m: Map, repeat: int, axes: str = "longest",
            grids: tuple[str, ...] = ("strongest", "byte grid")) -> Row:
    """Both sides on the same permuted map, taking turns per query, best of ``repeat``.

    The floor is built once per variant of ``grids`` (default: its bit grid and its byte
    grid, which win on different maps by a few per cent: ``--variants``); each query's
    floor time is the fastest round of any of them."""
    from planner.search import search

    perm = longest_last(m.free.shape) if axes == "longest" else (0, 1, 2)
    free = np.ascontiguousarray(m.free.transpose(perm))
    s = m.queries[:, :3][:, perm]
    g = m.queries[:, 3:6][:, perm]
    world = our_world(free)
    floors = [Floor(free, k) for k in grids]
    search(world, s[0], g[0])  # kernels loaded, the world's arrays made: outside the clock
    n = len(s)
    cost_o, cost_f = np.empty(n), np.empty(n)
    exp_o, exp_f = np.zeros(n, np.int64), np.zeros(n, np.int64)
    clock = harness.cpu_clock

    def ours(i):
        t0 = clock()
        r = search(world, s[i], g[i])
        t = clock() - t0
        cost_o[i], exp_o[i] = (r.cost if r.found else -1.0), r.expansions
        return t

    def floor(fl):
        def run(i):
            t0 = clock()
            c, e = fl.search(s[i], g[i])
            t = clock() - t0
            cost_f[i], exp_f[i] = c, e
            return t
        return run

    sides = {"ours": ours} | {f"floor {k}": floor(fl) for k, fl in zip(grids, floors,
                                                                      strict=True)}
    best = harness.interleaved(sides, range(n), repeat)
    for fl in floors:
        fl.close()
    fastest = np.min([best[f"floor {k}"] for k in grids], axis=0)
    bad = ~np.isclose(cost_o, cost_f, rtol=1e-9, atol=1e-9)
    if m.optimal is not None:
        bad |= ~np.isclose(cost_f, m.optimal, rtol=1e-6, atol=1e-6)
    return Row(m.name, perm, best["ours"], fastest, exp_o, exp_f, int(bad.sum()), n)


def variants(m: Map, repeat: int) -> None:
    """The floor with each trick switched off (:data:`VARIANTS`, and the map's own axis
    order), the variants taking turns per query, best of ``repeat``: time / the strongest's."""
    perm = longest_last(m.free.shape)
    free = np.ascontiguousarray(m.free.transpose(perm))
    s, g = m.queries[:, :3][:, perm], m.queries[:, 3:6][:, perm]
    floors = {k: (Floor(free, k), s, g) for k in VARIANTS}
    if perm != (0, 1, 2):
        floors["natural axes"] = (Floor(m.free), m.queries[:, :3], m.queries[:, 3:6])
    n = len(s)
    costs = {k: np.empty(n) for k in floors}

    def side(k):
        fl, a, b = floors[k]

        def run(i):
            t0 = harness.cpu_clock()
            costs[k][i] = fl.search(a[i], b[i])[0]
            return harness.cpu_clock() - t0
        return run

    best = harness.interleaved({k: side(k) for k in floors}, range(n), repeat)
    for fl, _, _ in floors.values():
        fl.close()
    print(f"{m.name}: {n} queries, the floor's variants taking turns per query, best of "
          f"{repeat}")
    for k, t in best.items():
        same = int(np.sum(np.isclose(costs[k], costs["strongest"], rtol=1e-9, atol=1e-9)))
        print(f"  {k:17s} {1e3 * t.sum():9.2f} ms  costs equal to the strongest's: {same}/{n}")
    for k, t in best.items():
        if k != "strongest":
            print(harness.ratio_line(f"floor time {k} / strongest, {m.name}", t,
                                     best["strongest"], note="per query"))


def check_all(path: Path) -> tuple[int, int, float]:
    """The floor alone on every query of a Warframe map: (queries, mismatches, M exp/s)."""
    free, scen = read_warframe(path)
    res = run(free, scen[:, :6].astype(np.int64))
    bad = int(np.sum(~np.isclose(res[:, 0], scen[:, 6], rtol=1e-6, atol=1e-6)))
    return len(scen), bad, res[:, 1].sum() / max(res[:, 2].sum(), 1e-12) / 1e6


def print_rows(rows: list[Row]) -> None:
    """The table, then one ratio line per map (ours speed / the floor's)."""
    print(f"{'map':10s} {'axes':>5s} {'queries':>7s} {'floor ms':>9s} {'ours ms':>9s} "
          f"{'speed':>6s} {'exp ratio':>9s} {'long':>5s} {'speed':>6s} {'cost!=':>6s}")
    for r in rows:
        speed = (r.exp_ours.sum() / r.ours.sum()) / (r.exp_floor.sum() / r.floor.sum())
        long = r.exp_floor >= LONG
        ls = ((r.exp_ours[long].sum() / r.ours[long].sum())
              / (r.exp_floor[long].sum() / r.floor[long].sum())) if long.any() else math.nan
        print(f"{r.name:10s} {''.join('xyz'[i] for i in r.perm):>5s} {r.checked:7d} "
              f"{1e3 * r.floor.sum():9.2f} {1e3 * r.ours.sum():9.2f} {speed:6.2f} "
              f"{r.exp_ours.sum() / max(1, r.exp_floor.sum()):9.3f} {int(long.sum()):5d} "
              f"{ls:6.2f} {r.mismatches:6d}")
        harness.record(f"floor/{r.name}", dict(
            axes="".join("xyz"[i] for i in r.perm), queries=r.checked,
            floor_ms=1e3 * r.floor.sum(), ours_ms=1e3 * r.ours.sum(), speed=speed,
            exp_ratio=r.exp_ours.sum() / max(1, r.exp_floor.sum()),
            long_queries=int(long.sum()), long_min_expansions=LONG, long_speed=ls,
            mismatches=r.mismatches))
    print("speed: ours expansions/s / the floor's over all queries (sum/sum); long: queries "
          f"of >= {LONG:,} floor expansions and the speed over them; axes: the map's axes "
          "from slowest to fastest")
    for r in rows:
        speed = (r.exp_ours.sum() / r.ours.sum()) / (r.exp_floor.sum() / r.floor.sum())
        # per query: ours expansions/s over the floor's = (floor s / exp) / (ours s / exp)
        print(harness.ratio_line(f"A* speed ours/floor {r.name}",
                                 r.floor / np.maximum(r.exp_floor, 1),
                                 r.ours / np.maximum(r.exp_ours, 1), goal=">= 0.9",
                                 overall=speed, note="per query, expansions/s"))


def maps(data: Path, names, queries: int, geb_queries: int):
    """The named maps present under ``data`` (Warframe names, ``geb079``), one at a time
    (a line for each one absent)."""
    for name in names:
        if name == "geb079":
            p = data / "octomap" / "geb079.bt"
            m = geb079(p, geb_queries) if p.is_file() else None
        else:
            p = data / "warframe" / f"{name}.3dmap"
            m = warframe(p, queries) if p.is_file() else None
        if m is None:
            print(f"{name}: not under {data}, skipped")
            continue
        yield m


def floor_rows(data: Path = harness.DATA, names=WARFRAME_MAPS + ("geb079",),
               queries: int = 100, geb_queries: int = 20, repeat: int = 3,
               axes: str = "longest",
               grids: tuple[str, ...] = ("strongest", "byte grid")) -> list[Row]:
    """Ours against the floor (the fastest of its variants ``grids`` per query) on each
    named map present (:func:`compare`); print the rows with :func:`print_rows`. What
    ``search_speed.py`` can call for its floor table."""
    rows = []
    for m in maps(data, names, queries, geb_queries):
        rows.append(compare(m, repeat, axes, grids))
        print(f"{m.name} done", file=sys.stderr, flush=True)
    return rows


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    harness.add_arguments(ap, repeat=3, data=True)
    ap.add_argument("--maps", nargs="+", default=list(WARFRAME_MAPS) + ["geb079"],
                    help="Warframe maps present under DATA/warframe, and geb079")
    ap.add_argument("--queries", type=int, default=100, help="queries per Warframe map")
    ap.add_argument("--geb-queries", type=int, default=20, help="geb079 queries (>= 10 m)")
    ap.add_argument("--axes", choices=("longest", "natural"), default="longest",
                    help="longest: the map's longest axis fastest on both sides (default); "
                         "natural: the map's own x, y, z order")
    ap.add_argument("--check-all", action="store_true",
                    help="the floor alone on every query of each Warframe map present")
    ap.add_argument("--variants", action="store_true",
                    help="the floor alone with each trick switched off, per map")
    ap.add_argument("--floor", nargs="+", choices=list(VARIANTS),
                    default=["strongest", "byte grid"], metavar="VARIANT",
                    help="the floor's variants ours is set against, the fastest per query "
                         "(default: strongest, byte grid); e.g. 'children in turn': a "
                         "yardstick that stays put while our heap changes (run it with "
                         "PYTHONPATH=OTHER_CHECKOUT for that checkout's planner)")
    a = ap.parse_args(argv)
    with harness.session("A*, cubic-26, ours vs the strongest C++ floor (in process, "
                         "thread CPU time)", smoke=a.smoke):
        if not available():
            return harness.skip("no C++ compiler (g++ / c++) on PATH: the C++ floor")
        if a.smoke:
            print_rows([compare(synthetic(), a.repeat, a.axes)])
            if a.variants:
                variants(synthetic(), a.repeat)
            return 0
        wf = a.data / "warframe"
        if a.check_all:
            total = 0
            for name in a.maps:
                p = wf / f"{name}.3dmap"
                if p.is_file():
                    n, bad, mps = check_all(p)
                    total += bad
                    print(f"{name}: {n} queries, {bad} cost mismatches, {mps:.2f} M exp/s")
            return 1 if total else 0
        if a.variants:
            for m in maps(a.data, a.maps, a.queries, a.geb_queries):
                variants(m, a.repeat)
            return 0
        rows = floor_rows(a.data, a.maps, a.queries, a.geb_queries, a.repeat, a.axes,
                          tuple(a.floor))
        if not rows:
            return harness.skip(f"no maps under {a.data}")
        print_rows(rows)
        bad = sum(r.mismatches for r in rows)
        print(f"cost mismatches (ours vs floor vs listed optimal): {bad}")
        return 1 if bad else 0


if __name__ == "__main__":
    raise SystemExit(main())
