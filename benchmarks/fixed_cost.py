"""Fixed cost per call: ``search()`` and ``plan()`` on a prebuilt world, outside the expansions.

Usage::

    python benchmarks/fixed_cost.py [--calls 3000] [--parts] [--smoke]

The query is one move long (start and goal are neighbouring free cells of a 64^3 cubic
world with a few obstacles), so the two expansions it makes (26 nodes generated) cost a small
share: the figure is what every call pays whatever its length (argument checks, endpoint
checks, the kernel call, building the result). ``plan()`` is timed with its endpoints given
three ways, as users write them: a tuple of floats (the README's example), a list, and a
float64 array; ``shortcut()`` (what ``plan(..., shortcut=True)`` adds) of a four-cell path
whose ends see each other. The same search with the goal at the start (one expansion, no node
generated) is the fixed cost with no expansion work at all. Taking turns between this
world and a second one (the same query on a BCC world of the same box), each ``search()``
also pays for the switch of world: what a query loop comparing lattices query by query pays.

Timing (``benchmarks/harness.py``): this thread's CPU time over batches of 100 calls, the
median per call over the batches (a CPU clock read costs about a microsecond, so single
short calls are not timed one by one); the kinds of call take turns batch by batch. After
warm-up: compilation is never counted. ``search_speed.py`` prints :func:`line`.
Goals (issue 41): ``search()`` <= 5 us, ``plan()`` <= 15 us with any of the three endpoint
kinds.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import harness  # noqa: E402  (the sibling module)

from planner import search as S  # noqa: E402
from planner.lattice import Lattice  # noqa: E402
from planner.planning import plan  # noqa: E402
from planner.world import World  # noqa: E402

BATCH = 100


def _query():
    """The one-move query: a 64^3 cubic world with a few obstacles, and two neighbouring
    free cells, searched once to warm everything up."""
    rng = np.random.default_rng(0)
    blocked = rng.integers(0, 64, (2000, 3))
    blocked = blocked[blocked[:, 0] >= 20]  # the query's corner stays free
    world = World(Lattice.named("cubic", 1.0), blocked, [[0, 0, 0], [63, 63, 63]])
    s, g = np.array([10, 10, 10]), np.array([11, 10, 10])
    S.warm_up()
    return world, s, g


def _per_call(named: dict, calls: int) -> dict:
    """Median thread CPU seconds per call of each callable of ``named``: ``calls`` calls
    each, in batches of :data:`BATCH`, the callables taking turns batch by batch."""
    batches = max(3, calls // BATCH)

    def batch(fn):
        def run(_):
            t0 = harness.cpu_clock()
            for _ in range(BATCH):
                fn()
            return (harness.cpu_clock() - t0) / BATCH
        return run

    sides = {k: batch(fn) for k, fn in named.items()}
    per = {k: np.empty(batches) for k in named}
    for i in range(batches):
        for k, side in sides.items():
            per[k][i] = side(i)
    return {k: float(np.median(v)) for k, v in per.items()}


def _second(world: World, s: np.ndarray) -> tuple[World, np.ndarray, np.ndarray]:
    """The one-move query on a BCC world of ``world``'s box and obstacle points."""
    lat = Lattice.named("bcc", 1.0)
    other = World(lat, lat.quantize(world.lattice.to_world(world.blocked)), world.bounds)
    a = lat.quantize(world.lattice.to_world(s[None]))[0]
    b = a + np.array([1, 0, 0])
    assert other.is_free(np.array([a, b])).all()
    return other, a, b


