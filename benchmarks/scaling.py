"""Scaling: time and peak memory of one corner-to-corner A* query on 64^3 ... 512^3 worlds,
ours (cubic-26) against the C++ anchor, optionally our FCC at the same cell volume.

Usage::

    python benchmarks/scaling.py                         # 64, 128, 256, 512
    python benchmarks/scaling.py --sizes 64,128 --fcc    # also FCC at the same cell volume
    python benchmarks/scaling.py --sizes 256 --density 0.2 --seed 3
    python benchmarks/scaling.py --smoke                 # 32^3, seconds

World: ``n^3`` cubic cells of 1 m, a seeded field of random axis-aligned boxes (edges
``n/32 .. n/8`` cells) blocking about ``--density`` of the cells, with a clear cube at two
opposite corners; the query runs from cell (1, 1, 1) to (n-2, n-2, n-2) (points, m, so FCC
runs between the cells holding them). The same field for every engine; our cost is
checked against the anchor's.

Measured, each engine in a process of its own (peak memory is per process):

* ours: this thread's CPU seconds of ``search()`` (after the warm-up: no JIT) on the
  world's first query and on the same query again ("repeat": the world's cell -> node map
  is then reused; the floor allocates its grid and slot map before its clock starts); the
  world's bytes
  (occupancy bits or hash set, and its unknown-cell bits or blocked-cell list); the
  search's own arrays (``SearchResult.peak_bytes``); and the peak resident memory during
  the two searches above the process's memory before the world was built (the kernel's
  high-water mark, reset after the build with ``/proc/self/clear_refs``, freed build
  temporaries handed back first): world + search, without the interpreter, numpy and numba;
* the floor (``benchmarks/cpp_anchor.py``, g++ -O3, compiled at run time, called through
  ctypes; skipped with a note when there is no compiler): its thread CPU seconds of the
  search and, measured as ours, the peak resident memory above the process before the map
  was made (bit grid, slot map, node records and heaps).

Ratios are ours / anchor (time and memory; lower is better for us). The machine may be
shared: trust the ratios of one run, not absolute times. No assertions: this prints figures.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import harness  # noqa: E402  (the sibling module)

HERE = Path(__file__).resolve().parent
SIZES = (64, 128, 256, 512)


def obstacle_field(n: int, density: float = 0.15, seed: int = 0) -> np.ndarray:
    """(n, n, n) bool, True = blocked: seeded random boxes until ``density`` of the cells
    are blocked, with a clear cube (edge max(3, n/16)) at the corners (0,0,0) and (n-1)^3."""
    rng = np.random.default_rng([seed, n])
    blocked = np.zeros((n, n, n), dtype=bool)
    lo_e, hi_e = max(1, n // 32), max(2, n // 8)
    target = density * n**3
    count = 0
    while count < target:
        for _ in range(16):
            e = rng.integers(lo_e, hi_e + 1, size=3)
            c = rng.integers(0, n, size=3)
            x0, y0, z0 = np.maximum(c - e // 2, 0)
            blocked[x0:x0 + e[0], y0:y0 + e[1], z0:z0 + e[2]] = True
        count = int(np.count_nonzero(blocked))
    k = max(3, n // 16)
    blocked[:k, :k, :k] = False
    blocked[-k:, -k:, -k:] = False
    return blocked


def query_points(n: int) -> tuple[np.ndarray, np.ndarray]:
    """Start and goal (m): the centres of cubic cells (1, 1, 1) and (n-2, n-2, n-2)."""
    return np.full(3, 1.0), np.full(3, n - 2.0)


def _rss_now() -> int:
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")


def _trim() -> None:
    """glibc's malloc_trim(0), where there is one (else nothing)."""
    import ctypes
    import ctypes.util

    try:
        ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6").malloc_trim(0)
    except (OSError, AttributeError):
        pass


