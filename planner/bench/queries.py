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
    free : callable, optional
        ``free(points (N, 3)) -> (N,) bool`` in the map's own frame: observed free space.
        When given, a start or goal outside it is dropped ("in unknown space"): a map with
        free-space information is queried only where it was observed.

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
        s = rng.uniform(lo, hi, (batch, 3))
        g = rng.uniform(lo, hi, (batch, 3))
        ok = np.ones(batch, dtype=bool)
        short = np.linalg.norm(g - s, axis=1) < min_distance * diag
        dropped["start and goal too close"] += int(np.sum(short & ok))
        ok &= ~short
        if free is not None:
            for what, pts in (("start", s), ("goal", g)):
                seen = free(pts)
                dropped[f"{what} in unknown space"] += int(np.sum(ok & ~seen))
                ok &= seen
        for what, pts in (("start", s), ("goal", g)):
            # Per lattice, so that a point inside a wall (blocked everywhere) is not charged
            # to whichever lattice happens to be checked first.
            valid = {name: w.points_free(pts) for name, w in worlds.items()}
            every = np.logical_and.reduce([~v for v in valid.values()])
            dropped[f"{what} blocked in every lattice"] += int(np.sum(ok & every))
            for name, v in valid.items():
                key = f"{what} blocked in {name}, free in another lattice"
                dropped[key] += int(np.sum(ok & ~v & ~every))
            ok &= np.logical_and.reduce(list(valid.values()))
        for i in np.flatnonzero(ok):
            if len(starts) < n:
                starts.append(s[i])
                goals.append(g[i])
    return (np.array(starts).reshape(-1, 3), np.array(goals).reshape(-1, 3),
            {k: v for k, v in dropped.items() if v})


def scenario_queries(path: str, n: int, seed: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``n`` queries of a MovingAI ``.3dscen`` file (evenly spread over its buckets).

    Returns starts, goals (n, 3) as float points and the listed optimal costs (n,).
    """
    from planner.io import load_scenarios

    sc = load_scenarios(path)
    starts, goals, costs = sc.starts, sc.goals, sc.costs
    k = len(costs)
    idx = np.unique(np.linspace(0, k - 1, min(n, k)).round().astype(int))
    return starts[idx].astype(float), goals[idx].astype(float), costs[idx]
