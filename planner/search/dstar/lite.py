"""Incremental replanning: D* Lite over the lattice graph, for a robot that moves and senses.

The graph, safe rule, edge costs (m) and heuristic are those of
``planner.search.search(..., method="astar")`` (:mod:`planner.search.moves`); the search
runs from the goal towards the start, so the start may move (:meth:`DStarLite.move_start`)
and changed cells (:meth:`DStarLite.update`, after the world was mutated, e.g. with
:meth:`planner.world.World.set_cells`) repair only the vertices whose edges they touch.
Kernels and data layout: :mod:`planner.search.dstar.kernel`; the changes' repair, the path and
the one compiled call a replan makes: :mod:`planner.search.dstar.replan`. :meth:`update`
only takes the changed cells; :meth:`plan` repairs, searches and extracts the path, and
reuses the previous path from the new start on while nothing it was read from changed.
When the changes only block cells and none lies under the stored path (its cells and its
moves' safe-rule cells), that path is still a shortest one: :meth:`plan` keeps it without
repairing and leaves the cells pending until a change reaches the path
(:mod:`planner.search.dstar.rest`).

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
from typing import NamedTuple

import numpy as np

from planner._entry import entry_point, raw_entry_point, signal_cause
from planner.errors import PlanError
from planner.occupancy.walk import as_cells
from planner.search._grow import grown
from planner.search._heap import grown_heap, new_heap
from planner.search._state import new_state
from planner.search.dstar import kernel as dk
from planner.search.dstar import replan as dr
from planner.search.dstar.rest import CheckLines, check_lines
from planner.search.heuristic import H_GAUGE, gauge_np
from planner.search.moves import carries_guarantee, move_set
from planner.search.result import RUN_FOUND, RUN_GROW, STATUS_OF_RUN, SearchResult
from planner.world.world import World

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
        affect = np.zeros(len(self._ms.union), np.int64)
        for m in range(nm):
            for e in self._ms.idx[self._ms.ptr[m]:self._ms.ptr[m + 1]]:
                affect[e] |= np.int64(1) << np.int64(m)
        occ = world.occupancy
        if occ.mode != 0:
            raise PlanError("D* Lite needs dense occupancy storage (an index box of at most "
                            "8 x the world's dense_budget cells; a smaller world)")
        self._bx = dk.new_box(occ.lo, occ.dims, self._ms)
        self._nd = dk.new_nodes(4096)
        self._heap = new_heap(4096)
        i8 = np.int64
        self._sc = dr.DScratch(ufree=np.empty(len(self._ms.union), np.bool_), affect=affect,
                               ss=np.empty(1024, i8), old=np.empty(1024, i8),
                               redo=np.empty(1024, np.bool_), touched=np.empty(1024, i8),
                               path=np.empty((4097, 3), i8), step=np.empty(4097, np.float64))
        self._state_array = new_state(dk.REPLAN_STATE)  # (1,): what the compiled call takes
        self._st = self._state_array[0]  # its record: a view, read and written from here
        self._sv = self._state_array.view(np.int64)  # the same by field index (_NODES...)
        self._fs = np.zeros(2)  # slots dk.KM and dk.PATH_COST
        self._last = self.start.copy()
        g = dk.node(self._bx, self._nd, self._st, *(int(x) for x in self.goal), True)
        self._st["goal"] = g
        self._nd.rhs[g] = 0.0
        dk.update_vertex(self._ms, self._nd, self._heap, self._st, 0.0, self.start, g)
        self._mark = (0, 0)  # lookups, expansions at the last plan
        self._seconds = 0.0  # engine time of update() lookups since the last plan
        self._pending: list[tuple[np.ndarray, np.ndarray | bool]] = []  # since then
        self._kept: list[tuple[np.ndarray, bool]] = []  # blocked, not repaired (_keep)
        self._kept_n = 0  # cells in _kept
        self._state: _Memo | None = None  # the ReplanState of the arrays: see _call
        self._keep_call = None  # keep_state's entry point (_keep)
        self._phase_call = None  # replan_phase_state's entry point (_phases)
        self._fl = {True: np.ones(1024, np.bool_), False: np.zeros(1024, np.bool_)}
        self._peak = 0
        self._repair = RepairCounts(0, 0)
        self._ordered = 0  # node count at the last renumbering (_compact)
        self._sized()

    # -- storage -----------------------------------------------------------------------
    def _room(self, extra: int) -> None:
        """Room for ``extra`` more nodes, a path through every node, and the repair
        scratch the kernel asked for (``need_scratch``)."""
        n = int(self._st["nodes"])
        cap = len(self._nd.key)
        if n + extra > cap:
            while cap < n + extra:
                cap *= 2
            self._nd = dk.new_nodes(cap, self._nd, n)
            self._heap = grown_heap(self._heap, cap, int(self._st["queued"]))
        sc = self._sc
        if len(sc.path) < n + 1:  # keeps the stored path
            k = int(self._st["path_len"])
            sc = sc._replace(path=grown(sc.path, 2 * n + 1, k),
                             step=grown(sc.step, 2 * n + 1, k))
        need = int(self._st["need_scratch"])
        if len(sc.touched) < need:
            sc = sc._replace(touched=np.empty(max(need, 2 * len(sc.touched)), np.int64))
        self._sc = sc
        self._sized()

    def _collect_room(self, k: int) -> None:
        """Scratch to collect the nodes of ``k`` changed cells (each once per stencil
        offset at most): reused between replans, grown by doubling."""
        size = k * (len(self._ms.union) + 1)
        sc = self._sc
        if len(sc.ss) < size:
            size = max(size, 2 * len(sc.ss))
            self._sc = sc._replace(ss=np.empty(size, np.int64), old=np.empty(size, np.int64),
                                   redo=np.empty(size, np.bool_))
            self._sized()

    @property
    def nodes(self) -> int:
        """Nodes created so far."""
        return int(self._sv[_NODES])

    @property
    def peak_bytes(self) -> int:
        """Bytes of the planner's own arrays (they only grow)."""
        return self._peak

    @property
    def last_repair(self) -> RepairCounts:
        """What the last :meth:`plan` repaired (zeros before the first and for a plan that
        kept the stored path or was told no change): for profiling."""
        return self._repair

    def pending_check_lines(self) -> CheckLines:
        """The cache lines a kept replan's check of the changes told since the last
        :meth:`plan` reads (:func:`planner.search.dstar.rest.check_lines`): for profiling."""
        pend = [c for c, _ in self._pending if len(c)]
        return check_lines(self._bx, np.concatenate(pend) if pend else _NONE)

    def _sized(self) -> None:
        """Recount :attr:`peak_bytes` (after arrays grew); the replan state is remade."""
        self._state = None
        self._peak = (len(self._nd.key) * dk.NODE.itemsize
                      + sum(a.nbytes for part in (self._heap, self._bx, self._sc)
                            for a in part))

    def _compact(self) -> None:
        """Renumber the nodes in box order (:func:`dk.box_ordered`), after a plan that at
        least doubled the node count (the first one mostly); counted in that plan's time."""
        self._nd, self._ordered = dk.box_ordered(self._nd, self._bx, self._heap, self._st)
        self._sized()

    # -- the three operations ------------------------------------------------------------
    def move_start(self, cell) -> None:
        """The robot moved to ``cell`` ((3,) int): keys stay valid through ``km``."""
        c = as_cells(cell)[0]
        self._fs[dk.KM] += float(gauge_np(self._ms.hmat, c - self._last))
        self._last = c.copy()
        self.start[:] = c  # in place: the replan's entry point is keyed on this array

    def update(self, changed_cells, blocked: bool | None = None) -> None:
        """Take the cells ``changed_cells`` ((K, 3) int) that flipped between free and
        blocked in the world (already mutated); the next :meth:`plan` repairs.

        ``blocked`` says what they all became (as :meth:`World.set_cells` was told);
        None looks each one up (K cell checks). Nodes whose edge stencil holds a newly
        blocked cell drop the moves it serves without a lookup; nodes near a newly freed
        cell look their stencil up again; edges that flipped repair their end nodes.
        Batches taken before one plan are repaired together, with the start and ``km``
        of that plan (as D* Lite's main loop: move, scan, update, compute), and with the
        blocked cells of plans that kept the stored path (module docstring).
        """
        c = changed_cells
        if not (type(c) is np.ndarray and c.dtype == np.int64 and c.ndim == 2
                and c.shape[1] == 3 and c.flags.c_contiguous and c.flags.writeable):
            c = as_cells(c) if len(c) else _NONE
            if not c.flags.writeable:  # the kernel's signature takes writeable arrays
                c = c.copy()
        if not len(c):
            return
        if blocked is None:  # lookups: engine work, timed as the next plan's
            t0 = time.perf_counter()
            state = ~self.world.checker.cells_free(c)
            self._seconds += time.perf_counter() - t0
            self._st["lookups"] += len(c)
        else:
            state = bool(blocked)  # made an array in plan()
        self._pending.append((c, state))

    def plan(self) -> SearchResult:
        """Shortest path from the current start to the goal on the world as it is now.

        Returns
        -------
        SearchResult
            ``cell_checks``, ``expansions`` and ``seconds`` cover the work since the
            previous :meth:`plan` (the updates included: they are repaired here, in one
            compiled call with the search and the path); ``generated`` counts every node
            ever created. ``seconds``, as A*'s, is the engine's own time: the compiled
            calls (and growing arrays between them) and the lookups of an ``update``
            told nothing, not the Python that prepares the call or builds this result.
            A plan that keeps the stored path (module docstring) makes no cell check of
            its own (an :meth:`update` told nothing still counts its lookups here) and no
            expansion.
        """
        return self._plan(None)

    def plan_phases(self) -> tuple[SearchResult, np.ndarray]:
        """:meth:`plan`, each phase of the replan run as its own compiled call and timed.

        The same phase code runs as in :meth:`plan` (one compiled call per phase instead
        of one for all), and the result is the same. For profiling: where a replan's time
        goes.

        Returns
        -------
        result : SearchResult
            As :meth:`plan`'s (its ``seconds`` include the phases' calls).
        seconds : ndarray, shape (4,), float64
            Wall seconds (``time.perf_counter``) of each phase's call, in the order of
            :data:`planner.search.dstar.replan.PHASES`: collecting the nodes whose edges
            the changes touch, repairing their edges, the search, extracting the path.
            NaN for a phase that did not run (collect and repair without changes; all
            four when the plan kept the stored path), and all NaN when a phase had to
            grow the planner's arrays (that plan's phases are not separated).
        """
        secs = np.full(len(dr.PHASES), np.nan)
        return self._plan(secs), secs

    def _plan(self, phase_secs: np.ndarray | None) -> SearchResult:
        """:meth:`plan`; with ``phase_secs`` (4,) the phases one call each, timed into it
        (:meth:`plan_phases`)."""
        st, pend = self._st, self._pending
        self._pending = []
        if self._sv[_PATH_VALID] and self._blocks_only(pend):
            kept = self._keep(pend)
            if kept is not None:
                self._repair = RepairCounts(0, 0)
                return kept
        if self._kept:  # repaired now, before the new changes
            pend = self._kept + pend
            self._kept, self._kept_n = [], 0
        if len(pend) == 1 and isinstance(pend[0][1], bool):
            cells = pend[0][0]
            state = self._flags(len(cells), pend[0][1])
        elif pend:
            cells = np.concatenate([p[0] for p in pend])
            state = np.concatenate([np.full(len(c), b) if isinstance(b, bool) else b
                                    for c, b in pend])
        else:
            cells, state = _NONE, _NONE_B
        if len(cells):
            self._collect_room(len(cells))
            st["phase"] = dr.PH_COLLECT
        else:
            st["phase"] = dr.PH_SEARCH
        st["check_start"] = 1  # the start's own cell: one lookup, as A*'s endpoint check
        call, arg = self._call()
        if phase_secs is not None and self._phase_call is None:  # compiled off the clock
            self._phase_call = entry_point(dr.replan_phase_state, (arg, cells, state))
        t0 = time.perf_counter()
        done = None if phase_secs is None else self._phases(arg, cells, state, phase_secs)
        while done is None or done == RUN_GROW:
            if done is not None:
                self._room(int(st["need_nodes"]))
                call, arg = self._call()
            done = call(arg, cells, state)
        n = int(st["collected"]) if len(cells) else 0  # before _compact renumbers them
        self._repair = RepairCounts(n, int((self._nd.mask[self._sc.ss[:n]] == 0).sum()))
        if int(st["nodes"]) >= max(_COMPACT_MIN, 2 * self._ordered):
            self._compact()
        self._seconds += time.perf_counter() - t0
        if done == RUN_FOUND:
            j, k = int(st["path_from"]), int(st["path_to"])
            return self._result(self._sc.path[j:k].copy(), float(self._fs[dk.PATH_COST]), "", done)
        why = ("start cell is blocked" if STATUS_OF_RUN[done] == "blocked"
               else f"goal unreachable: explored {self.nodes} cells")
        return self._result(None, math.inf, why, done)

    def _phases(self, arg, cells, state, secs: np.ndarray) -> int:
        """Run the replan one compiled call per phase (:func:`dr.replan_phase_state`),
        timing each into ``secs``; returns the replan's code. A phase that needs room
        returns RUN_GROW with ``secs`` all NaN: :meth:`_plan` grows and resumes it."""
        st = self._st  # self._phase_call: looked up once, its argument types never change
        while True:
            k = int(st["phase"])
            t0 = time.perf_counter()
            done = self._phase_call(arg, cells, state)
            secs[k] = time.perf_counter() - t0
            if done == RUN_GROW:
                secs[:] = np.nan
            if done != _RUN_NEXT:
                return done

    def _keep(self, pend: list) -> SearchResult | None:
        """The stored path from the start on, when the changes ``pend`` (all blocked)
        leave it a shortest path (:mod:`planner.search.dstar.rest`): they stay pending,
        unrepaired, with those kept before. None when it cannot be kept."""
        cells = pend[0][0] if len(pend) == 1 else (
            np.concatenate([p[0] for p in pend]) if pend else _NONE)
        sv = self._sv
        _, state = self._call()
        if self._keep_call is None:  # its argument types never change
            self._keep_call = raw_entry_point(dr.keep_state, (state, cells))
        t0 = time.perf_counter()
        try:  # the raw entry point: a Python call less than entry_point's wrapper
            kept = self._keep_call(state, cells)
        except SystemError as exc:
            raise signal_cause(exc) from None
        self._seconds += time.perf_counter() - t0
        if not kept:
            return None
        if len(cells):  # copied: the caller may reuse its array
            self._kept.append((cells.copy() if cells is pend[0][0] else cells, True))
            self._kept_n += len(cells)
        return self._result(self._sc.path[sv[_PATH_FROM]:sv[_PATH_TO]].copy(),
                            float(self._fs[dk.PATH_COST]), "", RUN_FOUND)

    def _blocks_only(self, pend: list) -> bool:
        """Whether the changes ``pend`` only block cells, few enough to keep pending."""
        n = self._kept_n
        for c, b in pend:
            if b is False or (b is not True and not b.all()):
                return False
            n += len(c)
        return n <= _KEEP_MAX

    def _flags(self, k: int, value: bool) -> np.ndarray:
        """``np.full(k, value)`` as a view of an array kept for the purpose."""
        a = self._fl[value]
        if len(a) < k:
            a = self._fl[value] = np.full(max(k, 2 * len(a)), value)
        return a[:k]

    def _call(self):
        """``(f, a)``: ``f(a, cells, blocked)`` runs ``dr.replan`` on the planner's arrays.

        ``a`` is a :class:`dr.ReplanState` of them (one object to unbox instead of ~45
        arrays), made again when one was replaced (the planner's grew: ``_room`` clears
        it; or the world's occupancy struct or ``start`` is another object); ``f`` the
        compiled entry point of its signature (:mod:`planner._entry`: numba's
        dispatcher would type the arguments on every call; here they are fixed:
        :meth:`plan` passes C-contiguous (K, 3) int64 cells and (K,) bool states)."""
        occ = self.world.occupancy
        memo = self._state
        if memo is not None and memo.occ is occ and memo.start is self.start:
            return memo.call, memo.state
        state = dr.new_state(occ=occ, ms=self._ms, bx=self._bx, nd=self._nd, heap=self._heap,
                             sc=self._sc, st=self._state_array, fs=self._fs, start=self.start)
        call = entry_point(dr.replan_state, (state, _NONE, _NONE_B))
        self._state = _Memo(occ, state, call, self.start)
        return call, state

    def _result(self, cells, cost, why, code) -> SearchResult:
        look, exp = int(self._sv[_LOOKUPS]), int(self._sv[_EXPANSIONS])
        look0, exp0 = self._mark
        checks, expansions = look - look0, exp - exp0
        self._mark = (look, exp)
        self.world.cell_checks += checks
        secs, self._seconds = self._seconds, 0.0
        found = cells is not None
        return SearchResult(found=found, cells=cells if found else np.zeros((0, 3), np.int64),
                            cost=cost, cell_checks=checks, expansions=expansions,
                            generated=self.nodes, seconds=secs, peak_bytes=self.peak_bytes,
                            reason=why, status=STATUS_OF_RUN[code], guarantee=self.guarantee)


