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
    """Sample ``n`` start/goal pairs in continuous space, kept only if valid everywhere.

    Candidates are drawn uniformly in the map's box ``bounds`` (a rotated world is in the
    map's own frame too, :mod:`planner.bench.worlds`), so every rotation of a map sees the
    same stream of candidates.

    Parameters
    ----------
    worlds : dict of str -> World
        Every lattice world of the group; a pair is kept only if both points are free
        in all of them.
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
        Counts of rejected candidates by reason, e.g. ``{"start blocked in fcc": 12}``.
    """
    rng = np.random.default_rng(seed)
    lo, hi = np.asarray(bounds, dtype=float)
    diag = float(np.linalg.norm(hi - lo))
    dropped: Counter = Counter()
    starts, goals = [], []
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
        for what, pts in (("start", s), ("goal", g)):
            # Per lattice, so that a point inside a wall (blocked everywhere) is not charged
            # to whichever lattice happens to be checked first.
            valid = {name: w.points_free(w.to_local(pts)) for name, w in worlds.items()}
            every = np.logical_and.reduce([~v for v in valid.values()])
            dropped[f"{what} blocked in every lattice"] += int(np.sum(ok & every))
            for name, v in valid.items():
                key = f"{what} blocked in {name}, free in another lattice"
                dropped[key] += int(np.sum(ok & ~v & ~every))
            ok &= np.logical_and.reduce(list(valid.values()))
        cand = np.flatnonzero(ok)
        while len(cand) and len(starts) < n:
            # only as many as still wanted: a check is a search per pair
            take, cand = cand[:n - len(starts)], cand[n - len(starts):]
            if neighbors is not None:
                linked = _connected(worlds, s[take], g[take], neighbors)
                dropped["start and goal connected in no lattice"] += int(np.sum(~linked))
                take = take[linked]
            for i in take:
                starts.append(s[i])
                goals.append(g[i])
    return (np.array(starts).reshape(-1, 3), np.array(goals).reshape(-1, 3),
            {k: v for k, v in dropped.items() if v})


def _connected(worlds: dict, starts: np.ndarray, goals: np.ndarray, neighbors: str) -> np.ndarray:
    """(Q,) bool: lattice A* (``neighbors`` moves) connects start i and goal i (points, m,
    free in every world) in at least one of ``worlds``. A search that stops at its budget
    counts as connected (not proved otherwise)."""
    from planner.search import search_many  # lazy: numba

    linked = np.zeros(len(starts), dtype=bool)
    for w in worlds.values():
        todo = np.flatnonzero(~linked)
        if not len(todo):
            break
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
