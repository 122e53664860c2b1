"""Running a search: :func:`search` and :func:`search_many` (A*, Dijkstra, Theta*, Lazy
Theta*, weighted Lazy Theta*), over the kernel of :mod:`planner.search.astar`.

Nodes are lattice cells, edges the offsets ``lattice.neighbors(neighbors)``, edge cost the
Euclidean distance between cell centres (m). The movement rule, the radius guarantee and
the heuristic are described in :mod:`planner.search.moves`.

Timing: :attr:`SearchResult.seconds` is the kernel time only; the first search in a process
first compiles or loads the kernels (:func:`warm_up`, reported as
:attr:`SearchResult.compile_seconds`).

Any-angle: ``theta`` and ``lazy-theta`` rank nodes by g plus the straight-line distance to
the goal, so they expand the whole tube where that sum is below the path length.
``weighted-theta`` is ``lazy-theta`` with that distance multiplied by :data:`H_WEIGHT`:
deeper nodes win the near-ties and the search dives as lattice A* does. Everything else is
Lazy Theta*'s (moves, movement rule, lazy parent rule, exact line of sight), so its paths
are valid under the same rule and carry the same radius guarantee; their length is not
Lazy Theta*'s and no bound on the difference is proven (weighted A*'s factor bound does not
carry over to the parent rule): ``benchmarks/search_speed.py --anyangle`` measures it.

Budget: every search is bounded. ``max_expansions`` (default: the memory budget divided by
the bytes a node costs, :data:`planner.search._nodes.BYTES_PER_NODE`) stops it with status
``"budget"``; the memory budget defaults to an eighth of the physical memory
(:func:`default_memory_budget`).

Examples
--------
>>> import numpy as np
>>> from planner.lattice import Lattice
>>> from planner.world import World
>>> w = World(Lattice.named("cubic", 1.0), [[2, 2, 2]], [[0, 0, 0], [4, 4, 4]])
>>> r = search(w, [0, 0, 0], [4, 4, 4])
>>> r.status, round(r.cost, 4), r.guarantee
('found', 8.2925, True)
"""

from __future__ import annotations

import math
import os
import time
from time import perf_counter as _clock

import numpy as np

from planner import budget as _budget
from planner.errors import PlanError
from planner.lattice import Lattice
from planner.occupancy.walk import as_cells
from planner.search._job import (
    H_WEIGHT,
    MEMORY_SHARE,
    METHODS,
    Job,
    default_max_expansions,
    default_memory_budget,
    limit,
    prepare,
)
from planner.search._nodes import new_slots, rehash
from planner.search.astar import driver as _driver
from planner.search.astar.kernel import SearchParams
from planner.search.moves import carries_guarantee, move_heuristic, move_stencils
from planner.search.reference import search_networkx
from planner.search.result import (
    RUN_BAD_GOAL,
    RUN_BAD_START,
    RUN_EXHAUSTED,
    RUN_FOUND,
    RUN_LIMIT,
    RUN_STOPPED,
    STATUS_OF_RUN,
    SearchResult,
    found_result,
)
from planner.world.world import World

__all__ = ["SearchResult", "search", "search_many", "search_points", "warm_up",
           "move_stencils", "move_heuristic", "METHODS", "carries_guarantee",
           "default_memory_budget", "default_max_expansions", "H_WEIGHT", "MEMORY_SHARE"]

_WARM: list[float] = []


def warm_up() -> float:
    """Compile (or load from numba's on-disk cache) every search kernel once per process, on
    a tiny world, so that no search times the JIT. :func:`search` calls it first; callers
    that report times may call it up front.

    Returns
    -------
    float
        Seconds it took (0.0 once done in this process).
    """
    if _WARM:
        return 0.0
    _WARM.append(0.0)  # before the searches below, which call warm_up again
    t0 = time.perf_counter()
    w = World(Lattice.named("cubic", 1.0), np.array([[1, 1, 1]]), [[0, 0, 0], [3, 3, 3]])
    for method in ("astar", "lazy-theta"):
        search(w, [0, 0, 0], [3, 3, 2], method=method)
    rehash(new_slots(1), 0)  # the driver's slot-map growth
    _WARM[0] = time.perf_counter() - t0
    return _WARM[0]


