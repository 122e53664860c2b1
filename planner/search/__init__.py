"""Graph search over lattice cells: A*, Dijkstra, Theta*, Lazy Theta*, D* Lite, shortcutting.

:func:`search` / :func:`search_many` (:mod:`~planner.search.run`), :class:`SearchResult` and
its statuses (:mod:`~planner.search.result`), the move sets and the heuristic
(:mod:`~planner.search.moves`), shortcutting a cell path (:mod:`~planner.search.smoothing`),
the A* family's kernel (:mod:`~planner.search.astar`), D* Lite
(:mod:`~planner.search.dstar`, :class:`DStarLite`), replanning by A* when a change touches
the path (:mod:`~planner.search.replanner`, :class:`AStarReplanner`), the heap
(:mod:`~planner.search._heap`), line of sight (:mod:`~planner.search._los`;
:func:`sight_many` for batches of segments, :mod:`~planner.search.sight`) and the networkx
reference (:mod:`~planner.search.reference`).
"""

from planner.search.dstar.lite import DStarLite
from planner.search.moves import carries_guarantee, move_heuristic, move_stencils
from planner.search.replanner import AStarReplanner
from planner.search.result import STATUSES, SearchResult
from planner.search.run import (
    METHODS,
    default_max_expansions,
    default_memory_budget,
    search,
    search_many,
    warm_up,
)
from planner.search.sight import Sight, sight_many
from planner.search.smoothing import shortcut

__all__ = ["AStarReplanner", "DStarLite", "METHODS", "STATUSES", "SearchResult", "Sight",
           "carries_guarantee", "default_max_expansions", "default_memory_budget",
           "move_heuristic", "move_stencils", "search", "search_many", "shortcut", "sight_many",
           "warm_up"]
