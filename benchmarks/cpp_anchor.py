"""A minimal C++ A* compiled at run time: the floor our engine is measured against.

Cubic lattice, 26 neighbours with MovingAI's no-corner-cutting rule (a move is allowed
only when every voxel of its bounding box is free), step costs 1, sqrt(2), sqrt(3), the
exact octile heuristic and the project's tie-break (lower f first, f rounded to 1e-9 so
that equal-cost paths tie exactly, then larger g). It is
written to be as fast as a minimal A* can be, so that a ratio against it is a fair one:
a dense byte grid padded by one voxel (no bounds tests), the 26-neighbourhood read once
per expansion into a bit mask and each move's required cells tested as one mask, heap
entries that carry the node's coordinates (the heuristic needs no division), per-cell
state (g, query stamp, heap index) in one calloc'd record, stamped with the query number
(nothing cleared between queries), and a binary heap with decrease-key. Built with the
system compiler (``g++ -O3 -march=native``) into a temporary directory; :func:`available`
says whether a compiler exists (callers skip with a note when it does not).

Used by ``benchmarks/search_speed.py``; also runnable alone::

    python benchmarks/cpp_anchor.py ../shared/data/warframe/Simple.3dmap   # optimal-cost check
"""

from __future__ import annotations

import functools
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

