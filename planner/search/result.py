"""The outcome of one search (every engine: A*, Dijkstra, Theta*, Lazy Theta*, D* Lite), the
one list of its statuses, and the engines' kernel return codes with the status each maps to.

Kernel codes (``RUN_*``) are what the compiled searches return; :data:`STATUS_OF_RUN` names
the :attr:`SearchResult.status` of each final one. ``RUN_GROW`` is never final: the driver
makes room and calls the kernel again; nor are ``RUN_BAD_START`` / ``RUN_BAD_GOAL`` (an end
cell is not free): :func:`planner.search.search` raises the endpoint's PlanError.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

__all__ = ["STATUSES", "STATUS_OF_RUN", "SearchResult", "found_result", "RUN_EXHAUSTED",
           "RUN_FOUND", "RUN_LIMIT", "RUN_GROW", "RUN_BUDGET", "RUN_STOPPED", "RUN_BLOCKED",
           "RUN_BAD_START", "RUN_BAD_GOAL"]

STATUSES = ("found", "unreachable", "budget", "blocked")  # described on SearchResult.status

RUN_EXHAUSTED = 0  # the open list ran empty (D* Lite: no path from the start)
RUN_FOUND = 1  # a path was found (D* Lite's ComputeShortestPath: settled)
RUN_LIMIT = 2  # the node limit was reached
RUN_GROW = 3  # the kernel needs bigger arrays; call again after growing them
RUN_BUDGET = 4  # the expansion budget was spent
RUN_STOPPED = 5  # stopped at a pause: the goal is sealed in a small pocket (A* driver)
RUN_BLOCKED = 6  # D* Lite: the start's own cell is blocked
RUN_BAD_START = 7  # A*: the start cell is not free (never final: the caller raises)
RUN_BAD_GOAL = 8  # A*: the goal cell is not free (never final: the caller raises)

#: the :attr:`SearchResult.status` of each final kernel code
STATUS_OF_RUN = {RUN_EXHAUSTED: "unreachable", RUN_FOUND: "found", RUN_LIMIT: "budget",
                 RUN_BUDGET: "budget", RUN_STOPPED: "unreachable", RUN_BLOCKED: "blocked"}


@dataclass(slots=True, kw_only=True)
class SearchResult:
    """Outcome of one search (built by keyword: thirteen fields read better by name).

    Attributes
    ----------
    found : bool
    cells : ndarray, shape (K, 3), int64
        Path cells from start to goal (any-angle methods: only the turning cells).
        Empty when not found.
    cost : float
        Path length between cell centres (m); ``inf`` when not found.
    cell_checks : int
        Occupancy lookups made by this search (each actual lookup counted once).
    expansions : int
        Nodes removed from the open list (the goal included).
    generated : int
        Distinct nodes created (start included).
    seconds : float
        Wall time of the search (numba backend: the kernel calls; networkx: build + search).
    peak_bytes : int
        Peak size of the search's own arrays (node table, heap, slot map, scratch), as
        grown for this search alone (the same whatever ran before it).
    reason : str
        Why no path was found ("" when found).
    status : str
        One of :data:`STATUSES`: ``"found"``; ``"unreachable"`` (the start's free component
        is exhausted: no path exists); ``"budget"`` (stopped by ``max_expansions`` /
        ``max_nodes``); ``"blocked"`` (D* Lite only: the robot's own cell became blocked by
        an update, so no path starts there).
    guarantee : bool
        Whether the path carries the radius guarantee
        (:func:`planner.search.moves.carries_guarantee`).
    compile_seconds : float
        Time spent compiling or loading the search kernels before this search (its first
        in the process; 0 after), never part of ``seconds`` (:func:`warm_up`).
    """

    found: bool
    cells: np.ndarray
    cost: float
    cell_checks: int
    expansions: int
    generated: int
    seconds: float
    peak_bytes: int
    reason: str = ""
    extra: dict = field(default_factory=dict)
    status: str = "found"
    guarantee: bool = True
    compile_seconds: float = 0.0

    def __repr__(self) -> str:
        # short: a path's cells can be millions of rows
        return (f"SearchResult(status={self.status!r}, cost={self.cost:.6g}, "
                f"cells={len(self.cells)}, expansions={self.expansions}, "
                f"seconds={self.seconds:.3g})")


_new = object.__new__


def found_result(*, cells: np.ndarray, cost: float, cell_checks: int, expansions: int,
                 generated: int, seconds: float, peak_bytes: int, guarantee: bool,
                 compile_seconds: float = 0.0) -> SearchResult:
    """``SearchResult(found=True, ...)`` (reason "", status "found", no extra) for a
    search's fast path. Calling a class with keywords makes CPython pack them into a dict
    for ``__init__``, which showed in ``search()``'s fixed cost
    (``benchmarks/fixed_cost.py``); this keyword-only function fills the slots itself
    (``tests/test_search.py`` checks it sets every field as the class does)."""
    r = _new(SearchResult)
    r.found, r.cells, r.cost, r.cell_checks = True, cells, cost, cell_checks
    r.expansions, r.generated, r.seconds, r.peak_bytes = expansions, generated, seconds, peak_bytes
    r.reason, r.extra, r.status = "", {}, "found"
    r.guarantee, r.compile_seconds = guarantee, compile_seconds
    return r