class RepairCounts(NamedTuple):
    """A plan's repair (:attr:`DStarLite.last_repair`)."""

    collected: int  # nodes whose stencil holds a changed cell, repaired
    died: int  # of those, left without edges (their own cell blocked, or walled in)


class _Memo(NamedTuple):
    """The planner's ReplanState, its entry point, and what they were made for (_call)."""

    occ: object  # the world's occupancy struct
    state: object  # dr.ReplanState of the planner's arrays
    call: object  # the compiled dr.replan_state for its type
    start: np.ndarray


_NONE = np.zeros((0, 3), np.int64)
_COMPACT_MIN = 1 << 14  # nodes: below this the node table fits in cache anyway
_KEEP_MAX = 1 << 15  # unrepaired cells: then a repair (bounds its batch's scratch)
_NONE_B = np.zeros(0, np.bool_)
_RUN_NEXT = dr.RUN_NEXT
# field indices of the state record, read through an int64 view (``_sv``): a record's
# field by name costs microseconds, more than a kept replan's compiled call
_PATH_VALID, _PATH_FROM, _PATH_TO, _LOOKUPS, _EXPANSIONS, _NODES = (
    dk.REPLAN_STATE.names.index(f) for f in ("path_valid", "path_from", "path_to",
                                             "lookups", "expansions", "nodes"))
