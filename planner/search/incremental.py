"""Incremental replanning: D* Lite over the lattice graph, for a robot that moves and senses.

The graph, safe rule, edge costs (m) and heuristic are those of
``planner.search.search(..., method="astar")`` (:mod:`planner.search.stencils`); the search
runs from the goal towards the start, so the start may move (:meth:`DStarLite.move_start`)
and changed cells (:meth:`DStarLite.update`, after the world was mutated, e.g. with
:meth:`planner.world.World.set_cells`) repair only the vertices whose edges they touch.
Kernels and data layout: :mod:`planner.search._dstar`.

Cell checks count every occupancy lookup actually made, as A* does: a node's edges cost one
lookup of its own cell plus one per union-stencil offset (A* skips the own cell, which it
reached through a checked move), looked up once and redone only for nodes whose stencil
holds a changed cell.

Examples
--------
>>> from planner.lattice import Lattice
>>> from planner.world import World
>>> w = World(Lattice.named("cubic", 1.0), [], [[0, 0, 0], [4, 4, 4]])
>>> d = DStarLite(w, [0, 0, 0], [4, 4, 4])
>>> round(d.plan().cost, 4)
6.9282
>>> d.update(w.set_cells([[2, 2, 2]], blocked=True))
>>> round(d.plan().cost, 4)
8.2925
"""

from __future__ import annotations

import math
import time

import numpy as np

from planner.errors import PlanError
from planner.keys import unpack
from planner.search import SearchResult
from planner.search import _dstar as dk
from planner.search._heap import Heap, new_heap
from planner.search.stencils import H_GAUGE, carries_guarantee, move_set
from planner.world import World, _cells

__all__ = ["DStarLite"]

_MAX_MOVES = 63  # edge masks are int64 bit sets


