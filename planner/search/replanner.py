"""Replanning by A* when, and only when, the changes touch the rest of the path.

A robot that senses while it walks blocks cells after every scan. When a scan only *blocks*
cells (costs only rise) and none of them is a cell the rest of the current path rests on
(its cells from the robot's on, and the safe-rule cells of its moves: a move exists while
they are all free, :mod:`planner.search.moves`), that rest costs what it did and every
other path costs at least what it did: it is still a shortest path and no search is
needed. Otherwise :class:`AStarReplanner` searches again with A* from the robot's cell
(:func:`planner.search.search`, whose kernel arrays and node table are kept between
searches, :mod:`planner.search.astar.driver`).

The check is compiled and reads the bit maps of :mod:`planner.search.dstar.rest` (the
kept D* Lite replan's: a bit per cell of the world's index box, and a bit per 4x4x4
block of it, read first). They mark the whole path as planned; a cell whose bit is set is
then looked up in the path's *rest index*: the sorted keys ``box index * K + i`` of every
cell the path's step ``i`` rests on (cell ``i`` and move ``i``'s safe-rule cells, K the
path length), so that a cell only the walked part rests on (behind the robot) does not
force a search.

Against :class:`planner.search.dstar.lite.DStarLite` (same interface, available by
name): D* Lite's first plan searches backwards from the goal and floods what A* would not
expand, and a repair that changes the path reads its cached nodes near every changed cell;
on the bundled office and geb079 explorations both cost more over a run than this
(``benchmarks/explore_speed.py``).

Examples
--------
>>> from planner.lattice import Lattice
>>> from planner.world import World
>>> w = World(Lattice.named("cubic", 1.0), [], [[0, 0, 0], [4, 4, 4]])
>>> p = AStarReplanner(w, [0, 0, 0], [4, 4, 4])
>>> round(p.plan().cost, 4)
6.9282
>>> p.update(w.set_cells([[0, 4, 4]], blocked=True))  # off the path: kept, no search
>>> r = p.plan()
>>> round(r.cost, 4), r.expansions, p.searches
(6.9282, 0, 1)
>>> p.update(w.set_cells([[2, 2, 2]], blocked=True))  # on it: A* again
>>> round(p.plan().cost, 4), p.searches
(8.2925, 2)
"""

from __future__ import annotations

import math
import time
from typing import NamedTuple

import numpy as np

from planner._entry import entry_point, raw_entry_point, signal_cause
from planner._numba import njit_cached
from planner.errors import PlanError
from planner.occupancy.walk import as_cells
from planner.search.dstar.rest import mark_path, move_of, on_rest
from planner.search.heuristic import H_GAUGE
from planner.search.moves import carries_guarantee, move_set
from planner.search.result import SearchResult
from planner.search.run import search
from planner.world.world import World

__all__ = ["AStarReplanner", "RestMap"]


class RestMap(NamedTuple):
    """The bit maps of :mod:`planner.search.dstar.rest` over a world's index box (the
    fields its kernels read from a D* Lite box)."""

    lo: np.ndarray  # (3,) int64
    dims: np.ndarray  # (3,) int64
    rest: np.ndarray  # (prod(dims) / 8,) uint8 bit per cell: the path rests on it
    rest_blocks: np.ndarray  # (prod((dims + 3) // 4) / 8,) uint8 bit per 4x4x4 block


