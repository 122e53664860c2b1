"""One task of a suite: a world configuration, a method and a batch of queries, run in
whatever process gets it (local, a pool worker, a Dask worker); each row records the host
that ran it."""

from __future__ import annotations

import contextlib
import time
from typing import NamedTuple

import numpy as np

from planner import planning as api
from planner import search
from planner.analysis.metadata import row_commit
from planner.bench.explore_rows import explore_rows
from planner.bench.host import worker_host
from planner.bench.metrics import Clearance
from planner.bench.rotations import IDENTITY_XYZW
from planner.bench.worlds import cached_frame, cached_world
from planner.errors import PlannerError
from planner.path import path_length

__all__ = ["run_task", "LATTICE_METHODS"]

_WORLDS: dict = {}
_CLEARANCE: dict = {}
_WARMED: set = set()
LATTICE_METHODS = ("astar", "dijkstra", "theta", "lazy-theta", "weighted-theta")


def _frame(map_path: str):
    return cached_frame(map_path)


def _world(task: dict):
    """Per-process cache: a worker builds (or loads, see
    :func:`planner.bench.worlds.cached_world`) each world once for all its queries."""
    quat = tuple(task.get("quaternion_xyzw", IDENTITY_XYZW))
    key = (task["map"], task["lattice"], task["cell_volume"], task["radius"], quat)
    if key not in _WORLDS:
        if len(_WORLDS) > 12:
            _WORLDS.clear()
        _WORLDS[key] = cached_world(task.get("world_cache"), *key)
    return _WORLDS[key]


def _clearance(map_path: str):
    """Clearance against the map's obstacles (paths of rotated worlds are in the map's own
    frame too, see :mod:`planner.bench.worlds`)."""
    if map_path not in _CLEARANCE:
        _CLEARANCE.clear()
        o = _frame(map_path).obstacles
        _CLEARANCE[map_path] = Clearance(o.points, o.boxes, o.box_sizes)
    return _CLEARANCE[map_path]


def _warm(world, task: dict) -> None:
    """Load every kernel a query of this configuration calls (search, shortcut, path
    metrics) once per process, on a two-cell query of the same lattice, so that no row
    times the JIT or numba's cache load."""
    key = (world.lattice.name, task["neighbors"], task["method"])
    if key in _WARMED or task["method"].startswith("ompl:"):
        return
    _WARMED.add(key)
    from planner.world import World  # lazy: numba

    lat = world.lattice
    a, b = lat.to_world(np.array([[0, 0, 0], [3, 0, 0]]))
    pad = 3.0 * lat.covering_radius
    tiny = World(lat, np.zeros((0, 3), np.int64),
                 np.array([np.minimum(a, b) - pad, np.maximum(a, b) + pad]))
    with contextlib.suppress(PlannerError):
        res = api.plan(tiny, a, b, method=task["method"], neighbors=_neighbors(task))
        if res.found and len(res.cells) > 2:
            search.shortcut(tiny, res.cells)


def _neighbors(task: dict) -> str:
    return task["neighbors"] if task["neighbors"] != "-" else "full"


class Cost(NamedTuple):
    """What one step of a query cost: occupancy lookups, wall and CPU seconds."""

    checks: int
    seconds: float
    cpu_seconds: float


def _cost_fields(search_cost: Cost, smooth_cost: Cost) -> dict:
    """The row's cost columns: search, post-processing (smoothing) and their sums, which
    are what the user pays for the delivered path (``cell_checks``, ``seconds``,
    ``cpu_seconds``)."""
    return {"search_checks": search_cost.checks, "search_seconds": search_cost.seconds,
            "search_cpu_seconds": search_cost.cpu_seconds,
            "smooth_checks": smooth_cost.checks, "smooth_seconds": smooth_cost.seconds,
            "smooth_cpu_seconds": smooth_cost.cpu_seconds,
            "cell_checks": search_cost.checks + smooth_cost.checks,
            "seconds": search_cost.seconds + smooth_cost.seconds,
            "cpu_seconds": search_cost.cpu_seconds + smooth_cost.cpu_seconds}


NO_COST = Cost(0, 0.0, 0.0)