def search(
    world: World,
    start_cell: np.ndarray,
    goal_cell: np.ndarray,
    *,
    method: str = "astar",
    neighbors: str = "full",
    corner_cutting: bool = False,
    backend: str = "numba",
    max_nodes: int | None = None,
    max_expansions: int | None = None,
    memory_budget: int | None = None,
) -> SearchResult:
    """Shortest path between two cells.

    Parameters
    ----------
    world : World
    start_cell, goal_cell : array_like of int, shape (3,)
        Lattice indices; both must be free (else PlanError naming which, where, and the
        nearest free cell: :meth:`World.endpoint_cell`).
    method : {"astar", "dijkstra", "theta", "lazy-theta", "weighted-theta"}
        ``weighted-theta``: Lazy Theta* with the heuristic weighted by :data:`H_WEIGHT`,
        at about A*'s cost (module docstring).
    neighbors : str
        ``lattice.neighbors`` kind: ``face``, ``full``, ``face+k``, ``full+k``.
    corner_cutting : bool
        False: the safe rule (:mod:`planner.search.moves`); True: only the target cell
        is checked (no radius guarantee unless the move set makes both rules equal).
    backend : {"numba", "networkx"}
        ``networkx`` (A*/Dijkstra only) builds the explicit free-cell graph of the start's
        component (at most ``max_nodes`` or 1,000,000 cells) and runs
        ``networkx.astar_path``: a slow readable reference.
    max_nodes : int, optional
        Give up (status "budget") once this many nodes exist.
    max_expansions : int, optional
        Give up (status "budget") after this many expansions. Default:
        :func:`default_max_expansions` of ``memory_budget``.
    memory_budget : int, optional
        Bytes the search may use (default :func:`default_memory_budget`); also caps the
        nodes created.

    Returns
    -------
    SearchResult
        Lookups are also added to ``world.cell_checks``.
    """
    if backend not in ("numba", "networkx"):
        raise PlanError(f"unknown backend {backend!r}; expected numba or networkx")
    job = prepare(world, method, neighbors, corner_cutting, max_nodes, max_expansions,
                  memory_budget, 1)
    compile_s = 0.0 if _WARM else warm_up()
    if backend == "networkx":
        s = world.endpoint_cell(start_cell, "start")
        gl = world.endpoint_cell(goal_cell, "goal")
        if job.params.anyangle:
            raise PlanError("the networkx backend supports astar and dijkstra only")
        res = search_networkx(world, s, gl, job.ms, job.max_nodes or None)
        res.guarantee = job.guarantee
        return res
    s, gl = start_cell, goal_cell  # as _end_cell, the usual case written out
    if not (type(s) is np.ndarray and s.shape == _SHAPE3 and s.dtype is _I8):
        s = _end_cell(s, "start")
    if not (type(gl) is np.ndarray and gl.shape == _SHAPE3 and gl.dtype is _I8):
        gl = _end_cell(gl, "goal")
    # _run written out (a call less on every search), and a query loop's next search
    # repeated by its job (the same arguments, see prepare) without comparing them again
    chk = world.checker
    pocket: list[tuple[int, int]] = []
    probe = (_goal_open, world, job.ms, pocket)
    t0 = _clock()
    got = _driver.repeat(chk, job, s, gl, probe)
    if got is None:
        ms, params = job.ms, job.params
        got = _driver.run(chk.occupancy, chk.walk, ms, s, gl, params,
                          _span(world) if params.anyangle else 0.0, chk, True, PROBE_AFTER,
                          probe, job)
    secs = _clock() - t0
    out, peak = got
    status, cells, cost, exp, gen, look = out
    if status == RUN_FOUND:
        world.cell_checks += look + 2  # and the two endpoint checks the kernel made
        return found_result(cells=cells, cost=cost, cell_checks=look + 2, expansions=exp,
                            generated=gen, seconds=secs, peak_bytes=peak,
                            guarantee=job.guarantee, compile_seconds=compile_s)
    res, look = _outcome(world, s, gl, job, out, peak, secs, pocket, compile_s)
    world.cell_checks += look + 2
    return res


def search_points(world: World, coords: tuple[float, ...], *, method: str = "astar",
                  neighbors: str = "full", corner_cutting: bool = False,
                  max_expansions: int | None = None,
                  memory_budget: int | None = None) -> SearchResult | None:
    """:func:`search` between the cells of a start and a goal point, with their lookups
    (:meth:`World.endpoints`, also counted in ``world.cell_checks``) made in the search's
    own kernel call when it can: what ``plan()`` does on a prebuilt world. ``coords``: the
    two points as :meth:`World.end_coords` gives them (m).

    Returns None, having checked or searched nothing, when it cannot: a lattice without a
    named rounding kernel, an any-angle method, an argument :func:`search` would refuse,
    this thread's first search of this kind, or an endpoint that is not free. The caller
    then does the same with :meth:`World.endpoints` (which raises the endpoint's error)
    and :func:`search`.
    """
    if not _WARM:
        return None
    try:
        job = prepare(world, method, neighbors, corner_cutting, None, max_expansions,
                      memory_budget, 1)
    except PlanError:
        return None
    chk = world.checker
    rounding = chk.rounding()
    ms, params = job.ms, job.params
    if rounding is None or params.anyangle:
        return None
    pocket: list[tuple[int, int]] = []
    t0 = _clock()
    got = _driver.run_points(chk.occupancy, chk.walk, ms, params, chk, rounding, coords,
                             PROBE_AFTER, (_goal_open, world, ms, pocket))
    secs = _clock() - t0
    if got is None:
        return None
    out, peak = got
    status, cells, cost, exp, gen, look = out
    if status == RUN_BAD_START or status == RUN_BAD_GOAL:
        return None
    if status == RUN_FOUND:
        world.cell_checks += look + 4  # the endpoints' lookups and the search's two checks
        return found_result(cells=cells, cost=cost, cell_checks=look + 2, expansions=exp,
                            generated=gen, seconds=secs, peak_bytes=peak,
                            guarantee=job.guarantee)
    res, look = _outcome(world, None, None, job, out, peak, secs, pocket, 0.0)
    world.cell_checks += look + 4
    return res