def ours(n: int, lattice: str, density: float, seed: int, memory_budget: int | None) -> dict:
    """One query with our A* (run in a child process: see the module docstring)."""
    from planner.lattice import Lattice
    from planner.search import search, warm_up
    from planner.world import World

    warm_up()
    base = _rss_now()
    t0 = harness.cpu_clock()
    blocked = obstacle_field(n, density, seed)
    lat = Lattice.named(lattice, cell_volume=1.0)
    if lattice == "cubic":
        cells = np.argwhere(blocked)
    else:
        cells = _cells_in_blocked_voxels(lat, blocked)
    del blocked
    world = World(lat, cells, np.array([[0.0] * 3, [n - 1.0] * 3]))
    del cells
    occ = world.occupancy  # built here, not inside the search
    build = harness.cpu_clock() - t0
    _trim()  # hand the build's freed temporaries back to the OS: RSS = live memory
    s, g = query_points(n)
    sc, gc = lat.quantize(np.stack([s, g]))
    reset = harness.reset_peak_rss()
    r, sec = harness.cpu_result(lambda: search(world, sc, gc, memory_budget=memory_budget))
    again = harness.cpu(lambda: search(world, sc, gc, memory_budget=memory_budget))  # reused
    peak = harness.peak_rss()
    return dict(engine=f"ours {lattice}", n=n, status=r.status, cost=r.cost,
                expansions=r.expansions, seconds=sec, repeat_seconds=again,
                build_seconds=build,
                world_bytes=int(occ.grid.nbytes + occ.table.nbytes + (
                    world.unknown_bits.bits.nbytes if world.unknown_bits is not None
                    else world.blocked.nbytes)),
                search_bytes=r.peak_bytes,
                rss_bytes=peak - base if reset else None, storage=world.storage)


def _cells_in_blocked_voxels(lat, blocked: np.ndarray) -> np.ndarray:
    """(M, 3) int64 cells of ``lat`` whose centre lies in a blocked 1 m voxel (voxel i spans
    [i - 0.5, i + 0.5) per axis), enumerated one index slab at a time."""
    n = blocked.shape[0]
    g = lat.generator
    corners = np.array(np.meshgrid(*[[-0.5, n - 0.5]] * 3)).reshape(3, -1).T
    w = corners @ np.linalg.inv(g).T
    lo = np.floor(w.min(axis=0)).astype(np.int64)
    hi = np.ceil(w.max(axis=0)).astype(np.int64)
    a = np.arange(lo[0], hi[0] + 1)
    b = np.arange(lo[1], hi[1] + 1)
    ab = np.stack(np.meshgrid(a, b, indexing="ij"), axis=-1).reshape(-1, 2)
    out = []
    for c in range(lo[2], hi[2] + 1):
        x = ab @ g[:, :2].T + c * g[:, 2]
        v = np.floor(x + 0.5).astype(np.int64)
        ok = np.all((v >= 0) & (v < n), axis=1)
        keep = np.flatnonzero(ok)
        keep = keep[blocked[v[keep, 0], v[keep, 1], v[keep, 2]]]
        if len(keep):
            out.append(np.concatenate([ab[keep], np.full((len(keep), 1), c)], axis=1))
    return np.concatenate(out) if out else np.zeros((0, 3), np.int64)


def anchor(n: int, density: float, seed: int) -> dict:
    """The C++ floor on the same field and query (run in a child process, as ours)."""
    import cpp_anchor

    cpp_anchor.library()  # compiled before the memory baseline
    base = _rss_now()
    free = ~obstacle_field(n, density, seed)
    fl = cpp_anchor.Floor(free)
    del free
    _trim()
    s, g = query_points(n)
    reset = harness.reset_peak_rss()
    (cost, exp), sec = harness.cpu_result(lambda: fl.search(s.astype(np.int64),
                                                            g.astype(np.int64)))
    peak = harness.peak_rss()
    return dict(engine="C++ anchor", n=n, status="found" if cost >= 0 else "unreachable",
                cost=float(cost) if cost >= 0 else float("inf"), expansions=int(exp),
                seconds=float(sec), rss_bytes=peak - base if reset else None,
                floor_bytes=fl.nbytes)


def _child(n: int, lattice: str, a) -> dict:
    cmd = [sys.executable, __file__, "--child", f"{n}:{lattice}", "--density", str(a.density),
           "--seed", str(a.seed)]
    if a.memory_budget:
        cmd += ["--memory-budget", str(a.memory_budget)]
    out = subprocess.run(cmd, capture_output=True, text=True)
    if out.returncode != 0:
        raise SystemExit(f"{lattice} {n}^3 failed: {out.stderr.strip()[-2000:]}")
    return json.loads(out.stdout.strip().splitlines()[-1])


def _sec(x) -> str:
    return "-" if x is None else f"{x:.3f}"


def _mb(x) -> str:
    return "-" if x is None else f"{x / 2**20:,.0f}"


