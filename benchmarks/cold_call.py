"""What a call costs right after the caches were swept (cold) against the same call again at
once (hot): the floor under a D* Lite replan that keeps its path, which runs right after a
scan and a map update have swept the caches (``benchmarks/explore_speed.py``).

Usage::

    python benchmarks/cold_call.py [--calls 300] [--sweep-mb 64] [--smoke]

Each row: the median over ``--calls`` rounds of (sweep ``--sweep-mb`` MB of memory, time
the call, time it again). The calls: a ``perf_counter()`` pair; a compiled (numba) function
of one integer, and of three arrays, called through numba's dispatcher (the engine calls
its kernels' raw entry points, which skip the dispatcher's argument typing: a little
less); a D* Lite replan that keeps its path (a cell blocked far from it;
``SearchResult.seconds``, the engine time ``explore_speed.py`` compares) and an A*
``search()`` of a short query on the same world (its ``seconds``, and the whole call).
The clock is ``time.perf_counter`` (wall), not the CPU clock the other scripts use
(``benchmarks/harness.py``): the calls last 0.1-50 us and a thread CPU clock read costs
about a microsecond itself. Each row's ``ratio`` line: cold / hot, paired per round.
No assertions: this prints figures.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np
from numba import njit

sys.path.insert(0, str(Path(__file__).resolve().parent))
import harness  # noqa: E402  (the sibling module)

from planner import search as S  # noqa: E402
from planner.lattice import Lattice  # noqa: E402
from planner.search import DStarLite  # noqa: E402
from planner.world import World  # noqa: E402


@njit(cache=False)
def _one_int(x):
    return x > 0


@njit(cache=False)
def _three_arrays(a, b, c):
    return a.shape[0] + b.shape[0] + c.shape[0] > 0


def _rows(calls: int, sweep_mb: int) -> list[tuple[str, np.ndarray, np.ndarray]]:
    """(name, cold s per round, hot s per round) of each call (module docstring)."""
    big = np.zeros(sweep_mb << 20, np.uint8)

    def sweep():
        big[::64] += 1  # one write per cache line

    a = np.zeros((300, 3), np.int64)
    f = np.ones(300, np.bool_)
    one, three = _one_int, _three_arrays
    one(1)  # compiled here, outside the rounds
    three(a, f, a)
    clock = time.perf_counter

    world = World(Lattice.named("bcc", 1.0), np.zeros((0, 3), np.int64),
                  [[0, 0, 0], [40, 40, 8]])
    start = world.endpoint(np.array([1.0, 1.0, 1.0]), "start")[1]
    goal = world.endpoint(np.array([38.0, 38.0, 6.0]), "goal")[1]
    # two cells far off the path: blocking either keeps it
    far = [world.endpoint(np.array(p), "cell")[1][None] for p in ([1.0, 38.0, 1.0],
                                                                 [38.0, 1.0, 1.0])]
    state = {"planner": _fresh(world, start, goal)}
    near = state["planner"].plan().cells[4]  # a short A* query: four moves
    S.search(world, start, near)

    def timed(fn):
        t0 = clock()
        fn()
        return clock() - t0

    def replan(k):
        p = state["planner"]
        p.update(world.set_cells(far[k], True), blocked=True)
        return p.plan().seconds

    def undo():  # outside the timing: free both cells, a new planner (a freed cell repairs)
        for c in far:
            world.set_cells(c, False)
        state["planner"] = _fresh(world, start, goal)

    out = []
    for name, fn, undo_after in (
            ("perf_counter() pair", lambda k: timed(lambda: None), None),
            ("compiled call, one int", lambda k: timed(lambda: one(1)), None),
            ("compiled call, three arrays", lambda k: timed(lambda: three(a, f, a)), None),
            ("D* Lite replan that keeps its path (seconds)", replan, undo),
            ("A* search(), short query (seconds)",
             lambda k: S.search(world, start, near).seconds, None),
            ("A* search(), short query (whole call)",
             lambda k: timed(lambda: S.search(world, start, near)), None)):
        cold, hot = np.empty(calls), np.empty(calls)
        for i in range(calls):
            sweep()
            cold[i] = fn(0)
            hot[i] = fn(1)
            if undo_after is not None:
                undo_after()
        out.append((name, cold, hot))
    return out


def _fresh(world, start, goal) -> DStarLite:
    """A D* Lite planner on the world as it is, its first plan made."""
    p = DStarLite(world, start, goal)
    p.plan()
    return p


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--calls", type=int, default=300, help="rounds per row")
    ap.add_argument("--sweep-mb", type=int, default=64, help="memory swept before a call")
    harness.add_arguments(ap, repeat=None)
    a = ap.parse_args(argv)
    calls, sweep = (20, 8) if a.smoke else (a.calls, a.sweep_mb)
    with harness.session("a call right after the caches were swept against the same call "
                         "hot", smoke=a.smoke):
        print(f"median of {calls} rounds; cold: right after sweeping {sweep} MB")
        print(f"{'call':<46} {'cold us':>8} {'hot us':>8}")
        rows = _rows(calls, sweep)
        for name, cold, hot in rows:
            print(f"{name:<46} {np.median(cold) * 1e6:8.2f} {np.median(hot) * 1e6:8.2f}")
        for name, cold, hot in rows:
            print(harness.ratio_line(f"cold/hot {name}", cold, hot, note="paired per round"))
    return 0


if __name__ == "__main__":
    sys.exit(main())
