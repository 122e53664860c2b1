"""Cold numbers where users feel them: 1,000 DA1 queries in a new process, two checkouts.

Usage::

    python benchmarks/cold_queries.py                          # this checkout, 3 runs
    python benchmarks/cold_queries.py --src ../old-checkout    # old first, then this one
    python benchmarks/cold_queries.py --queries 1000 --runs 5
    python benchmarks/cold_queries.py --smoke                  # 20 queries, one run

Each run is a new Python process that imports the package from its checkout (``PYTHONPATH``),
reads the Warframe DA1 map and its scenario file, builds the world and answers the first
``--queries`` queries one by one with ``search()``, as a user's script would. It reports the
process's wall time and its parts: import, reading the map, building the world, the first query
(which loads the compiled kernels from the package's cache) and the remaining queries: the
process's wall time and CPU time (this process's children, ``os.times``), the parts by the
child's own CPU clock (``time.process_time``). Before
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

# The sibling harness module; imported by the parent only (it imports numpy, which the
# child must time as part of its import).
sys.path.insert(0, str(Path(__file__).resolve().parent))

ROOT = Path(__file__).resolve().parents[1]
PARTS = ("process", "cpu", "import", "read", "build", "first", "queries")


def child(path: str, queries: int) -> None:
    """One run inside the new process: print its timings (s) as one JSON line."""
    clock = time.process_time
    t0 = clock()
    import numpy as np

    from planner.lattice import Lattice
    from planner.search import search
    from planner.world import World

    t1 = clock()
    dims = np.loadtxt(path, max_rows=1, usecols=(1, 2, 3), dtype=np.int64)
    blocked = np.loadtxt(path, skiprows=1, dtype=np.int64, ndmin=2)
    scen = np.loadtxt(f"{path}.3dscen", skiprows=2, ndmin=2)[:queries]
    t2 = clock()
    world = World(Lattice.named("cubic", 1.0), blocked, np.array([[0, 0, 0], dims - 1.0]))
    t3 = clock()
    starts = scen[:, :3].astype(np.int64)
    goals = scen[:, 3:6].astype(np.int64)
    costs = [search(world, starts[0], goals[0]).cost]
    t4 = clock()
    costs += [search(world, s, g).cost for s, g in zip(starts[1:], goals[1:], strict=True)]
    t5 = clock()
    bad = sum(abs(c - q) > 1e-6 * q for c, q in zip(costs, scen[:, 6], strict=True))
    print(json.dumps({"import": t1 - t0, "read": t2 - t1, "build": t3 - t2, "first": t4 - t3,
                      "queries": t5 - t4, "mismatches": int(bad)}))


def run(src: Path, queries: int, da1: Path) -> dict:
    """Run :func:`child` in a new process on checkout ``src``; add the process's wall time
    and its CPU time."""
    import harness

    env = dict(os.environ, PYTHONPATH=str(src))
    t0 = time.perf_counter()
    out, cpu = harness.process_cpu(lambda: subprocess.run(
        [sys.executable, __file__, "--child", str(da1), str(queries)], env=env, cwd=src,
        capture_output=True, text=True, check=True))
    wall = time.perf_counter() - t0
    return {"process": wall, "cpu": cpu, **json.loads(out.stdout.strip().splitlines()[-1])}


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if len(argv) == 3 and argv[0] == "--child":
        child(argv[1], int(argv[2]))
        return 0
    import harness

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--queries", type=int, default=1000, help="DA1 queries per run (1000)")
    ap.add_argument("--runs", type=int, default=3, help="timed runs per checkout (3)")
    ap.add_argument("--src", type=Path, help="another checkout to compare with (runs first)")
    harness.add_arguments(ap, repeat=None, data=True)
    a = ap.parse_args(argv)
    if a.smoke:
        a.queries, a.runs = 20, 1
    da1 = a.data / "warframe" / "DA1.3dmap"
    with harness.session("DA1 queries in a new process per run", smoke=a.smoke):
        if not da1.exists():
            return harness.skip(f"{da1} is absent")
        return _measure(a, da1)


def _measure(a, da1: Path) -> int:
    import harness

    names = {"this": ROOT}
    if a.src is not None:
        names = {"other": a.src.resolve(), "this": ROOT}
    for src in names.values():  # fill each checkout's kernel cache; never timed
        run(src, 2, da1)
    rows: dict[str, list[dict]] = {n: [] for n in names}
    for i in range(a.runs):
        for n, src in names.items():
            rows[n].append(run(src, a.queries, da1))
            print(f"run {i + 1}/{a.runs} {n}: {rows[n][-1]['process']:.2f} s", file=sys.stderr)
    print(f"{a.queries} DA1 queries, one search() each, new process per run; "
          f"median of {a.runs} runs (s; process: wall, cpu: the process's CPU, the parts: "
          "its CPU clock)")
    print(f"{'checkout':8s} " + " ".join(f"{p:>8s}" for p in PARTS) + f" {'mismatch':>8s}")
    for n, rs in rows.items():
        med = {p: statistics.median(r[p] for r in rs) for p in PARTS}
        print(f"{n:8s} " + " ".join(f"{med[p]:8.3f}" for p in PARTS)
              + f" {max(r['mismatches'] for r in rs):8d}")
    if "other" in rows:
        ratio = {p: statistics.median(t[p] / o[p] for t, o in zip(rows["this"], rows["other"],
                                                                  strict=True)) for p in PARTS}
        print(f"{'this/old':8s} " + " ".join(f"{ratio[p]:8.2f}" for p in PARTS))
        print(harness.ratio_line("process CPU this/other checkout",
                                 [r["cpu"] for r in rows["this"]],
                                 [r["cpu"] for r in rows["other"]], note="paired per run"))
    this = rows["this"]
    print(harness.ratio_line("setup/queries (import, read, build, first query / the rest)",
                             [r["import"] + r["read"] + r["build"] + r["first"] for r in this],
                             [r["queries"] for r in this], note="per run, CPU"))
    return 1 if any(r["mismatches"] for rs in rows.values() for r in rs) else 0


if __name__ == "__main__":
    sys.exit(main())
