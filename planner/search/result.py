"""The outcome of one search (every engine: A*, Dijkstra, Theta*, Lazy Theta*, D* Lite) and
the one list of its statuses."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

__all__ = ["STATUSES", "SearchResult"]

STATUSES = ("found", "unreachable", "budget", "blocked")  # described on SearchResult.status


@dataclass
class SearchResult:
    """Outcome of one search.

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
        Peak size of the search's own arrays (node table, heap, slot map, scratch).
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
