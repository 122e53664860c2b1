"""Cold numbers where users feel them: 1,000 DA1 queries in a new process, two checkouts.

Usage::

    python benchmarks/cold_queries.py                          # this checkout, 3 runs
    python benchmarks/cold_queries.py --src ../old-checkout    # old first, then this one
    python benchmarks/cold_queries.py --queries 1000 --runs 5

Each run is a new Python process that imports the package from its checkout (``PYTHONPATH``),
reads the Warframe DA1 map and its scenario file, builds the world and answers the first
``--queries`` queries one by one with ``search()``, as a user's script would. It reports the
process's wall time and its parts: import, reading the map, building the world, the first query
(which loads the compiled kernels from the package's cache) and the remaining queries. Before
the timed runs, each checkout runs once untimed so that its kernel cache is filled: compilation
is never counted. With ``--src``, the checkouts take turns run by run and the last column is the
median ratio this checkout / the other one, so both see the same machine load.

Every run checks each query's cost against the scenario file's optimal cost and prints the
number of mismatches. No assertions: this prints figures.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DA1 = ROOT / ".." / "shared" / "data" / "warframe" / "DA1.3dmap"
PARTS = ("process", "import", "read", "build", "first", "queries")


def child(path: str, queries: int) -> None:
    """One run inside the new process: print its timings (s) as one JSON line."""
    t0 = time.perf_counter()
    import numpy as np

    from planner.lattice import Lattice
    from planner.search import search
    from planner.world import World

    t1 = time.perf_counter()
    dims = np.loadtxt(path, max_rows=1, usecols=(1, 2, 3), dtype=np.int64)
    blocked = np.loadtxt(path, skiprows=1, dtype=np.int64, ndmin=2)
    scen = np.loadtxt(f"{path}.3dscen", skiprows=2, ndmin=2)[:queries]
    t2 = time.perf_counter()
    world = World(Lattice.named("cubic", 1.0), blocked, np.array([[0, 0, 0], dims - 1.0]))
    t3 = time.perf_counter()
    starts = scen[:, :3].astype(np.int64)
    goals = scen[:, 3:6].astype(np.int64)
    costs = [search(world, starts[0], goals[0]).cost]
    t4 = time.perf_counter()
    costs += [search(world, s, g).cost for s, g in zip(starts[1:], goals[1:], strict=True)]
    t5 = time.perf_counter()
    bad = sum(abs(c - q) > 1e-6 * q for c, q in zip(costs, scen[:, 6], strict=True))
    print(json.dumps({"import": t1 - t0, "read": t2 - t1, "build": t3 - t2, "first": t4 - t3,
                      "queries": t5 - t4, "mismatches": int(bad)}))


def run(src: Path, queries: int) -> dict:
    """Run :func:`child` in a new process on checkout ``src``; add the process's wall time."""
    env = dict(os.environ, PYTHONPATH=str(src))
    t0 = time.perf_counter()
    out = subprocess.run([sys.executable, __file__, "--child", str(DA1), str(queries)],
                         env=env, cwd=src, capture_output=True, text=True, check=True)
    wall = time.perf_counter() - t0
    return {"process": wall, **json.loads(out.stdout.strip().splitlines()[-1])}


def main() -> int:
    if len(sys.argv) == 4 and sys.argv[1] == "--child":
        child(sys.argv[2], int(sys.argv[3]))
        return 0
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--queries", type=int, default=1000, help="DA1 queries per run (1000)")
    ap.add_argument("--runs", type=int, default=3, help="timed runs per checkout (3)")
    ap.add_argument("--src", type=Path, help="another checkout to compare with (runs first)")
    a = ap.parse_args()
    if not DA1.exists():
        print(f"skipped: {DA1} is absent")
        return 0
    names = {"this": ROOT}
    if a.src is not None:
        names = {"other": a.src.resolve(), "this": ROOT}
    for src in names.values():  # fill each checkout's kernel cache; never timed
        run(src, 2)
    rows: dict[str, list[dict]] = {n: [] for n in names}
    for i in range(a.runs):
        for n, src in names.items():
            rows[n].append(run(src, a.queries))
            print(f"run {i + 1}/{a.runs} {n}: {rows[n][-1]['process']:.2f} s", file=sys.stderr)
    print(f"{a.queries} DA1 queries, one search() each, new process per run; "
          f"median of {a.runs} runs (s)")
    print(f"{'checkout':8s} " + " ".join(f"{p:>8s}" for p in PARTS) + f" {'mismatch':>8s}")
    for n, rs in rows.items():
        med = {p: statistics.median(r[p] for r in rs) for p in PARTS}
        print(f"{n:8s} " + " ".join(f"{med[p]:8.3f}" for p in PARTS)
              + f" {max(r['mismatches'] for r in rs):8d}")
    if "other" in rows:
        ratio = {p: statistics.median(t[p] / o[p] for t, o in zip(rows["this"], rows["other"],
                                                                  strict=True)) for p in PARTS}
        print(f"{'this/old':8s} " + " ".join(f"{ratio[p]:8.2f}" for p in PARTS))
    return 0


if __name__ == "__main__":
    sys.exit(main())