SOURCE = r"""
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <vector>

// Input (binary, little endian): int64 nx ny nz, uint8 free[nx*ny*nz] (x fastest),
// int64 nq, then nq x 6 int64 (sx sy sz gx gy gz). Output: one line per query:
// cost expansions seconds.
//
// Per expansion: one read of the 26 neighbours into a bit mask; each move is allowed when
// its required cells (the voxels of its bounding box) are all set in it, one AND and one
// compare. Heap entries carry the node's coordinates, so the heuristic needs no division.
// Per-cell state is stamped with the query number (nothing is cleared between queries).
struct Entry { double f, g; int64_t v; int32_t x, y, z, pad; };
// Per-cell state in one record (one cache line visit per neighbour, not two).
struct Cell { double g; uint32_t stamp; int32_t at; };  // stamp 2k+1 open, 2k+2 closed

static inline bool before(const Entry& a, const Entry& b) {  // the project's order:
    return a.f < b.f || (a.f == b.f && a.g > b.g);             // lower f, then larger g
}

struct Heap {  // binary min-heap with decrease-key (each cell's heap index in Cell::at)
    std::vector<Entry> a;
    Cell* cell;
    void clear() { a.clear(); }
    bool empty() const { return a.empty(); }
    void up(size_t i, const Entry& e) {
        while (i > 0) {
            size_t p = (i - 1) >> 1;
            if (!before(e, a[p])) break;
            a[i] = a[p]; cell[a[i].v].at = (int32_t)i; i = p;
        }
        a[i] = e; cell[e.v].at = (int32_t)i;
    }
    void push(const Entry& e) { a.push_back(e); up(a.size() - 1, e); }
    void decrease(const Entry& e) { up((size_t)cell[e.v].at, e); }
    Entry pop() {
        Entry top = a[0], last = a.back(); a.pop_back();
        size_t n = a.size(), i = 0;
        if (n) {
            for (;;) {
                size_t c = 2 * i + 1;
                if (c >= n) break;
                if (c + 1 < n && before(a[c + 1], a[c])) ++c;
                if (!before(a[c], last)) break;
                a[i] = a[c]; cell[a[i].v].at = (int32_t)i; i = c;
            }
            a[i] = last; cell[last.v].at = (int32_t)i;
        }
        return top;
    }
};

int main(int argc, char** argv) {
    if (argc < 2) return 2;
    FILE* in = std::fopen(argv[1], "rb");
    if (!in) return 2;
    int64_t d[3];
    if (std::fread(d, 8, 3, in) != 3) return 2;
    const int64_t X = d[0] + 2, Y = d[1] + 2, Z = d[2] + 2;  // padded by one blocked voxel
    std::vector<uint8_t> raw(d[0] * d[1] * d[2]);
    if (std::fread(raw.data(), 1, raw.size(), in) != raw.size()) return 2;
    uint8_t* fr = (uint8_t*)std::calloc(X * Y * Z, 1);
    for (int64_t z = 0; z < d[2]; ++z)
        for (int64_t y = 0; y < d[1]; ++y)
            std::memcpy(&fr[((z + 1) * Y + (y + 1)) * X + 1], &raw[(z * d[1] + y) * d[0]], d[0]);
    std::vector<uint8_t>().swap(raw);
    int64_t nq;
    if (std::fread(&nq, 8, 1, in) != 1) return 2;
    std::vector<int64_t> q(6 * nq);
    if (std::fread(q.data(), 8, 6 * nq, in) != (size_t)(6 * nq)) return 2;
    std::fclose(in);

    // Bit b of a neighbourhood mask is the voxel at offset (b % 3 - 1, b / 3 % 3 - 1, b / 9 - 1).
    int64_t off[27]; int mdx[26], mdy[26], mdz[26]; int64_t mv[26]; double mc[26];
    uint32_t need[26]; int nm = 0;
    for (int b = 0; b < 27; ++b) off[b] = ((b / 9 - 1) * Y + (b / 3 % 3 - 1)) * X + (b % 3 - 1);
    for (int dz = -1; dz <= 1; ++dz)
    for (int dy = -1; dy <= 1; ++dy)
    for (int dx = -1; dx <= 1; ++dx) {
        if (!dx && !dy && !dz) continue;
        uint32_t m = 0;
        for (int cz = std::min(0, dz); cz <= std::max(0, dz); ++cz)
            for (int cy = std::min(0, dy); cy <= std::max(0, dy); ++cy)
                for (int cx = std::min(0, dx); cx <= std::max(0, dx); ++cx)
                    if (cx || cy || cz) m |= 1u << ((cz + 1) * 9 + (cy + 1) * 3 + cx + 1);
        mdx[nm] = dx; mdy[nm] = dy; mdz[nm] = dz; need[nm] = m;
        mv[nm] = (dz * Y + dy) * X + dx;
        mc[nm] = std::sqrt((double)(dx * dx + dy * dy + dz * dz));
        ++nm;
    }
    const double s2m1 = std::sqrt(2.0) - 1.0, s3m2 = std::sqrt(3.0) - std::sqrt(2.0);
    // f on a 1e-9 grid, as ours: equal-cost paths then tie exactly (float noise would
    // otherwise decide) and the larger-g tie-break dives along them.
    const double fq = 1e-9, fq_inv = 1.0 / fq;
    auto fkey = [&](double f) { return std::floor(f * fq_inv + 0.5) * fq; };
    Cell* cell = (Cell*)std::calloc(X * Y * Z, sizeof(Cell));
    Heap open; open.a.reserve(1 << 16); open.cell = cell;
    for (int64_t k = 0; k < nq; ++k) {
        auto t0 = std::chrono::steady_clock::now();
        const uint32_t seen = (uint32_t)(2 * k + 1), done = seen + 1;
        const int32_t sx = q[6 * k] + 1, sy = q[6 * k + 1] + 1, sz = q[6 * k + 2] + 1;
        const int32_t gx = q[6 * k + 3] + 1, gy = q[6 * k + 4] + 1, gz = q[6 * k + 5] + 1;
        const int64_t s = ((int64_t)sz * Y + sy) * X + sx, t = ((int64_t)gz * Y + gy) * X + gx;
        // octile: a >= b >= c -> a + (sqrt2 - 1) b + (sqrt3 - sqrt2) c
        auto h = [&](int32_t x, int32_t y, int32_t z) {
            int32_t a = std::abs(x - gx), b = std::abs(y - gy), c = std::abs(z - gz);
            int32_t hi = std::max(a, std::max(b, c)), lo = std::min(a, std::min(b, c));
            int32_t mid = a + b + c - hi - lo;
            return (double)hi + s2m1 * mid + s3m2 * lo;
        };
        double cost = -1; int64_t exp = 0;
        open.clear();
        if (fr[s] && fr[t]) {
            cell[s].g = 0; cell[s].stamp = seen;
            open.push({fkey(h(sx, sy, sz)), 0.0, s, sx, sy, sz, 0});
            while (!open.empty()) {
                const Entry n = open.pop();
                cell[n.v].stamp = done; ++exp;
                if (n.v == t) { cost = n.g; break; }
                const uint8_t* c = fr + n.v;
                uint32_t nb = 0;
                for (int b = 0; b < 27; ++b) nb |= (uint32_t)c[off[b]] << b;
                for (int m = 0; m < 26; ++m) {
                    if ((nb & need[m]) != need[m]) continue;
                    const int64_t w = n.v + mv[m];
                    Cell& cw = cell[w];
                    if (cw.stamp == done) continue;
                    const double ng = n.g + mc[m];
                    if (cw.stamp != seen) {
                        cw.stamp = seen; cw.g = ng;
                        const int32_t x = n.x + mdx[m], y = n.y + mdy[m], z = n.z + mdz[m];
                        open.push({fkey(ng + h(x, y, z)), ng, w, x, y, z, 0});
                    } else if (ng < cw.g) {
                        cw.g = ng;
                        const int32_t x = n.x + mdx[m], y = n.y + mdy[m], z = n.z + mdz[m];
                        open.decrease({fkey(ng + h(x, y, z)), ng, w, x, y, z, 0});
                    }
                }
            }
        }
        double sec = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        std::printf("%.9f %lld %.9f\n", cost, (long long)exp, sec);
    }
    // This image's own peak resident memory on stderr (its getrusage would also count the
    // parent's pages mapped before exec).
    if (FILE* f = std::fopen("/proc/self/status", "r")) {
        char line[256];
        while (std::fgets(line, sizeof line, f))
            if (!std::strncmp(line, "VmHWM:", 6)) std::fputs(line, stderr);
        std::fclose(f);
    }
    return 0;
}
"""


