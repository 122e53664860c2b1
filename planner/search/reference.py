"""networkx reference backend: the explicit free-cell graph of the start's component, then
``networkx.astar_path``. Readable and slow; for cross-checking the numba kernel."""

from __future__ import annotations

import itertools
import math
import time

import numpy as np

from planner.errors import PlanError
from planner.search.heuristic import estimate_np
from planner.search.result import SearchResult

NX_NODE_CAP = 1_000_000


def search_networkx(world, s: np.ndarray, gl: np.ndarray, ms, cap: int | None = None):
    """A* (or Dijkstra when ``ms.hkind`` is 0) from cell ``s`` to ``gl`` ((3,) int64) over
    the graph of allowed moves of :class:`~planner.search.moves.MoveSet` ``ms``, built by
    BFS over the start's free component (at most ``cap`` cells, default 1,000,000)."""
    import networkx as nx

    cap = cap or NX_NODE_CAP
    t0 = time.perf_counter()
    before = world.cell_checks
    graph = nx.Graph()
    start, goal = tuple(s.tolist()), tuple(gl.tolist())
    graph.add_node(start)
    seen = {start}
    queue = [start]
    needs = [ms.idx[ms.ptr[m]:ms.ptr[m + 1]] for m in range(len(ms.moves))]
    moves_l = ms.moves.tolist()
    while queue:
        if len(seen) > cap:
            raise PlanError(f"networkx backend: the start's component exceeds {cap} cells; "
                            "use backend='numba'")
        u = queue.pop()
        free = world.is_free(np.asarray(u) + ms.union)
        for m, d in enumerate(moves_l):
            if not free[needs[m]].all():
                continue
            v = (u[0] + d[0], u[1] + d[1], u[2] + d[2])
            graph.add_edge(u, v, weight=float(ms.cost[m]))
            if v not in seen:
                seen.add(v)
                queue.append(v)
    checks = world.cell_checks - before + 2

    gen = world.lattice.generator

    def h(a, b):
        return float(estimate_np(ms, gen, np.subtract(b, a)))

    n = graph.number_of_nodes()
    if goal not in graph:
        return SearchResult(found=False, cells=np.zeros((0, 3), np.int64), cost=math.inf,
                            cell_checks=checks, expansions=0, generated=n,
                            seconds=time.perf_counter() - t0, peak_bytes=0,
                            reason=f"goal unreachable: explored {n} cells",
                            status="unreachable")
    path = nx.astar_path(graph, start, goal, heuristic=h, weight="weight")
    cost = float(sum(graph[a][b]["weight"] for a, b in itertools.pairwise(path)))
    return SearchResult(found=True, cells=np.array(path, dtype=np.int64).reshape(-1, 3),
                        cost=cost, cell_checks=checks, expansions=0, generated=n,
                        seconds=time.perf_counter() - t0, peak_bytes=0)