def new_rest_map(lo: np.ndarray, dims: np.ndarray) -> RestMap:
    """Empty rest map over the box ``lo + [0, dims)``."""
    dims = np.asarray(dims, np.int64).copy()
    cells, blocks = int(np.prod(dims)), int(np.prod((dims + 3) >> 2))
    return RestMap(np.asarray(lo, np.int64).copy(), dims,
                   np.zeros((cells + 7) // 8, np.uint8), np.zeros((blocks + 7) // 8, np.uint8))


@njit_cached
def rest_index(ms, rm, path, rest):  # pragma: no cover - compiled
    """Sorted keys ``box index * K + i`` of the cells step ``i`` of ``path`` ((K, 3) int64)
    rests on (cell i, and move i's safe-rule cells; cells outside the box left out);
    ``rest[i]`` (K,) is set to the cost of the path from cell i on (m), summed from the
    goal back."""
    k = path.shape[0]
    nmax = 0
    for m in range(ms.moves.shape[0]):
        nmax = max(nmax, ms.ptr[m + 1] - ms.ptr[m])
    keys = np.empty(k * (nmax + 1), np.int64)
    n = 0
    d0, d1, d2 = rm.dims[0], rm.dims[1], rm.dims[2]
    for i in range(k):
        p0, p1, p2 = path[i, 0], path[i, 1], path[i, 2]
        a, b, c = p0 - rm.lo[0], p1 - rm.lo[1], p2 - rm.lo[2]
        if 0 <= a < d0 and 0 <= b < d1 and 0 <= c < d2:
            keys[n] = ((a * d1 + b) * d2 + c) * k + i
            n += 1
        if i + 1 == k:
            break
        m = move_of(ms, path[i + 1, 0] - p0, path[i + 1, 1] - p1, path[i + 1, 2] - p2)
        rest[i] = ms.cost[m] if m >= 0 else np.nan
        if m < 0:
            continue
        for e in ms.idx[ms.ptr[m]:ms.ptr[m + 1]]:
            a, b, c = (p0 + ms.union[e, 0] - rm.lo[0], p1 + ms.union[e, 1] - rm.lo[1],
                       p2 + ms.union[e, 2] - rm.lo[2])
            if 0 <= a < d0 and 0 <= b < d1 and 0 <= c < d2:
                keys[n] = ((a * d1 + b) * d2 + c) * k + i
                n += 1
    if k:
        rest[k - 1] = 0.0
    for i in range(k - 2, -1, -1):
        rest[i] += rest[i + 1]
    return np.sort(keys[:n])


@njit_cached
def replace_rest(ms, rm, old, new, rest):  # pragma: no cover - compiled
    """Clear the rest bits of the path ``old`` ((K0, 3) int64, may be empty), set those of
    ``new`` ((K, 3)); returns ``new``'s :func:`rest_index` (``rest`` (K,) filled). One
    compiled call per new path."""
    if old.shape[0]:
        mark_path(ms, rm, old, old.shape[0], False)
    if new.shape[0]:
        mark_path(ms, rm, new, new.shape[0], True)
    return rest_index(ms, rm, new, rest)


@njit_cached(_nrt=False)
def _bisect(keys, x):  # pragma: no cover - compiled
    """The first position of sorted ``keys`` holding a value >= x."""
    lo, hi = 0, keys.shape[0]
    while lo < hi:
        mid = (lo + hi) >> 1
        if keys[mid] < x:
            lo = mid + 1
        else:
            hi = mid
    return lo


@njit_cached(_nrt=False)
def rest_hit(rm, keys, k, at, cells):  # pragma: no cover - compiled
    """Whether a cell of ``cells`` ((C, 3) int64) is one the path's steps ``at`` .. ``k - 1``
    rest on. Each cell's bits in ``rm`` are read first (most cells end there), then
    ``keys`` (:func:`rest_index`) by bisection."""
    for j in range(cells.shape[0]):
        b = on_rest(rm, cells[j, 0], cells[j, 1], cells[j, 2])
        if b >= 0:
            i = _bisect(keys, b * k + at)  # this cell's first step from ``at`` on
            if i < keys.shape[0] and keys[i] < (b + 1) * k:
                return True
    return False


class AStarReplanner:
    """A* between a (moving) start cell and a goal cell, re-run only when the changes
    touch the rest of the current path (module docstring).

    The interface of :class:`planner.search.dstar.lite.DStarLite`: mutate ``world`` (e.g.
    :meth:`World.set_cells`), pass the changed cells to :meth:`update`, move the start
    with :meth:`move_start`, and :meth:`plan`.

    Parameters
    ----------
    world : World
    start, goal : array_like of int, shape (3,)
        Lattice indices, free when the planner is made (PlanError otherwise).
    neighbors : str
        ``lattice.neighbors`` kind.
    corner_cutting : bool
        As :func:`planner.search.search`.

    Attributes
    ----------
    start, goal : ndarray (3,) int64
    searches : int
        Plans that searched (the others kept the path).
    """

    def __init__(self, world: World, start, goal, neighbors: str = "full",
                 corner_cutting: bool = False):
        if not isinstance(world, World):
            raise PlanError(f"world must be a World, got {type(world).__name__}")
        self.world = world
        self.start = world.endpoint_cell(start, "start").copy()
        self.goal = world.endpoint_cell(goal, "goal").copy()
        self.neighbors, self.corner_cutting = neighbors, bool(corner_cutting)
        self._ms = move_set(world.lattice, neighbors, corner_cutting, H_GAUGE)
        self.guarantee = carries_guarantee(world.lattice, neighbors, corner_cutting)
        occ = world.occupancy
        # a sparse world's box can be huge: no bit maps then, every change searches again
        self._rm = new_rest_map(occ.lo, occ.dims) if occ.mode == 0 else None
        self._path: np.ndarray | None = None  # (K, 3) the current path
        self._keys = np.zeros(0, np.int64)  # its rest index
        self._rest = np.zeros(0)  # (K,) cost of the path from each of its cells on (m)
        self._at = 0  # the start's row in it, -1 when the start left it
        self._pending: list[np.ndarray] = []  # blocked cells since the last plan
        self._freed = False  # a cell was freed (or looked up) since then: search
        self._seconds = 0.0  # engine time of update() lookups since the last plan
        self._lookups = 0
        self._hit_call = self._rest_call = None  # compiled entry points (planner._entry)
        self.searches = 0

    def move_start(self, cell) -> None:
        """The robot moved to ``cell`` ((3,) int): on the path it keeps it."""
        c = as_cells(cell)[0]
        self.start[:] = c
        p, at = self._path, self._at
        if p is not None and at >= 0:
            if at + 1 < len(p) and (p[at + 1] == c).all():
                self._at = at + 1
            elif not (p[at] == c).all():
                hit = np.flatnonzero((p == c).all(axis=1))
                self._at = int(hit[0]) if len(hit) else -1

    def update(self, changed_cells, blocked: bool | None = None) -> None:
        """Take the cells ``changed_cells`` ((K, 3) int) that flipped between free and
        blocked in the world (already mutated); the next :meth:`plan` decides whether to
        search. ``blocked`` says what they all became; None looks each one up."""
        c = changed_cells
        # the compiled check is called without type checks: C-contiguous, writeable int64
        if not (type(c) is np.ndarray and c.dtype == np.int64 and c.ndim == 2
                and c.shape[1] == 3 and c.flags.c_contiguous and c.flags.writeable):
            c = np.require(as_cells(c) if len(c) else _NONE, np.int64, ["C", "W"])
        if not len(c):
            return
        if blocked is None:
            t0 = time.perf_counter()
            state = ~self.world.checker.cells_free(c)
            self._seconds += time.perf_counter() - t0
            self._lookups += len(c)
            if not state.all():
                self._freed = True
            c = np.ascontiguousarray(c[state])
        elif not blocked:
            self._freed = True
            return
        self._pending.append(c)

    def plan(self) -> SearchResult:
        """Shortest path from the current start to the goal on the world as it is now.

        Returns
        -------
        SearchResult
            A kept path makes no cell check and no expansion (an :meth:`update` told
            nothing counts its lookups); a search's are A*'s. ``seconds``: the engine's
            time, the check and the rest index included (as A*'s, not the Python around
            it).
        """
        pend, self._pending = self._pending, []
        freed, self._freed = self._freed, False
        at = self._at
        if self._path is not None and at >= 0 and self._rm is not None and not freed:
            cells = pend[0] if len(pend) == 1 else np.concatenate(pend) if pend else _NONE
            t0 = time.perf_counter()
            if self._hit_call is None:  # its argument types never change
                self._hit_call = raw_entry_point(rest_hit, (self._rm, self._keys, 1, 0, cells))
            try:  # the raw entry point: a Python call less than entry_point's wrapper
                hit = self._hit_call(self._rm, self._keys, len(self._path), at, cells)
            except SystemError as exc:
                raise signal_cause(exc) from None
            self._seconds += time.perf_counter() - t0
            if not hit:
                return self._result(True, self._path[at:].copy(), float(self._rest[at]), 0, 0,
                                    0, "found", "")
        return self._search()

    def _search(self) -> SearchResult:
        self.searches += 1
        try:
            r = search(self.world, self.start, self.goal, method="astar",
                       neighbors=self.neighbors, corner_cutting=self.corner_cutting)
        except PlanError:  # an end cell is blocked: the start (stuck) or the goal
            t0 = time.perf_counter()
            free = self.world.checker.cells_free(np.stack([self.start, self.goal]))
            self._seconds += time.perf_counter() - t0
            self.world.cell_checks += 2
            self._set_path(None)
            if not free[0]:
                return self._result(False, None, math.inf, 2, 0, 0, "blocked",
                                    "start cell is blocked")
            return self._result(False, None, math.inf, 2, 0, 0, "unreachable",
                                "goal unreachable: its cell is blocked")
        self._seconds += r.seconds  # its lookups are in world.cell_checks already
        self._set_path(r.cells if r.found else None)
        return self._result(r.found, r.cells, r.cost, r.cell_checks, r.expansions,
                            r.generated, r.status, r.reason)

    def _set_path(self, cells: np.ndarray | None) -> None:
        """Replace the current path (and its rest bits and rest index) by ``cells``."""
        new = _NONE if cells is None else np.require(cells, np.int64, ["C", "W"])
        self._rest = np.empty(len(new))
        if self._rm is not None:
            old = _NONE if self._path is None else self._path
            t0 = time.perf_counter()
            if self._rest_call is None:  # its argument types never change
                self._rest_call = entry_point(replace_rest, (self._ms, self._rm, old, new,
                                                             self._rest))
            self._keys = self._rest_call(self._ms, self._rm, old, new, self._rest)
            self._seconds += time.perf_counter() - t0
        elif len(new):  # no bit maps: the costs alone (every change searches again)
            step = np.linalg.norm(np.diff(self.world.lattice.to_world(new), axis=0), axis=1)
            self._rest[:] = np.append(np.cumsum(step[::-1])[::-1], 0.0)
        self._path, self._at = (None if cells is None else new), 0

    def _result(self, found, cells, cost, checks, expansions, generated, status, why
                ) -> SearchResult:
        """The plan's result, with the lookups of :meth:`update` since the last one (added
        to ``world.cell_checks`` here; a search's own are added by it)."""
        if self._lookups:
            self.world.cell_checks += self._lookups
            checks += self._lookups
            self._lookups = 0
        secs, self._seconds = self._seconds, 0.0
        return SearchResult(found=found, cells=cells if found else _NONE.copy(), cost=cost,
                            cell_checks=checks, expansions=expansions, generated=generated,
                            seconds=secs, peak_bytes=0, reason=why, status=status,
                            guarantee=self.guarantee)


_NONE = np.zeros((0, 3), np.int64)
