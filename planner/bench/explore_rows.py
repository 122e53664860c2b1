"""Exploration in the benchmark suite: ``methods = ["explore"]`` runs
:func:`planner.explore.explore` on each sampled query of every map, rotation, lattice and
neighbour set, with the sensor of the suite's optional ``[explore]`` table::

    methods = ["astar", "explore"]

    [explore]
    sensor_range = 4.0        # m
    fov = [360.0, 30.0]       # horizontal total, vertical +- (degrees)
    resolution = 3.0          # degrees between rays
    max_steps = 5000          # moves before giving up (status "budget")

A row holds the run's outcome (``status``; ``found`` when the goal was reached), the
distance travelled (m), moves, replans, the explorer's replanner (``replanner``, the
default of :func:`planner.explore.explore`) and the replans that searched (``searched``;
the others kept their path), mismatches (replanned costs that differ from A* from scratch
on the same map state: must be 0) and contacts, and per replan (after the first plan,
which has nothing to reuse) the medians of the replanner's and from-scratch cell checks
and times and of their ratios. ``cell_checks``, ``expansions`` and ``seconds`` are the
replanner's totals over the run (``total_time_ratio``: against A* at every replan).
``length`` stays None: a travelled distance is not a planned path, so exploration rows
never enter the path-length ratios.

Rotations: as every row of a rotated suite, the robot explores the map in its own frame
on the lattice turned by R^T (:func:`planner.bench.worlds.rotated_lattice`), which is the
map turned by R against the lattice; point and box maps alike.
"""

from __future__ import annotations

import math
import time

import numpy as np

from planner.analysis.metadata import row_commit
from planner.bench.host import worker_host
from planner.bench.rotations import IDENTITY_XYZW
from planner.bench.worlds import cached_frame, rotated_lattice
from planner.errors import PlannerError

__all__ = ["EXPLORE_KEYS", "explore_rows", "check_explore_table"]

EXPLORE_KEYS = {"sensor_range": 4.0, "fov": [360.0, 30.0], "resolution": 3.0,
                "max_steps": 5000}
"""The ``[explore]`` table's keys and their defaults."""


def check_explore_table(table: dict) -> str | None:
    """None when ``table`` (the suite's ``[explore]``) is valid, else what is wrong."""
    extra = sorted(set(table) - set(EXPLORE_KEYS))
    if extra:
        return f"unknown key {extra[0]!r} in [explore] (known: {', '.join(EXPLORE_KEYS)})"
    r = table.get("sensor_range", 4.0)
    if isinstance(r, bool) or not isinstance(r, int | float) or not 0 < r < math.inf:
        return "'explore.sensor_range' must be a positive number of metres"
    fov = table.get("fov", [360.0, 30.0])
    if (not isinstance(fov, list) or len(fov) != 2
            or not all(isinstance(x, int | float) and not isinstance(x, bool) for x in fov)
            or not (0 < fov[0] <= 360 and 0 <= fov[1] <= 90)):
        return "'explore.fov' must be [horizontal, vertical] degrees, 0<h<=360, 0<=v<=90"
    res = table.get("resolution", 3.0)
    if isinstance(res, bool) or not isinstance(res, int | float) or not 0 < res <= 90:
        return "'explore.resolution' must be a number of degrees in (0, 90]"
    s = table.get("max_steps", 5000)
    if isinstance(s, bool) or not isinstance(s, int) or not 1 <= s <= 10**7:
        return "'explore.max_steps' must be an integer in 1..10000000"
    return None


def _setting(task: dict):
    """The map the robot explores, its bounds (m) and the task's (turned) lattice."""
    frame = cached_frame(task["map"])
    lat = rotated_lattice(task["lattice"], task["cell_volume"],
                          task.get("quaternion_xyzw", IDENTITY_XYZW))
    return frame.obstacles, frame.bounds, lat


def explore_rows(task: dict) -> list[dict]:
    """Rows of one exploration task (a world configuration and a batch of queries)."""
    from planner.explore import explore  # lazy: numba

    cfg = {**EXPLORE_KEYS, **task.get("explore", {})}
    rows = []
    for q in task["queries"]:
        base = {k: task[k] for k in ("suite", "map", "cell_volume", "radius", "lattice",
                                     "neighbors", "method", "seed")}
        base.update(commit=row_commit(), **worker_host(), rotation=task.get("rotation", 0),
                    quaternion_xyzw=list(task.get("quaternion_xyzw", IDENTITY_XYZW)),
                    query=q["id"], start=q["start"], goal=q["goal"],
                    optimal_cost=q.get("optimal_cost"), length=None, length_smoothed=None,
                    clearance=None, collision_free=None, peak_bytes=0,
                    sensor_range=cfg["sensor_range"], fov=list(cfg["fov"]),
                    resolution=cfg["resolution"])
        t0 = time.perf_counter()
        try:
            source, bounds, lat = _setting(task)
            r = explore(source, q["start"], q["goal"], lattice=lat, radius=task["radius"],
                        bounds=bounds, sensor_range=cfg["sensor_range"],
                        fov=tuple(cfg["fov"]), resolution=cfg["resolution"],
                        neighbors=task["neighbors"], max_steps=cfg["max_steps"])
        except PlannerError as exc:
            rows.append({**base, "found": False, "status": "error", "reason": str(exc),
                         "cell_checks": 0, "expansions": 0, "seconds": 0.0,
                         "run_seconds": time.perf_counter() - t0})
            continue
        rows.append({**base, **_figures(r), "run_seconds": time.perf_counter() - t0})
    return rows


def _figures(r) -> dict:
    """The row's numbers from an :class:`planner.explore.ExploreResult`."""
    k = slice(1, None) if r.replans > 1 else slice(None)

    def med(a) -> float | None:
        return float(np.median(a[k])) if len(a[k]) else None

    q = r.ratios()
    return {"found": r.status == "reached", "status": r.status,
            "reason": "" if r.status == "reached" else r.status,
            "distance": r.distance, "moves": len(r.trajectory) - 1, "replans": r.replans,
            "replanner": r.replanner, "searched": int(r.searched.sum()),
            "mismatches": r.mismatches, "contacts": r.contacts,
            "cell_checks": int(r.replan_checks.sum()),
            "expansions": int(r.replan_expansions.sum()),
            "seconds": float(r.replan_seconds.sum()),
            "astar_cell_checks": int(r.astar_checks.sum()),
            "astar_seconds": float(r.astar_seconds.sum()),
            "replan_checks_median": med(r.replan_checks),
            "replan_astar_checks_median": med(r.astar_checks),
            "replan_seconds_median": med(r.replan_seconds),
            "replan_astar_seconds_median": med(r.astar_seconds),
            **{k2: (v if math.isfinite(v) else None) for k2, v in q.items()}}
