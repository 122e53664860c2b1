"""OMPL baseline speed and quality on the office map.

(a) Validity checks per second: the compiled callable OMPL calls (``world.checker.
is_valid``, :class:`planner.world.ValidityChecker`) vs a pure Python checker calling
``world.points_free`` once per state, in this process; the exact motion check in cells/s;
and the checks/s reached inside OMPL planning (cell lookups / planning wall time).

(b) Success rate, time to first solution and raw / simplified length of rrtconnect,
rrtstar, informedrrtstar, bitstar and prmstar over seeds and time limits, against the
lattice Theta* length on the same query (ratio = OMPL / Theta*).

Usage::

    python benchmarks/ompl_speed.py            # 5 seeds, 1 s and 5 s, first query (~3 min)
    python benchmarks/ompl_speed.py --quick    # 2 seeds, 1 s (~20 s)
    python benchmarks/ompl_speed.py --smoke    # (a) on 5,000 states; (b) one 0.2 s run

Rates in (a) are by this thread's CPU time (``benchmarks/harness.py``); (b) reports OMPL's
own times (its time limit is wall time). (b) needs OMPL's Python bindings: without them it
is skipped with one line.
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import statistics
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import harness  # noqa: E402  (the sibling module)

from planner import ompl, search  # noqa: E402
from planner import planning as api  # noqa: E402

ROOT = harness.ROOT
clock = harness.cpu_clock
PLANNERS = ("rrtconnect", "rrtstar", "informedrrtstar", "bitstar", "prmstar")


def checks_per_second(world, n: int, rng: np.random.Generator) -> dict:
    """States/s of the compiled callable vs per-call ``world.points_free``, cells/s of the
    exact motion check (all in this process, random points in the bounds)."""
    lo, hi = world.bounds
    pts = rng.uniform(lo, hi, size=(n, 3))
    chk = world.checker
    chk.is_valid(pts[0])  # load the kernels
    chk.check_motion(pts[0], pts[1])
    chk.checks = 0
    t0 = clock()
    for p in pts.tolist():
        chk.is_valid(p)
    compiled = n / (clock() - t0)
    m = max(n // 10, 100)
    t0 = clock()
    for p in pts[:m]:
        world.points_free(p[None])
    python = m / (clock() - t0)
    # Motions of ~1 m (RRT-like steps): cell lookups per second and motions per second.
    b = np.clip(pts[:m] + rng.normal(0, 0.6, size=(m, 3)), lo, hi)
    chk.checks = 0
    t0 = clock()
    for a, c in zip(pts[:m].tolist(), b.tolist(), strict=True):
        chk.check_motion(a, c)
    dt = clock() - t0
    return {"compiled_states_per_s": compiled, "python_states_per_s": python,
            "ratio": compiled / python, "motion_cells_per_s": chk.checks / dt,
            "motions_per_s": m / dt}


def theta_length(world, start, goal) -> float:
    lat = world.lattice
    cells = lat.quantize(np.array([start, goal], dtype=float))
    res = search.search(world, cells[0], cells[1], method="theta")
    if not res.found:
        return float("nan")
    p = np.concatenate([[start], lat.to_world(res.cells[1:-1]), [goal]])
    return float(np.linalg.norm(np.diff(p, axis=0), axis=1).sum())


def _med(xs) -> float:
    xs = [x for x in xs if x is not None]
    return statistics.median(xs) if xs else float("nan")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--map", default=str(ROOT / "maps" / "office.ply"))
    ap.add_argument("--lattice", default="cubic")
    ap.add_argument("--radius", type=float, default=0.2)
    ap.add_argument("--seeds", type=int, default=5)
    ap.add_argument("--limits", type=float, nargs="+", default=[1.0, 5.0])
    ap.add_argument("--planners", nargs="+", default=list(PLANNERS))
    ap.add_argument("--queries", default="0", help="comma list of query indices or 'all'")
    ap.add_argument("--checks", type=int, default=200_000, help="states for part (a)")
    ap.add_argument("--quick", action="store_true", help="2 seeds, 1 s, fewer checks")
    ap.add_argument("--json", help="write the rows here")
    harness.add_arguments(ap, repeat=None)
    args = ap.parse_args(argv)
    if args.quick:
        args.seeds, args.limits, args.checks = 2, [1.0], 50_000
    if args.smoke:
        args.seeds, args.limits, args.checks = 1, [0.2], 5_000
        args.planners = args.planners[:1]
    with harness.session("OMPL baseline: validity checks and planners", smoke=args.smoke):
        return _run(args)


def _run(args: argparse.Namespace) -> int:
    t0 = clock()
    world = api.build_world(args.map, args.lattice, radius=args.radius)
    print(f"world: {world!r}, cell size {world.cell_size:.3f} m, "
          f"built in {clock() - t0:.1f} s")
    side = Path(args.map).with_suffix(".json")
    queries = json.loads(side.read_text()).get("queries", []) if side.is_file() else []
    if not queries:
        lo, hi = world.bounds
        queries = [{"start": (lo + 0.1 * (hi - lo)).tolist(),
                    "goal": (hi - 0.1 * (hi - lo)).tolist()}]
    pick = range(len(queries)) if args.queries == "all" else [
        int(i) for i in args.queries.split(",")]

    print("\n(a) validity checks per second (this process)")
    cps = checks_per_second(world, args.checks, np.random.default_rng(0))
    print(f"  compiled callable  {cps['compiled_states_per_s']:12,.0f} states/s")
    print(f"  world.points_free  {cps['python_states_per_s']:12,.0f} states/s (one per call)")
    print(f"  ratio              {cps['ratio']:12.1f} x")
    print(harness.single_ratio("compiled callable / world.points_free states per s",
                               cps["compiled_states_per_s"], cps["python_states_per_s"],
                               note="thread CPU"))
    print(f"  exact motion check {cps['motions_per_s']:12,.0f} motions/s "
          f"({cps['motion_cells_per_s']:,.0f} cells/s)")

    if importlib.util.find_spec("ompl") is None:
        print("\n(b) skipped: OMPL's Python bindings (module ompl) are not installed")
        return 0
    print("\n(b) planners (medians over seeds; ratio = OMPL length / Theta* length)")
    hdr = (f"{'q':>2} {'planner':<16}{'limit':>6}{'succ':>6}{'t_first':>9}{'raw':>8}"
           f"{'simp':>8}{'theta':>8}{'raw/th':>8}{'simp/th':>8}{'checks/s':>11}")
    print(hdr)
    rows = []
    for qi in pick:
        q = queries[qi]
        s, g = np.asarray(q["start"], float), np.asarray(q["goal"], float)
        th = theta_length(world, s, g)
        for name in args.planners:
            for limit in args.limits:
                rs = ompl.run_seeds(world, s, g, range(args.seeds), planner=name,
                                    time_limit=limit)
                ok = [r for r in rs if r.found]
                raw = _med(r.length_raw for r in ok)
                simp = _med(r.length_simplified or r.length_raw for r in ok)
                row = {"query": qi, "planner": name, "limit": limit,
                       "success": len(ok) / len(rs),
                       "t_first": _med(r.time_to_first_solution for r in ok),
                       "raw": raw, "simplified": simp, "theta": th,
                       "checks_per_s": _med(r.checks_per_second for r in rs),
                       "reasons": sorted({r.reason for r in rs if r.reason})}
                rows.append(row)
                print(f"{qi:>2} {name:<16}{limit:>6g}{row['success']:>6.0%}"
                      f"{row['t_first']:>9.3f}{raw:>8.2f}{simp:>8.2f}{th:>8.2f}"
                      f"{raw / th:>8.3f}{simp / th:>8.3f}{row['checks_per_s']:>11,.0f}")
                for why in row["reasons"]:
                    print(f"{'':>3}  note: {why}")
    for row in rows:
        print(harness.single_ratio(f"OMPL {row['planner']} {row['limit']:g} s simplified "
                                   f"length / Theta*, query {row['query']}",
                                   row["simplified"], row["theta"], note="median of seeds"))
    print(f"\ntotal {clock() - t0:.0f} s CPU")
    if args.json:
        Path(args.json).write_text(json.dumps({"checks": cps, "rows": rows}, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