def table(rows: list[dict]) -> str:
    """Markdown table, one line per world size and engine, with ratios to the anchor."""
    head = ("| world | engine | status | cost m | expansions | search s | repeat s | "
            "world MB | search MB | peak RSS MB | time / anchor | memory / anchor |")
    lines = [head, "|" + "---|" * (head.count("|") - 1)]
    for n in sorted({r["n"] for r in rows}):
        group = [r for r in rows if r["n"] == n]
        an = next((r for r in group if r["engine"] == "C++ anchor"), None)
        for r in group:
            tr = mr = "-"
            if an is not None and r is not an:
                tr = f"{r['seconds'] / an['seconds']:.2f}" if an["seconds"] > 0 else "-"
                if r.get("rss_bytes") is not None and an.get("rss_bytes"):
                    mr = f"{r['rss_bytes'] / an['rss_bytes']:.2f}"
            lines.append(
                f"| {n}^3 | {r['engine']} | {r['status']} | {r['cost']:.3f} | "
                f"{r['expansions']:,} | {r['seconds']:.3f} | {_sec(r.get('repeat_seconds'))} | "
                f"{_mb(r.get('world_bytes'))} | "
                f"{_mb(r.get('search_bytes'))} | {_mb(r.get('rss_bytes'))} | {tr} | {mr} |")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--sizes", default=",".join(map(str, SIZES)),
                    help="comma-separated world edges in cells (default 64,128,256,512)")
    ap.add_argument("--fcc", action="store_true", help="also our FCC at the same cell volume")
    ap.add_argument("--density", type=float, default=0.15, help="blocked share of the cells")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--memory-budget", type=int, default=None,
                    help="bytes our search may use (default: planner's budget)")
    ap.add_argument("--child", help=argparse.SUPPRESS)
    harness.add_arguments(ap, repeat=None)
    a = ap.parse_args(argv)
    if a.child:  # one engine run, in its own process: print its row as JSON
        n, lattice = a.child.split(":")
        if lattice == "floor":
            print(json.dumps(anchor(int(n), a.density, a.seed)))
        else:
            print(json.dumps(ours(int(n), lattice, a.density, a.seed, a.memory_budget)))
        return 0
    if a.smoke:
        a.sizes = "32"
    with harness.session("one corner-to-corner A* query as the world grows, ours vs the "
                         "C++ floor", smoke=a.smoke):
        return _run(a)


def _run(a) -> int:
    import cpp_anchor

    sizes = [int(s) for s in a.sizes.split(",") if s.strip()]
    rows, notes = [], []
    for n in sizes:
        an = _child(n, "floor", a) if cpp_anchor.available() else None
        if an is None:
            notes.append("C++ anchor skipped: no g++ / c++ on PATH")
        else:
            rows.append(an)
        for lattice in ("cubic", "fcc") if a.fcc else ("cubic",):
            r = _child(n, lattice, a)
            rows.append(r)
            if lattice == "cubic" and an is not None and r["status"] == "found":
                if abs(r["cost"] - an["cost"]) > 1e-6 * max(1.0, an["cost"]):
                    notes.append(f"{n}^3: cost mismatch, ours {r['cost']} vs anchor {an['cost']}")
        print(f"{n}^3 done", file=sys.stderr, flush=True)
    print(f"Corner-to-corner A* (26 neighbours on cubic, full neighbours on FCC; safe rule), "
          f"box field {a.density:.0%} blocked, seed {a.seed}; one query per world; each engine "
          "in its own process.\n")
    print(table(rows))
    print("\nsearch s: thread CPU time of the search call (ours: after warm-up, no JIT, the "
          "world's first query; repeat s: the same query again; anchor: one ctypes call). "
          "world MB: our occupancy and blocked-cell list; search MB: our search arrays; peak "
          "RSS MB: peak during the searches above the process before the map was made "
          "(VmHWM; world + search), each in a process of its own. Ratios: ours / anchor, "
          "first query.")
    for note in dict.fromkeys(notes):
        print(f"note: {note}")
    for n in sizes:
        an = next((r for r in rows if r["n"] == n and r["engine"] == "C++ anchor"), None)
        cu = next((r for r in rows if r["n"] == n and r["engine"] == "ours cubic"), None)
        if an is not None and cu is not None:
            print(harness.single_ratio(f"search time ours cubic / floor, {n}^3",
                                       cu["seconds"], an["seconds"], note="one query, CPU"))
            if cu.get("rss_bytes") and an.get("rss_bytes"):
                print(harness.single_ratio(f"peak memory ours cubic / floor, {n}^3",
                                           cu["rss_bytes"], an["rss_bytes"], note="VmHWM"))
    return 0


if __name__ == "__main__":
    sys.exit(main())