_SHAPE3, _I8 = (3,), np.dtype(np.int64)


def _end_cell(cell, what: str) -> np.ndarray:
    """A start or goal cell as (3,) int64 (PlanError for another shape or dtype); whether
    it is free is checked by the kernel, which names it when not."""
    c = as_cells(cell)
    if len(c) != 1:
        raise PlanError(f"{what} must be one cell (i, j, k), got shape {c.shape}")
    return c[0]


def _run(world: World, s: np.ndarray, gl: np.ndarray, job: Job,
         compile_s: float = 0.0) -> tuple[SearchResult, int]:
    """One kernel search between two free cells: the result and the lookups to add to
    ``world.cell_checks`` (left to the caller, so that threads never write to the world)."""
    chk = world.checker
    ms, params = job.ms, job.params
    pocket: list[tuple[int, int]] = []
    t0 = _clock()
    out, peak = _driver.run(chk.occupancy, chk.walk, ms, s, gl, params,
                            _span(world) if params.anyangle else 0.0, chk, True, PROBE_AFTER,
                            (_goal_open, world, ms, pocket))
    return _outcome(world, s, gl, job, out, peak, _clock() - t0, pocket, compile_s)


def _goal_open(world: World, ms, pocket: list, s, gl) -> bool:
    """Asked once, by a search still going after :data:`PROBE_AFTER` expansions: False (and
    the goal probe's ``(cells, lookups)`` appended to ``pocket``) when the goal is sealed
    in a small pocket."""
    p = _goal_pocket(world, ms, s, gl)
    if p is not None:
        pocket.append(p)
    return p is None


def _outcome(world: World, s: np.ndarray, gl: np.ndarray, job: Job, out: tuple, peak: int,
             secs: float, pocket: list, compile_s: float) -> tuple[SearchResult, int]:
    """The result of a kernel search (``out``, ``peak``: :func:`_driver.run`'s answer) and
    the lookups to add to ``world.cell_checks``; the endpoint's PlanError when an end cell
    is not free."""
    status, cells, cost, exp, gen, look = out
    if status == RUN_FOUND:
        return found_result(cells=cells, cost=cost, cell_checks=look + 2, expansions=exp,
                            generated=gen, seconds=secs, peak_bytes=peak,
                            guarantee=job.guarantee, compile_seconds=compile_s), look
    checks, max_nodes = look + 2, job.max_nodes  # and the two endpoint checks
    if status == RUN_BAD_START or status == RUN_BAD_GOAL:
        what = "start" if status == RUN_BAD_START else "goal"
        cell = s if status == RUN_BAD_START else gl
        world.endpoint_cell(cell, what)  # raises the endpoint's error
        raise PlanError(f"{what} cell {cell.tolist()} is not free")  # pragma: no cover
    if status == RUN_STOPPED:  # the goal is sealed in a small pocket
        (n, probe_look), = pocket  # the one probe's answer
        why = f"goal unreachable: its free space is {n} cells, closed off from the start"
        checks, look = checks + probe_look, look + probe_look
    elif status == RUN_EXHAUSTED:
        why = f"goal unreachable: explored {gen} cells"
    elif status == RUN_LIMIT and max_nodes and gen >= max_nodes:
        why = f"node limit {max_nodes} reached after {exp} expansions"
    else:
        why = f"search budget exhausted after {exp} expansions ({peak} bytes)"
    return SearchResult(found=False, cells=cells, cost=math.inf, cell_checks=checks,
                        expansions=exp, generated=gen, seconds=secs, peak_bytes=peak,
                        reason=why, status=STATUS_OF_RUN[status], guarantee=job.guarantee,
                        compile_seconds=compile_s), look


