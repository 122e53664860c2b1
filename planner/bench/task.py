"""One task of a suite: a world configuration, a method and a batch of queries, run in
whatever process gets it (local, a pool worker, a Dask worker); each row records the host
that ran it."""

from __future__ import annotations

import time

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


def run_task(task: dict) -> list[dict]:
    """Run one task (a world configuration, a method and a batch of queries).

    A plain function of plain data so that it pickles to processes and Dask workers.
    """
    if task["method"] == "explore":  # a robot sensing its way, not one planned path
        return explore_rows(task)
    world = _world(task)
    clear = _clearance(task["map"])
    step = 0.25 * world.lattice.packing_radius
    rows = []
    for q in task["queries"]:
        base = {k: task[k] for k in ("suite", "map", "cell_volume", "radius", "lattice",
                                     "neighbors", "method", "seed")}
        base.update(commit=row_commit(), **worker_host(), rotation=task.get("rotation", 0),
                    quaternion_xyzw=list(task.get("quaternion_xyzw", IDENTITY_XYZW)))
        base.update(query=q["id"], start=q["start"], goal=q["goal"],
                    optimal_cost=q.get("optimal_cost"))
        if task["method"].startswith("ompl:"):  # its budget (s): Planner Arena's timelimit
            base["time_limit"] = float(task.get("ompl_time", 1.0))
        t0 = time.perf_counter()
        try:
            res = api.plan(world, q["start"], q["goal"], method=task["method"],
                           neighbors=task["neighbors"] if task["neighbors"] != "-" else "full",
                           time_limit=task.get("ompl_time", 1.0), seed=task["seed"])
        except PlannerError as exc:
            rows.append({**base, "found": False, "reason": str(exc), "length": None,
                         "length_smoothed": None, "cell_checks": 0, "expansions": 0,
                         "seconds": time.perf_counter() - t0, "peak_bytes": 0,
                         "clearance": None, "collision_free": None})
            continue
        row = {**base, "found": res.found, "reason": res.reason, "cell_checks": res.cell_checks,
               "expansions": res.expansions, "seconds": res.seconds,
               "peak_bytes": res.peak_bytes, "length": None, "length_smoothed": None,
               "clearance": None, "collision_free": None}
        if res.found:
            raw = res.path
            if task["method"].startswith("ompl:"):
                raw_path = np.asarray(res.extra.get("path_raw", raw), dtype=float).reshape(-1, 3)
                smooth = raw
                raw = raw_path if len(raw_path) > 1 else raw
            elif task["method"] in ("astar", "dijkstra"):
                cells = search.shortcut(world, res.cells)
                smooth = np.concatenate([raw[:1], world.to_map(world.lattice.to_world(cells)),
                                         raw[-1:]])
            else:
                smooth = raw
            c_raw = clear.of_path(raw, step)
            c_smooth = clear.of_path(smooth, step)
            tol = 1e-9 * max(1.0, world.lattice.covering_radius)
            row.update(length=path_length(raw), length_smoothed=path_length(smooth),
                       clearance=min(c_raw, c_smooth),
                       collision_free=bool(min(c_raw, c_smooth) >= task["radius"] - tol),
                       waypoints=len(raw))
        rows.append(row)
    return rows