class DStarLite:
    """D* Lite between a (moving) start cell and a goal cell of a world.

    Parameters
    ----------
    world : World
        Dense occupancy storage (the node map spans its index box). Mutate it in place
        (:meth:`World.set_cells`) and pass the changed cells to :meth:`update`.
    start, goal : array_like of int, shape (3,)
        Lattice indices, free when the planner is made (PlanError otherwise, as A*).
    neighbors : str
        ``lattice.neighbors`` kind (at most 63 moves).
    corner_cutting : bool
        As :func:`planner.search.search`.

    Attributes
    ----------
    start, goal : ndarray (3,) int64
    """

    def __init__(self, world: World, start, goal, neighbors: str = "full",
                 corner_cutting: bool = False):
        if not isinstance(world, World):
            raise PlanError(f"world must be a World, got {type(world).__name__}")
        self.world = world
        self.start = world.endpoint_cell(start, "start").copy()
        self.goal = world.endpoint_cell(goal, "goal").copy()
        lat = world.lattice
        self._ms = move_set(lat, neighbors, corner_cutting, H_GAUGE)
        nm = len(self._ms.moves)
        if nm > _MAX_MOVES:
            raise PlanError(f"D* Lite supports at most {_MAX_MOVES} moves, {neighbors!r} "
                            f"has {nm}")
        self.guarantee = carries_guarantee(lat, neighbors, corner_cutting)
        # affect[j]: the moves whose safe-rule cells include union offset j
        self._affect = np.zeros(len(self._ms.union), np.int64)
        for m in range(nm):
            for e in self._ms.idx[self._ms.ptr[m]:self._ms.ptr[m + 1]]:
                self._affect[e] |= np.int64(1) << np.int64(m)
        occ = world.occupancy
        if occ.mode != 0:
            raise PlanError("D* Lite needs dense occupancy storage (a smaller world)")
        self._bx = dk.DBox(np.full(int(np.prod(occ.dims)), -1, np.int32), occ.lo.copy(),
                           occ.dims.copy())
        self._nd = dk.new_nodes(4096)
        self._heap = new_heap(4096)
        self._ufree = np.empty(len(self._ms.union), np.bool_)
        self._st = np.zeros(dk.S_SIZE, np.int64)
        self._km = 0.0
        self._last = self.start.copy()
        g = dk.node(self._bx, self._nd, self._st, *(int(x) for x in self.goal), True)
        self._st[dk.S_GOAL] = g
        self._nd.rhs[g] = 0.0
        dk.update_vertex(self._ms, self._nd, self._heap, self._st, self._km, self.start, g)
        self._mark = (0, 0)  # lookups, expansions at the last plan
        self._seconds = 0.0  # kernel time since the last plan
        self._scr: dict[str, np.ndarray] = {}  # scratch kept between repairs

    # -- storage -----------------------------------------------------------------------
    def _room(self, extra: int) -> None:
        n = int(self._st[dk.S_N])
        cap = len(self._nd.key)
        if n + extra <= cap:
            return
        while cap < n + extra:
            cap *= 2
        self._nd = dk.DNodes(*(_grown(a, cap, n) for a in self._nd))
        self._heap = Heap(*(_grown(a, cap, int(self._st[dk.S_HN])) for a in self._heap))

    def _scratch(self, name: str, size: int, dtype) -> np.ndarray:
        """A scratch array of at least ``size`` items, reused between calls (a replan
        should not pay for allocating buffers sized to the whole node table)."""
        a = self._scr.get(name)
        if a is None or len(a) < size:
            a = np.empty(max(size, 2 * len(a) if a is not None else 1024), dtype)
            self._scr[name] = a
        return a

    @property
    def nodes(self) -> int:
        """Nodes created so far."""
        return int(self._st[dk.S_N])

    @property
    def peak_bytes(self) -> int:
        """Bytes of the planner's own arrays."""
        return sum(a.nbytes for part in (self._nd, self._heap, self._bx) for a in part)

    # -- the three operations ------------------------------------------------------------
    def move_start(self, cell) -> None:
        """The robot moved to ``cell`` ((3,) int): keys stay valid through ``km``."""
        c = _cells(cell)[0]
        self._km += float(_gauge(self._ms.hmat, c - self._last))
        self._last = c.copy()
        self.start = c.copy()

    def update(self, changed_cells, blocked: bool | None = None) -> None:
        """Repair after the cells ``changed_cells`` ((K, 3) int) flipped between free and
        blocked in the world (already mutated).

        ``blocked`` says what they all became (as :meth:`World.set_cells` was told);
        None looks each one up (K cell checks). Nodes whose edge stencil holds a newly
        blocked cell drop the moves it serves without a lookup; nodes near a newly freed
        cell look their stencil up again; edges that flipped repair their end nodes.
        """
        c = _cells(changed_cells) if len(changed_cells) else np.zeros((0, 3), np.int64)
        if not len(c):
            return
        t0 = time.perf_counter()
        if blocked is None:
            state = ~self.world.checker.cells_free(c)
            self._st[dk.S_LOOK] += len(c)
        else:
            state = self._scratch("state", len(c), np.bool_)
            state[:len(c)] = bool(blocked)
        size = len(c) * (len(self._ms.union) + 1)
        ss = self._scratch("ss", size, np.int64)
        old = self._scratch("old", size, np.int64)
        redo = self._scratch("redo", size, np.bool_)
        n = dk.collect(self._ms, self._affect, self._bx, self._nd, self._st, c, state, ss,
                       old, redo)
        nm = len(self._ms.moves)
        self._room(n * nm + 1)
        dk.apply_changes(self.world.occupancy, self._ms, self._ufree, self._bx, self._nd,
                         self._heap, self._st, self._km, self.start, ss, old, redo, n,
                         self._scratch("touched", 2 * n * nm + 1, np.int64))
        self._seconds += time.perf_counter() - t0

    def plan(self) -> SearchResult:
        """Shortest path from the current start to the goal on the world as it is now.

        Returns
        -------
        SearchResult
            ``cell_checks``, ``expansions`` and ``seconds`` cover the work since the
            previous :meth:`plan` (the updates included); ``generated`` counts every node
            ever created.
        """
        t0 = time.perf_counter()
        occ = self.world.occupancy
        st = self._st
        first = True  # the start's own cell is looked up once, as A*'s endpoint check
        while True:
            self._room(len(self._ms.moves) + 1)
            done = dk.compute_path(occ, self._ms, self._ufree, self._bx, self._nd,
                                   self._heap, st, self._km, self.start, first)
            if done == dk.BLOCKED:
                return self._result(None, math.inf, t0, "start cell is blocked", "blocked")
            if done == dk.DONE:
                break
            first = False
        out = self._scratch("path", self.nodes + 1, np.int64)
        k, cost = dk.extract(occ, self._ms, self._ufree, self._bx, self._nd, st, self.start,
                             out)
        if k == 0:
            return self._result(None, math.inf, t0,
                                f"goal unreachable: explored {self.nodes} cells",
                                "unreachable")
        return self._result(unpack(out[:k], 3), float(cost), t0, "", "found")

    def _result(self, cells, cost, t0, why, status) -> SearchResult:
        look, exp = int(self._st[dk.S_LOOK]), int(self._st[dk.S_EXP])
        checks, expansions = look - self._mark[0], exp - self._mark[1]
        self._mark = (look, exp)
        self.world.cell_checks += checks
        secs = self._seconds + time.perf_counter() - t0
        self._seconds = 0.0
        found = cells is not None
        return SearchResult(found, cells if found else np.zeros((0, 3), np.int64), cost,
                            checks, expansions, self.nodes, secs, self.peak_bytes, why,
                            status=status, guarantee=self.guarantee)


def _gauge(hmat: np.ndarray, e: np.ndarray) -> float:
    return max(0.0, float((hmat @ e.astype(float)).max()))


def _grown(a: np.ndarray, size: int, keep: int) -> np.ndarray:
    b = np.empty(size, a.dtype)
    b[:keep] = a[:keep]
    return b