def search_many(
    world: World,
    start_cells: np.ndarray,
    goal_cells: np.ndarray,
    *,
    method: str = "astar",
    neighbors: str = "full",
    corner_cutting: bool = False,
    workers: int | None = None,
    max_nodes: int | None = None,
    max_expansions: int | None = None,
    memory_budget: int | None = None,
) -> list[SearchResult]:
    """Shortest paths for many start / goal pairs on one world, ``workers`` at a time.

    Each pair gets the result :func:`search` would give it (same path, cost and counts).
    The search kernel releases the GIL, so the threads search in parallel on the one
    shared world: no copies, no processes.

    Parameters
    ----------
    world : World
    start_cells, goal_cells : array_like of int, shape (Q, 3)
        Lattice indices, all free (checked before any search: PlanError naming the query).
    method, neighbors, corner_cutting, max_nodes, max_expansions
        As :func:`search` (numba backend).
    workers : int, optional
        Threads (default: the CPUs this process may use, at most Q).
    memory_budget : int, optional
        Bytes for all searches together (default :func:`default_memory_budget`): each of
        the ``workers`` concurrent searches gets its share.

    Returns
    -------
    list of SearchResult, length Q, in query order
        Their lookups are also added to ``world.cell_checks``.
    """
    from concurrent.futures import ThreadPoolExecutor  # local: only search_many runs threads

    a, b = as_cells(start_cells), as_cells(goal_cells)
    if a.shape != b.shape:
        raise PlanError(f"start_cells and goal_cells must have the same shape (Q, 3), got "
                        f"{a.shape} and {b.shape}")
    if workers is None:
        cpus = os.sched_getaffinity(0) if hasattr(os, "sched_getaffinity") else None
        workers = len(cpus) if cpus else (os.cpu_count() or 1)
    workers = max(1, min(limit(workers, "workers"), len(a)))
    job = prepare(world, method, neighbors, corner_cutting, max_nodes, max_expansions,
                  memory_budget, workers)
    compile_s = warm_up()
    for i in range(len(a)):
        world.endpoint_cell(a[i], f"query {i}: start")
        world.endpoint_cell(b[i], f"query {i}: goal")

    def one(i: int) -> tuple[SearchResult, int]:
        return _run(world, a[i], b[i], job, compile_s if i == 0 else 0.0)

    if workers == 1:
        done = [one(i) for i in range(len(a))]
    else:
        with ThreadPoolExecutor(workers) as pool:
            done = list(pool.map(one, range(len(a))))
    out = []
    for res, look in done:
        world.cell_checks += look
        out.append(res)
    return out


GOAL_PROBE = 256  # expansions of the search from the goal (the goal probe)
#: expansions after which a search still going runs the goal probe: most searches end
#: sooner and skip it. The probe costs more than its GOAL_PROBE expansions suggest (each
#: one generates fresh nodes on the paged slot map, and the pause goes through Python:
#: the time of several hundred expansions of the main search), so it waits until that is
#: a few per cent of the search. At 2,048 it cost Warframe Complex a twentieth of its A*
#: time (`python benchmarks/cpp_anchor.py --maps Complex --queries 200`: ours / floor
#: overall 0.88-0.90 at 2,048, 0.93-0.94 here); a sealed goal costs at most this many
#: expansions (a few ms) before the probe stops its search.
PROBE_AFTER = 16384


def _goal_pocket(world: World, ms, start, goal) -> tuple[int, int] | None:
    """``(cells, lookups)`` when a search from the goal (lattice moves, at most
    :data:`GOAL_PROBE` expansions) runs out of cells before reaching the start: the goal
    is sealed off, so an unbounded search from the start could only end at the budget.
    None otherwise; its lookups are then not counted (not part of the measured search;
    its time, well under a millisecond, is). Nothing is written to the world.
    The moves are symmetric (the same cells are checked either way), so this is exact."""
    chk = world.checker
    (status, _, _, _, nodes, lookups), _ = _driver.run(
        chk.occupancy, chk.walk, ms, goal, start, SearchParams(0, 0, GOAL_PROBE), 0.0,
        owner=chk, dense=False)
    if status != RUN_EXHAUSTED:
        return None
    return nodes, lookups


def _span(world: World) -> float:
    """Longest line of sight inside the world (m): sizes the any-angle walk scratch. Capped
    so the scratch (~72 bytes per cell a sight line may touch) stays within 1/16 of the
    memory budget: a huge box must not allocate by its size; longer sight lines walk on
    fresh arrays."""
    walk = world.checker.walk
    step = math.sqrt(2.0 * float(walk.rhs.min()))
    steps = _budget.memory_budget() / 16 / 72 / (len(walk.full) + 1)
    return min(float(np.linalg.norm(world.bounds[1] - world.bounds[0])), steps * step)
