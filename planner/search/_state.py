"""The engines' typed kernel state: one numpy record every search kernel reads and writes.

A* / Dijkstra / Theta* / Lazy Theta* (:mod:`planner.search.astar`) and D* Lite
(:mod:`planner.search.dstar`) keep their counters in a record whose first fields are
:data:`COMMON` (same names, same meaning in both); each engine appends the few fields only it
has (:func:`state_dtype`). Kernels take the record (``st.nodes += 1``); Python reads it as a
(1,) structured array (``int(state["expansions"][0])``), so a compiled call passes one
array instead of a list of counters, and adding a field never renumbers another.

Fields of :data:`COMMON` (all int64):

- ``nodes``: nodes created (node table rows in use);
- ``queued``: entries in the heap (:mod:`planner.search._heap`);
- ``expansions``: nodes removed from the heap and expanded;
- ``lookups``: occupancy lookups made (:attr:`planner.search.SearchResult.cell_checks`);
- ``goal``: node slot of the goal (A*: once reached; D* Lite: its search's root);
- ``stamp``: generation counter stamping per-query scratch (A*: line-of-sight walks;
  D* Lite: update batches), so scratch is never cleared between uses;
- ``status``: the last ``RUN_*`` code (:mod:`planner.search.result`) a kernel returned.
"""

from __future__ import annotations

import numpy as np

__all__ = ["COMMON", "state_dtype", "new_state"]

COMMON = ("nodes", "queued", "expansions", "lookups", "goal", "stamp", "status")


def state_dtype(*extra: str) -> np.dtype:
    """Record dtype of :data:`COMMON` followed by the engine's own ``extra`` int64 fields."""
    return np.dtype([(name, np.int64) for name in (*COMMON, *extra)])


def new_state(dtype: np.dtype) -> np.ndarray:
    """A zeroed (1,) state array of ``dtype`` (a :func:`state_dtype`)."""
    return np.zeros(1, dtype)