def available() -> bool:
    """True when a C++ compiler (``g++`` or ``c++``) is on PATH."""
    return _compiler() is not None


def _compiler() -> str | None:
    return shutil.which("g++") or shutil.which("c++")


@functools.lru_cache(maxsize=1)
def binary() -> Path:
    """Compile the anchor once per process; returns the executable's path."""
    cxx = _compiler()
    if cxx is None:
        raise RuntimeError("no C++ compiler (g++) on PATH: the C++ anchor is skipped")
    tmp = Path(tempfile.mkdtemp(prefix="cpp_anchor_"))
    src = tmp / "astar.cpp"
    src.write_text(SOURCE)
    exe = tmp / "astar"
    subprocess.run([cxx, "-O3", "-march=native", "-std=c++17", "-o", str(exe), str(src)],
                   check=True, capture_output=True)
    return exe


def run(free: np.ndarray, queries: np.ndarray) -> np.ndarray:
    """Run the anchor on a dense grid.

    Parameters
    ----------
    free : ndarray of bool, shape (nx, ny, nz)
        True where a voxel is free (index order x, y, z).
    queries : ndarray of int, shape (Q, 6)
        ``sx sy sz gx gy gz`` voxel indices.

    Returns
    -------
    ndarray, shape (Q, 3)
        Per query: path cost (-1 when unreachable), expansions, seconds (search only:
        loading and padding the grid are outside the clock).
    """
    return run_measured(free, queries)[0]


def run_measured(free: np.ndarray, queries: np.ndarray) -> tuple[np.ndarray, int | None]:
    """:func:`run`, and the anchor process's own peak resident memory (bytes; its VmHWM
    after exec, None where /proc is not there)."""
    free = np.asarray(free, dtype=bool)
    q = np.ascontiguousarray(queries, dtype=np.int64).reshape(-1, 6)
    with tempfile.TemporaryDirectory(prefix="cpp_anchor_in_") as tmp:
        path = Path(tmp) / "in.bin"
        with open(path, "wb") as f:
            f.write(np.asarray(free.shape, dtype="<i8").tobytes())
            for z in range(free.shape[2]):  # x fastest, one z slab at a time (no full copy)
                f.write(np.ascontiguousarray(free[:, :, z].T, dtype=np.uint8).tobytes())
            f.write(np.int64(len(q)).tobytes())
            f.write(q.astype("<i8").tobytes())
        res = subprocess.run([str(binary()), str(path)], check=True, capture_output=True,
                             text=True)
    peak = [int(line.split()[1]) * 1024 for line in res.stderr.splitlines()
            if line.startswith("VmHWM:")]
    return np.loadtxt(res.stdout.splitlines(), ndmin=2).reshape(-1, 3), (peak or [None])[0]


def main(argv: list[str] | None = None) -> int:
    """Check the anchor against a MovingAI map's listed optimal costs."""
    args = sys.argv[1:] if argv is None else argv
    if not args:
        print(__doc__)
        return 2
    path = Path(args[0])
    dims = np.loadtxt(path, max_rows=1, usecols=(1, 2, 3), dtype=np.int64)
    blocked = np.loadtxt(path, skiprows=1, dtype=np.int64, ndmin=2)
    free = np.ones(dims, dtype=bool)
    free[tuple(blocked.T)] = False
    scen = np.loadtxt(f"{path}.3dscen", skiprows=2, ndmin=2)
    n = int(args[1]) if len(args) > 1 else 1000
    res = run(free, scen[:n, :6].astype(np.int64))
    bad = int(np.sum(np.abs(res[:, 0] - scen[:n, 6]) > 1e-6 * np.maximum(1, scen[:n, 6])))
    print(f"{path.name}: {n} queries, {bad} cost mismatches, "
          f"{res[:, 1].sum() / res[:, 2].sum() / 1e6:.2f} M expansions/s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
