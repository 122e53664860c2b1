"""Start/goal pairs identical for every lattice and method of a benchmark group."""

from __future__ import annotations

from collections import Counter

import numpy as np


def sample_queries(
    worlds: dict,
    bounds: np.ndarray,
    n: int,
    seed: int,
    min_distance: float = 0.3,
    max_tries: int = 200,
    *,
    free=None,
    neighbors: str | None = "full",
) -> tuple[np.ndarray, np.ndarray, dict]:
    """Sample ``n`` start/goal pairs in continuous space, kept when some lattice can run
    them (both ends free in it, connected in one of them).

    Candidates are drawn uniformly in the map's box ``bounds`` (a rotated world is in the
    map's own frame too, :mod:`planner.bench.worlds`), so every rotation of a map sees the
    same stream of candidates.

    Parameters
    ----------
    worlds : dict of str -> World
        Every lattice world of the group; a pair is kept when both points are free in at
        least one of them (a lattice that blocks an end fails that query: at equal cell
        volume the lattices block different shares of the free space, and that loss is
        part of the answer).
    bounds : ndarray, shape (2, 3)
        The map's own world box (m) to sample in (before rotation).
    n : int
        Pairs wanted.
    min_distance : float
        Minimum start-goal distance as a fraction of the box diagonal (trivial queries
        measure nothing).
    free : FreeSpace, optional
        Observed free space (:class:`planner.bench.worlds.FreeSpace`, or any object with
        ``sample(rng, n) -> (n, 3)`` points): candidates are drawn uniformly from it
        instead of the box, so a map with free-space information is queried only where it
        was observed (and a building whose box is mostly unobserved still yields queries).
    neighbors : str or None
        Move set of the connectivity check: a pair is kept only if lattice A* with these
        moves connects it in at least one world (a pair no lattice connects compares
        nothing, and an any-angle search would spend its whole budget proving it). One
        world that connects it is enough, so a lattice that loses a passage still shows as
        a failure of that lattice. ``"full"`` contains the face moves, so it connects
        whatever ``"face"`` does. None: no check.

    Returns
    -------
    starts, goals : ndarray, shape (n', 3)
        ``n' <= n`` when the free space is too small to find more.
    dropped : dict
        Counts of rejected candidates by reason (``"start or goal blocked in every
        lattice"``, ...), and per lattice: ``"candidates free in some lattice"`` (the
        candidates at least one lattice could run), ``"candidates blocked in fcc"`` (of
        those, the ones whose start or goal FCC blocks) and ``"kept but blocked in fcc"``
        (kept pairs FCC cannot run).
    """
    rng = np.random.default_rng(seed)
    lo, hi = np.asarray(bounds, dtype=float)
    diag = float(np.linalg.norm(hi - lo))
    dropped: Counter = Counter()
    starts, goals = [], []
    blocked_in: Counter = Counter()  # candidates whose start or goal each lattice blocks
    kept_blocked: Counter = Counter()
    candidates = 0
    batch = max(64, 4 * n)
    for _ in range(max_tries):
        if len(starts) >= n:
            break
        if free is None:
            s = rng.uniform(lo, hi, (batch, 3))
            g = rng.uniform(lo, hi, (batch, 3))
            ok = np.ones(batch, dtype=bool)
        else:
            s, g = free.sample(rng, batch), free.sample(rng, batch)
            ok = np.all((s >= lo) & (s <= hi) & (g >= lo) & (g <= hi), axis=1)
            dropped["start or goal outside the map box"] += int(np.sum(~ok))
        short = np.linalg.norm(g - s, axis=1) < min_distance * diag
        dropped["start and goal too close"] += int(np.sum(short & ok))
        ok &= ~short
        # A pair is kept when some lattice has both ends free (a lattice that blocks an
        # end of it fails the query, and that loss is part of its answer); the drops are
        # counted per lattice for the report.
        free_s = {name: w.points_free(w.to_local(s)) for name, w in worlds.items()}
        free_g = {name: w.points_free(w.to_local(g)) for name, w in worlds.items()}
        both = {name: free_s[name] & free_g[name] for name in worlds}
        some = np.logical_or.reduce(list(both.values()))
        dropped["start or goal blocked in every lattice"] += int(np.sum(ok & ~some))
        ok &= some
        for name in worlds:
            blocked_in[name] += int(np.sum(ok & ~both[name]))
        cand = np.flatnonzero(ok)
        while len(cand) and len(starts) < n:
            # only as many as still wanted: a check is a search per pair
            take, cand = cand[:n - len(starts)], cand[n - len(starts):]
            if neighbors is not None:
                linked = _connected(worlds, s[take], g[take], neighbors,
                                    {k: v[take] for k, v in both.items()})
                dropped["start and goal connected in no lattice"] += int(np.sum(~linked))
                take = take[linked]
            for i in take:
                starts.append(s[i])
                goals.append(g[i])
                for name in worlds:
                    kept_blocked[name] += int(not both[name][i])
        candidates += int(np.sum(ok))
    dropped = {k: v for k, v in dropped.items() if v}
    dropped["candidates free in some lattice"] = candidates
    for name in worlds:
        dropped[f"candidates blocked in {name}"] = blocked_in[name]
        dropped[f"kept but blocked in {name}"] = kept_blocked[name]
    return (np.array(starts).reshape(-1, 3), np.array(goals).reshape(-1, 3), dropped)


def _connected(worlds: dict, starts: np.ndarray, goals: np.ndarray, neighbors: str,
               free: dict | None = None) -> np.ndarray:
    """(Q,) bool: lattice A* (``neighbors`` moves) connects start i and goal i (points, m)
    in at least one of ``worlds`` where both are free (``free``: name -> (Q,) bool; None:
    free in every world). A search that stops at its budget counts as connected (not
    proved otherwise)."""
    from planner.search import search_many  # lazy: numba

    linked = np.zeros(len(starts), dtype=bool)
    for w in worlds.values():
        todo = np.flatnonzero(~linked)
        if not len(todo):
            break
        if free is not None:
            name = next(k for k, v in worlds.items() if v is w)
            todo = todo[free[name][todo]]
            if not len(todo):
                continue

        def q(p, w=w):  # the map's points in the world's (local) cells
            return w.lattice.quantize(w.to_local(p))

        found = search_many(w, q(starts[todo]), q(goals[todo]), neighbors=neighbors)
        linked[todo] = [r.status != "unreachable" for r in found]
    return linked


def scenario_queries(path: str, n: int, seed: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``n`` queries of a MovingAI ``.3dscen`` file (evenly spread over its buckets).

    Returns starts, goals (n, 3) as float points and the listed optimal costs (n,).
    """
    from planner.io import load_scenarios  # lazy: scipy

    sc = load_scenarios(path)
    starts, goals, costs = sc.starts, sc.goals, sc.costs
    k = len(costs)
    idx = np.unique(np.linspace(0, k - 1, min(n, k)).round().astype(int))
    return starts[idx].astype(float), goals[idx].astype(float), costs[idx]
