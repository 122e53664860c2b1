"""A minimal C++ A* compiled at run time: the floor our engine is measured against.

Cubic lattice, 26 neighbours with MovingAI's no-corner-cutting rule (a move is allowed
only when every voxel of its bounding box is free), step costs 1, sqrt(2), sqrt(3), the
exact octile heuristic, a binary heap with lazy deletion, a dense byte grid padded by one
voxel so that neighbour lookups need no bounds test. Built with the system compiler
(``g++ -O3 -march=native``) into a temporary directory; :func:`available` says whether a
compiler exists (callers skip with a note when it does not).

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
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <queue>
#include <vector>

// Input (binary, little endian): int64 nx ny nz, uint8 free[nx*ny*nz] (x fastest),
// int64 nq, then nq x 6 int64 (sx sy sz gx gy gz). Output: one line per query:
// cost expansions seconds.
struct Node { double f, g; int64_t v; };
struct Cmp { bool operator()(const Node& a, const Node& b) const {
    return a.f > b.f || (a.f == b.f && a.g < b.g); } };

int main(int argc, char** argv) {
    FILE* in = std::fopen(argv[1], "rb");
    int64_t d[3];
    if (std::fread(d, 8, 3, in) != 3) return 2;
    const int64_t X = d[0] + 2, Y = d[1] + 2, Z = d[2] + 2;  // padded by one blocked voxel
    std::vector<uint8_t> raw(d[0] * d[1] * d[2]);
    if (std::fread(raw.data(), 1, raw.size(), in) != raw.size()) return 2;
    std::vector<uint8_t> fr(X * Y * Z, 0);
    for (int64_t z = 0; z < d[2]; ++z)
        for (int64_t y = 0; y < d[1]; ++y)
            std::memcpy(&fr[((z + 1) * Y + (y + 1)) * X + 1], &raw[(z * d[1] + y) * d[0]], d[0]);
    int64_t nq;
    if (std::fread(&nq, 8, 1, in) != 1) return 2;
    std::vector<int64_t> q(6 * nq);
    if (std::fread(q.data(), 8, 6 * nq, in) != (size_t)(6 * nq)) return 2;
    std::fclose(in);

    // The 26 moves, each with the offsets (relative to the source) that must be free.
    std::vector<int64_t> mv; std::vector<double> mc; std::vector<std::vector<int64_t>> need;
    for (int dz = -1; dz <= 1; ++dz)
    for (int dy = -1; dy <= 1; ++dy)
    for (int dx = -1; dx <= 1; ++dx) {
        if (!dx && !dy && !dz) continue;
        mv.push_back((dz * Y + dy) * X + dx);
        mc.push_back(std::sqrt((double)(dx * dx + dy * dy + dz * dz)));
        std::vector<int64_t> nd;
        for (int cz = std::min(0, dz); cz <= std::max(0, dz); ++cz)
            for (int cy = std::min(0, dy); cy <= std::max(0, dy); ++cy)
                for (int cx = std::min(0, dx); cx <= std::max(0, dx); ++cx)
                    if (cx || cy || cz) nd.push_back((cz * Y + cy) * X + cx);
        need.push_back(nd);
    }
    const double s2 = std::sqrt(2.0), s3 = std::sqrt(3.0);
    std::vector<double> g(X * Y * Z);
    std::vector<uint32_t> seen(X * Y * Z, 0);  // query stamp: g valid / closed
    std::vector<uint32_t> closed(X * Y * Z, 0);
    for (int64_t k = 0; k < nq; ++k) {
        auto t0 = std::chrono::steady_clock::now();
        const uint32_t stamp = (uint32_t)(k + 1);
        auto idx = [&](const int64_t* p) { return ((p[2] + 1) * Y + (p[1] + 1)) * X + p[0] + 1; };
        const int64_t s = idx(&q[6 * k]), t = idx(&q[6 * k + 3]);
        const int64_t gx = q[6 * k + 3] + 1, gy = q[6 * k + 4] + 1, gz = q[6 * k + 5] + 1;
        auto h = [&](int64_t v) {
            int64_t x = v % X, y = (v / X) % Y, z = v / (X * Y);
            int64_t a = std::llabs(x - gx), b = std::llabs(y - gy), c = std::llabs(z - gz);
            if (a < b) std::swap(a, b); if (b < c) std::swap(b, c); if (a < b) std::swap(a, b);
            return s3 * c + s2 * (b - c) + (double)(a - b);
        };
        std::priority_queue<Node, std::vector<Node>, Cmp> open;
        double cost = -1; int64_t exp = 0;
        if (fr[s] && fr[t]) {
            g[s] = 0; seen[s] = stamp; open.push({h(s), 0, s});
            while (!open.empty()) {
                Node n = open.top(); open.pop();
                if (closed[n.v] == stamp || n.g > g[n.v]) continue;
                closed[n.v] = stamp; ++exp;
                if (n.v == t) { cost = n.g; break; }
                for (size_t m = 0; m < mv.size(); ++m) {
                    const int64_t w = n.v + mv[m];
                    if (closed[w] == stamp) continue;
                    bool ok = true;
                    for (int64_t o : need[m]) if (!fr[n.v + o]) { ok = false; break; }
                    if (!ok) continue;
                    const double ng = n.g + mc[m];
                    if (seen[w] != stamp || ng < g[w]) {
                        seen[w] = stamp; g[w] = ng; open.push({ng + h(w), ng, w});
                    }
                }
            }
        }
        double sec = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        std::printf("%.9f %lld %.9f\n", cost, (long long)exp, sec);
    }
    // This image's own peak resident memory on stderr (its getrusage would also count the
    // parent's pages mapped before exec).
    if (FILE* st = std::fopen("/proc/self/status", "r")) {
        char line[256];
        while (std::fgets(line, sizeof line, st))
            if (!std::strncmp(line, "VmHWM:", 6)) std::fputs(line, stderr);
        std::fclose(st);
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