def run_task(task: dict) -> list[dict]:
    """Run one task (a world configuration, a method and a batch of queries).

    A plain function of plain data so that it pickles to processes and Dask workers.

    Every row carries what the user pays for the path it delivers: the search
    (``search_checks``, ``search_seconds`` wall, ``search_cpu_seconds`` CPU of the whole
    :func:`planner.plan` call) and the post-processing (``smooth_*``: line-of-sight
    shortcutting of an A*/Dijkstra path, :func:`planner.search.shortcut`, and joining its
    ends as :func:`planner.plan` with ``shortcut=True`` does: the same path, its checks
    counted as plan() counts them; 0 for any-angle methods, whose path is delivered as
    searched, and for OMPL, whose simplification is inside its own time), and their sums
    ``cell_checks``, ``seconds`` and ``cpu_seconds``. ``delivered`` names the path whose
    length the report compares (``"smoothed"`` or ``"raw"``; ``length_smoothed`` is always that
    path's length). ``blocked`` is True when the lattice blocks the start or goal (the
    query was sampled free on another lattice).
    """
    if task["method"] == "explore":  # a robot sensing its way, not one planned path
        return explore_rows(task)
    world = _world(task)
    clear = _clearance(task["map"])
    step = 0.25 * world.lattice.packing_radius
    _warm(world, task)
    meth = task["method"]
    smoothed = meth in ("astar", "dijkstra")
    rows = []
    for q in task["queries"]:
        base = {k: task[k] for k in ("suite", "map", "cell_volume", "radius", "lattice",
                                     "neighbors", "method", "seed")}
        base.update(commit=row_commit(), **worker_host(), rotation=task.get("rotation", 0),
                    quaternion_xyzw=list(task.get("quaternion_xyzw", IDENTITY_XYZW)))
        base.update(query=q["id"], start=q["start"], goal=q["goal"],
                    optimal_cost=q.get("optimal_cost"),
                    delivered="smoothed" if smoothed or meth.startswith("ompl:") else "raw")
        if meth.startswith("ompl:"):  # its budget (s): Planner Arena's timelimit
            base["time_limit"] = float(task.get("ompl_time", 1.0))
        t0, c0 = time.perf_counter(), time.process_time()
        try:
            res = api.plan(world, q["start"], q["goal"], method=meth,
                           neighbors=_neighbors(task),
                           time_limit=task.get("ompl_time", 1.0), seed=task["seed"])
        except PlannerError as exc:
            spent = Cost(0, time.perf_counter() - t0, time.process_time() - c0)
            rows.append({**base, "found": False, "reason": str(exc),
                         "blocked": _blocked(world, q), "length": None,
                         "length_smoothed": None, **_cost_fields(spent, NO_COST),
                         "expansions": 0, "peak_bytes": 0, "clearance": None,
                         "collision_free": None})
            continue
        searched = Cost(res.cell_checks, time.perf_counter() - t0, time.process_time() - c0)
        smooth_cost = NO_COST
        row = {**base, "found": res.found, "reason": res.reason, "blocked": False,
               "expansions": res.expansions, "peak_bytes": res.peak_bytes, "length": None,
               "length_smoothed": None, "clearance": None, "collision_free": None}
        if res.found:
            raw = res.path
            if meth.startswith("ompl:"):
                raw_path = np.asarray(res.extra.get("path_raw", raw), dtype=float).reshape(-1, 3)
                smooth = raw
                raw = raw_path if len(raw_path) > 1 else raw
            elif smoothed:
                s_pt, _, g_pt, _ = world.endpoints(q["start"], q["goal"])  # as plan()'s
                t1, c1 = time.perf_counter(), time.process_time()
                smooth, checks = _smoothed(world, res.cells, s_pt, g_pt)
                smooth_cost = Cost(checks, time.perf_counter() - t1, time.process_time() - c1)
            else:
                smooth = raw
            c_raw = clear.of_path(raw, step)
            c_smooth = clear.of_path(smooth, step)
            tol = 1e-9 * max(1.0, world.lattice.covering_radius)
            row.update(length=path_length(raw), length_smoothed=path_length(smooth),
                       clearance=min(c_raw, c_smooth),
                       collision_free=bool(min(c_raw, c_smooth) >= task["radius"] - tol),
                       waypoints=len(raw))
        rows.append({**row, **_cost_fields(searched, smooth_cost)})
    return rows


def _smoothed(world, cells: np.ndarray, start: np.ndarray, goal: np.ndarray
              ) -> tuple[np.ndarray, int]:
    """The path ``plan(..., shortcut=True)`` delivers for the searched ``cells`` (K, 3)
    and the checks it counts for its smoothing: :func:`planner.search.shortcut` of the
    cells (its lookups counted), then the ends joined as :func:`planner.planning.joined`
    joins them (those lookups uncounted, as plan()'s ``cell_checks`` leaves them out).
    ``start``, ``goal`` (3,): the endpoints in the world's frame (m); the path is in the
    map's frame (m), shape (K', 3)."""
    before = world.cell_checks
    cut = search.shortcut(world, cells)
    checks = world.cell_checks - before
    path = api.joined(world, np.concatenate([start[None], world.lattice.to_world(cut),
                                             goal[None]]))
    return world.to_map(path), checks


def _blocked(world, q: dict) -> bool:
    """The lattice blocks the query's start or goal (or they lie outside its bounds)."""
    try:
        pts = np.array([q["start"], q["goal"]], dtype=float)
        return not bool(np.all(world.points_free(pts)))
    except (PlannerError, ValueError):
        return True
