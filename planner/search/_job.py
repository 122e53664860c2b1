"""A search's settings: the method, move set and budgets :func:`planner.search.search` and
:func:`planner.search.search_many` derive from their arguments, checked once per distinct
arguments (:func:`prepare`), not on every call."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from planner import budget as _budget
from planner.errors import PlanError
from planner.search._nodes import BYTES_PER_NODE
from planner.search.astar.kernel import LAZY_THETA, THETA, SearchParams
from planner.search.heuristic import H_EUCLID, H_GAUGE, H_ZERO
from planner.search.moves import MoveSet, carries_guarantee, move_set
from planner.world.world import World

__all__ = ["H_WEIGHT", "METHODS", "MEMORY_SHARE", "Job", "default_max_expansions",
           "default_memory_budget", "limit", "prepare"]

METHODS = ("astar", "dijkstra", "theta", "lazy-theta", "weighted-theta")
_ANYANGLE = {"astar": 0, "dijkstra": 0, "theta": THETA, "lazy-theta": LAZY_THETA,
             "weighted-theta": LAZY_THETA}
_HKIND = {"astar": H_GAUGE, "dijkstra": H_ZERO, "theta": H_EUCLID, "lazy-theta": H_EUCLID,
          "weighted-theta": H_EUCLID}
H_WEIGHT = 1.03  # weighted-theta's factor: dives like A*, lengths near Lazy Theta*'s
_WEIGHT = {"weighted-theta": H_WEIGHT}
MEMORY_SHARE = _budget.MEMORY_SHARE  # of physical memory, the default memory budget


def default_memory_budget() -> int:
    """Bytes a search may use by default: the one memory budget of :mod:`planner.budget`
    (``PLANNER_MEMORY_BUDGET`` / ``--memory-budget``, else an eighth of the physical
    memory)."""
    return _budget.memory_budget()


def default_max_expansions(memory_budget: int | None = None) -> int:
    """Expansions allowed within ``memory_budget`` bytes (default
    :func:`default_memory_budget`): the node budget ``budget // BYTES_PER_NODE``."""
    b = default_memory_budget() if memory_budget is None else int(memory_budget)
    return max(1, b // BYTES_PER_NODE)


def limit(value, name: str) -> int:
    """``value`` as a positive int below 2**63 (0 for None); PlanError naming ``name``."""
    if value is None:
        return 0
    if (isinstance(value, bool) or not isinstance(value, int | np.integer) or value <= 0
            or value >= 2**63):
        raise PlanError(f"{name} must be a positive integer below 2**63, got {value!r}")
    return int(value)


class Job(NamedTuple):
    """What one call of ``search`` or ``search_many`` passes each of its kernel searches."""

    ms: MoveSet
    params: SearchParams
    max_nodes: int  # the caller's node limit (0 none), for the result's reason
    guarantee: bool


_JOBS: dict[tuple, tuple] = {}  # the arguments of a call -> (lattice, its Job)
_LAST: list = [None]  # (lattice, the arguments, env token, Job) of the last call


def prepare(world: World, method: str, neighbors: str, corner_cutting: bool, max_nodes,
            max_expansions, memory_budget, workers: int) -> Job:
    """Check the arguments shared by ``search`` and ``search_many`` and derive the
    move set and kernel settings; ``workers`` concurrent searches share the memory budget.
    Remembered per lattice and arguments (and the budget's environment variable): a
    search's arguments are checked once, not on every call. The last call's are compared
    by identity first (a query loop passes the same objects), which costs less than
    hashing them."""
    lat = world.lattice
    env = _budget.env_token()
    last = _LAST[0]
    if (last is not None and last[0] is lat and last[1] is method and last[2] is neighbors
            and last[3] is corner_cutting and last[4] is max_nodes
            and last[5] is max_expansions and last[6] is memory_budget and last[7] == workers
            and last[8] is env):
        return last[9]
    key = (id(lat), method, neighbors, corner_cutting, type(max_nodes), max_nodes,
           type(max_expansions), max_expansions, type(memory_budget), memory_budget, workers,
           env)
    try:
        hit = _JOBS.get(key)
    except TypeError:  # an unhashable argument: checked (and refused) below
        hit = key = None
    if hit is not None and hit[0] is lat:
        job = hit[1]
    else:
        if method not in METHODS:
            raise PlanError(f"unknown method {method!r}; expected one of {', '.join(METHODS)}")
        nodes = limit(max_nodes, "max_nodes")
        budget = limit(memory_budget, "memory_budget") or default_memory_budget()
        budget_nodes = default_max_expansions(max(1, budget // workers))
        max_exp = limit(max_expansions, "max_expansions") or budget_nodes
        ms = move_set(lat, neighbors, corner_cutting, _HKIND[method])
        node_cap = min(nodes, budget_nodes) if nodes else budget_nodes
        params = SearchParams(_ANYANGLE[method], node_cap, max_exp, _WEIGHT.get(method, 1.0))
        job = Job(ms, params, nodes, carries_guarantee(lat, neighbors, corner_cutting))
        if key is not None:
            if len(_JOBS) >= 256:
                _JOBS.clear()
            _JOBS[key] = (lat, job)
    _LAST[0] = (lat, method, neighbors, corner_cutting, max_nodes, max_expansions,
                memory_budget, workers, env, job)
    return job