def fixed_cost(calls: int = 3000) -> dict:
    """Median thread CPU seconds per call of ``search()`` (``search``), of the engine time it
    reports (``engine``, ``SearchResult.seconds``), of ``search()`` from a cell to itself
    (``same``), of ``search()`` taking turns between two worlds (``turns``, per call) and
    of ``plan()`` with tuple, list and array endpoints (``plan tuple``, ``plan list``,
    ``plan array``) and of ``shortcut()`` of a four-cell path (``shortcut``)."""
    world, s, g = _query()
    other, s2, g2 = _second(world, s)

    def turns():
        S.search(world, s, g)
        S.search(other, s2, g2)

    ps, pg = world.lattice.to_world(np.array([s, g]))
    ts, tg = tuple(float(v) for v in ps), tuple(float(v) for v in pg)
    ls, lg = list(ts), list(tg)
    ps, pg = np.ascontiguousarray(ps, dtype=np.float64), np.ascontiguousarray(pg, np.float64)
    # a short path to smooth (the corner x < 20 is free): one sight test keeps its ends
    path = np.array([s, g, g + np.array([1, 1, 0]), g + np.array([2, 1, 0])])
    for _ in range(50):
        S.search(world, s, g)
        S.shortcut(world, path)
        plan(world, ts, tg)
        plan(world, ls, lg)
        plan(world, ps, pg)
    out = _per_call({"search": lambda: S.search(world, s, g),
                     "same": lambda: S.search(world, s, s),
                     "turns": turns,
                     "plan tuple": lambda: plan(world, ts, tg),
                     "plan list": lambda: plan(world, ls, lg),
                     "plan array": lambda: plan(world, ps, pg),
                     "shortcut": lambda: S.shortcut(world, path)}, calls)
    out["turns"] /= 2  # two searches per call
    out["engine"] = float(np.median([S.search(world, s, g).seconds for _ in range(BATCH)]))
    return out


def line(calls: int = 3000) -> str:
    """One printed line of :func:`fixed_cost` (microseconds)."""
    r = fixed_cost(calls)
    harness.record("fixed_cost", dict(calls=calls, batch=BATCH,
                                      **{f"{k.replace(' ', '_')}_us": v * 1e6
                                         for k, v in r.items()}))
    return (f"fixed cost per call on a prebuilt world (one-move query; thread CPU time, median "
            f"per call over batches of {BATCH}, {calls} calls): search() "
            f"{r['search'] * 1e6:.1f} us (goal <= 5; its engine call "
            f"{r['engine'] * 1e6:.1f} us; {r['same'] * 1e6:.1f} us from a cell to itself; "
            f"{r['turns'] * 1e6:.1f} us taking turns between two worlds), "
            f"plan() with tuple / list / array endpoints {r['plan tuple'] * 1e6:.1f} / "
            f"{r['plan list'] * 1e6:.1f} / {r['plan array'] * 1e6:.1f} us (goal <= 15 each); "
            f"shortcut() of a four-cell path {r['shortcut'] * 1e6:.1f} us")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    harness.add_arguments(ap, repeat=None)
    ap.add_argument("--calls", type=int, default=3000, help="calls per figure")
    ap.add_argument("--parts", action="store_true",
                    help="also search()'s engine call against the rest of the call")
    a = ap.parse_args(argv)
    calls = 300 if a.smoke else a.calls
    with harness.session("fixed cost per call on a prebuilt world", smoke=a.smoke):
        r = fixed_cost(calls)
        print(f"search()            {r['search'] * 1e6:7.2f} us   (goal <= 5)")
        print(f"search() to itself  {r['same'] * 1e6:7.2f} us")
        print(f"search(), two worlds taking turns  {r['turns'] * 1e6:7.2f} us")
        for k in ("tuple", "list", "array"):
            print(f"plan() {k:5s} ends   {r['plan ' + k] * 1e6:7.2f} us   (goal <= 15)")
        print(f"shortcut(), 4 cells {r['shortcut'] * 1e6:7.2f} us")
        if a.parts:
            print(f"search()'s engine call (SearchResult.seconds, its own clock) "
                  f"{r['engine'] * 1e6:.2f} us; the rest of the call "
                  f"{(r['search'] - r['engine']) * 1e6:.2f} us")
        for k in ("tuple", "list"):
            print(harness.single_ratio(f"plan() {k} / array endpoints", r["plan " + k],
                                       r["plan array"], goal="1: no endpoint kind pays more",
                                       note="medians per call"))
        print(harness.single_ratio("plan() array / search()", r["plan array"], r["search"],
                                   note="medians per call: what plan() adds to a search"))
    return 0


if __name__ == "__main__":
    sys.exit(main())
