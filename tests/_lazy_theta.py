"""Lazy Theta* in plain Python with an exact f order: the oracle for the compiled loop's
f grid (tests/test_anyangle.py). Slow and readable; small worlds only."""

from __future__ import annotations

import heapq

import numpy as np

from planner.search.heuristic import H_EUCLID
from planner.search.moves import move_set


def lazy_theta(world, start: np.ndarray, goal: np.ndarray, grid: bool = False) -> float:
    """Length (m) of Lazy Theta*'s path from cell ``start`` to ``goal`` ((3,) int64) over
    the full move set under the safe rule, its open list in exact f order with the larger
    g first among ties; ``inf`` when none exists. Sight lines are the world's exact
    segment test between cell centres (:meth:`planner.world.World.segment_free`).

    ``grid``: file each node as the compiled loop does instead, under f less the end
    allowance on the f grid through the start's f (planner.search.astar.loop)."""
    from planner.search.astar.loop import END_SLACK, F_STEP, F_STEP_ANY_ANGLE

    lat = world.lattice
    moves = move_set(lat, "full", False, H_EUCLID)
    needs = [moves.union[moves.idx[moves.ptr[m]:moves.ptr[m + 1]]] for m in range(len(moves.moves))]

    def centre(cell):
        return lat.to_world(np.array(cell))

    def allowed(cell):
        """(move's target, its length) for every move the safe rule allows from ``cell``."""
        for m, need in enumerate(needs):
            if world.is_free(np.asarray(cell) + need).all():
                yield tuple(int(x) for x in np.asarray(cell) + moves.moves[m]), moves.cost[m]

    target = tuple(int(x) for x in goal)
    goal_point = centre(target)
    first = tuple(int(x) for x in start)
    shortest = float(moves.cost.min())
    f_start = float(np.linalg.norm(goal_point - centre(first)))
    step = max(F_STEP * shortest, F_STEP_ANY_ANGLE * f_start)
    origin = f_start + (0.5 - 1e-6) * step

    def key(g, h, a):
        if not grid:
            return g + h
        f = g + h - END_SLACK * shortest**2 / max(min(a, h), shortest)
        return origin + np.floor((f - origin) * (1.0 / step) + 0.5) * step

    cost, parent, closed = {first: 0.0}, {first: first}, set()
    heap = [(f_start, -0.0, first)]
    while heap:
        _, minus_g, cell = heapq.heappop(heap)
        if cell in closed or -minus_g != cost[cell]:
            continue  # a stale entry
        up = parent[cell]
        if up != cell and not world.segment_free(centre(up), centre(cell)):
            # SetVertex: the best closed neighbour an allowed move reaches
            best = min((cost[v] + c, v) for v, c in allowed(cell) if v in closed)
            cost[cell], parent[cell] = best
            up = parent[cell]
        if cell == target:
            return cost[cell]
        closed.add(cell)
        for v, _ in allowed(cell):
            if v in closed:
                continue
            a = float(np.linalg.norm(centre(v) - centre(up)))
            g = cost[up] + a
            if g < cost.get(v, np.inf):
                cost[v], parent[v] = g, up
                h = float(np.linalg.norm(goal_point - centre(v)))
                heapq.heappush(heap, (key(g, h, a), -g, v))
    return float("inf")
