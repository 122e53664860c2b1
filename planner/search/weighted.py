"""Weighted Lazy Theta* (``method="weighted-theta"``): any-angle paths at about A*'s cost.

Lazy Theta* with the Euclidean heuristic expands every cell whose g plus straight-line
distance to the goal is below the path length: a thin tube along the whole path, much more
than lattice A* (whose move-set gauge is flat along the many equal-cost lattice paths, so it
dives) expands. Weighting the heuristic, ``f = g + w |x - goal|`` with ``w`` =
:data:`WEIGHT` slightly above 1, makes deeper nodes win every near-tie, so the search dives
too; everything else is ``method="lazy-theta"``: the same move set and movement rule, the
same lazy parent rule (a parent assumed in sight, verified on expansion, else the best
closed lattice neighbour) and the same exact line of sight (:mod:`planner.search._los`).
The lookups of both (the expanded cells' move cells and every sight line's cells) are
counted in ``cell_checks``.

Guarantee: a valid path from start to goal under the same rule as Theta* and Lazy Theta*
(every segment between consecutive returned cells is a line of sight, or an allowed lattice
move), with the radius guarantee whenever the move set carries it. Its length is *not*
Lazy Theta*'s, and it is not bounded by the lattice A* path's either: an inflated heuristic
gives up the search order's optimality, and no bound on the difference is proven (weighted
A*'s factor ``w`` bound does not carry over to Lazy Theta*'s parent rule).
``benchmarks/search_speed.py --anyangle`` measures the length ratio to Lazy Theta* and the
time ratio to A* on real maps.

Unreachable goals: unlike the A* driver, no probe from the goal stops the search early when
the goal is sealed in a small pocket; the search then ends when the start's component (or
the budget) is exhausted.
"""

from __future__ import annotations

import math
import time

import numpy as np

from planner.search._entry import entry_point, struct_key
from planner.search._los import new_scratch
from planner.search._weighted_kernel import (
    W_BUDGET,
    W_EXHAUSTED,
    W_FOUND,
    W_LIMIT,
    weighted_run,
)
from planner.search.moves import MoveSet
from planner.search.result import SearchResult
from planner.world.world import World

__all__ = ["WEIGHT", "weighted_search"]

#: heuristic weight of ``method="weighted-theta"``
WEIGHT = 1.03
_STATUS = {W_FOUND: "found", W_EXHAUSTED: "unreachable", W_LIMIT: "budget",
           W_BUDGET: "budget"}
_KERNELS: dict[tuple, object] = {}


def _kernel(occ, walk, ms, *args) -> tuple[object, float]:
    """The compiled kernel for these structs' types (called without per-call argument
    typing) and the seconds spent compiling or loading it (0 once done)."""
    k = (struct_key(occ), struct_key(walk), struct_key(ms))
    fn = _KERNELS.get(k)
    if fn is not None:
        return fn, 0.0
    t0 = time.perf_counter()
    fn = _KERNELS[k] = entry_point(weighted_run, (occ, walk, ms, *args))
    return fn, time.perf_counter() - t0


def weighted_search(world: World, start: np.ndarray, goal: np.ndarray, ms: MoveSet,
                    span: float, max_nodes: int, max_expansions: int, node_limit: int = 0,
                    weight: float = WEIGHT) -> tuple[SearchResult, int]:
    """One weighted Lazy Theta* search between two free cells.

    Parameters
    ----------
    world : World
    start, goal : ndarray, shape (3,), int64
        Free lattice cells (checked by the caller).
    ms : MoveSet
        The move set and rule (:func:`planner.search.moves.move_set`).
    span : float
        Longest sight line (m) the walk scratch is sized for (longer ones use fresh
        arrays).
    max_nodes, max_expansions : int
        Limits (<= 0: none); ``node_limit`` is the caller's own node limit (0: none), named
        in the result's reason.
    weight : float
        Heuristic weight (>= 1).

    Returns
    -------
    result : SearchResult
    lookups : int
        Occupancy lookups, for the caller to add to ``world.cell_checks`` (threads never
        write to the world).
    """
    chk = world.checker
    sc = new_scratch(span, chk.walk)
    s = np.ascontiguousarray(start, np.int64)
    g = np.ascontiguousarray(goal, np.int64)
    args = (s, g, float(weight), sc, 4096, int(max_nodes), int(max_expansions))
    fn, compile_s = _kernel(chk.occupancy, chk.walk, ms, *args)
    t0 = time.perf_counter()
    status, cells, cost, exp, gen, look, peak = fn(chk.occupancy, chk.walk, ms, *args)
    secs = time.perf_counter() - t0
    checks = int(look) + 2  # and the two endpoint checks
    peak = int(peak) + sum(a.nbytes for a in sc)
    exp, gen = int(exp), int(gen)
    if status == W_FOUND:
        return SearchResult(True, cells, float(cost), checks, exp, gen, secs, peak,
                            extra={"weight": float(weight)},
                            compile_seconds=compile_s), int(look)
    if status == W_EXHAUSTED:
        why = f"goal unreachable: explored {gen} cells"
    elif status == W_LIMIT and node_limit and gen >= node_limit:
        why = f"node limit {node_limit} reached after {exp} expansions"
    else:
        why = f"search budget exhausted after {exp} expansions ({peak} bytes)"
    return SearchResult(False, np.zeros((0, 3), np.int64), math.inf, checks, exp, gen, secs,
                        peak, why, status=_STATUS[status],
                        compile_seconds=compile_s), int(look)
