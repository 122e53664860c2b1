"""Running a suite: tasks fan out to local processes or a Dask cluster; every finished row
is appended to ``results.jsonl`` at once, so a killed run loses nothing finished and
``resume`` skips what is done."""

from __future__ import annotations

import json
import math
import os
import sys
import time
from concurrent.futures import ProcessPoolExecutor, as_completed
from multiprocessing import get_context
from pathlib import Path

import numpy as np

from planner.bench.queries import sample_queries, scenario_queries
from planner.bench.suite import Suite
from planner.errors import PlannerError

_WORLDS: dict = {}
_CLEARANCE: dict = {}
LATTICE_METHODS = ("astar", "dijkstra", "theta", "lazy-theta")


def _world(map_path: str, lattice: str, cell_volume: float, radius: float):
    """Per-process cache: a worker builds each world once for all its queries."""
    from planner.api import build_world

    key = (map_path, lattice, cell_volume, radius)
    if key not in _WORLDS:
        if len(_WORLDS) > 12:
            _WORLDS.clear()
        _WORLDS[key] = build_world(map_path, lattice, cell_volume=cell_volume, radius=radius)
    return _WORLDS[key]


def _clearance(map_path: str, obstacles):
    from planner.bench.metrics import Clearance

    if map_path not in _CLEARANCE:
        _CLEARANCE.clear()
        _CLEARANCE[map_path] = Clearance(obstacles.points, obstacles.boxes, obstacles.box_size)
    return _CLEARANCE[map_path]


def row_key(r: dict) -> str:
    return "|".join(str(r[k]) for k in ("map", "cell_volume", "radius", "lattice",
                                        "neighbors", "method", "seed", "query"))


def _path_length(p: np.ndarray) -> float:
    return float(np.linalg.norm(np.diff(p, axis=0), axis=1).sum()) if len(p) > 1 else math.nan


def run_task(task: dict) -> list[dict]:
    """Run one task (a world configuration, a method and a batch of queries).

    A plain function of plain data so that it pickles to processes and Dask workers.
    """
    from planner import api, search

    world = _world(task["map"], task["lattice"], task["cell_volume"], task["radius"])
    clear = _clearance(task["map"], world.obstacles)
    step = 0.25 * world.lattice.packing_radius
    rows = []
    for q in task["queries"]:
        base = {k: task[k] for k in ("suite", "map", "cell_volume", "radius", "lattice",
                                     "neighbors", "method", "seed")}
        base.update(query=q["id"], start=q["start"], goal=q["goal"],
                    optimal_cost=q.get("optimal_cost"))
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
                smooth = np.concatenate([raw[:1], world.lattice.to_world(cells), raw[-1:]])
            else:
                smooth = raw
            c_raw = clear.of_path(raw, step)
            c_smooth = clear.of_path(smooth, step)
            tol = 1e-9 * max(1.0, world.lattice.covering_radius)
            row.update(length=_path_length(raw), length_smoothed=_path_length(smooth),
                       clearance=min(c_raw, c_smooth),
                       collision_free=bool(min(c_raw, c_smooth) >= task["radius"] - tol),
                       waypoints=len(raw))
        rows.append(row)
    return rows


def plan_tasks(suite: Suite, log=print) -> tuple[list[dict], dict]:
    """Expand a suite into tasks; sample the queries once per map x volume x radius group.

    Returns the tasks and, per group, the query-sampling record (kept, dropped by reason).
    """
    from planner.api import build_world

    tasks, record = [], {}
    for m in suite.maps:
        for cv in m.cell_volumes:
            for radius in m.radii:
                group = f"{Path(m.path).name} cell {cv:g} m^3 radius {radius:g} m"
                n = m.queries or suite.queries
                if m.scenarios:
                    s, g, costs = scenario_queries(m.scenarios, n, suite.seed)
                    dropped = {}
                else:
                    log(f"sampling {n} queries for {group} ...")
                    worlds = {lat: build_world(m.path, lat, cell_volume=cv, radius=radius)
                              for lat in suite.lattices}
                    bounds = next(iter(worlds.values())).bounds
                    s, g, dropped = sample_queries(worlds, bounds, n, suite.seed,
                                                   suite.min_distance)
                    costs = [None] * len(s)
                record[group] = {"kept": len(s), "wanted": n, "dropped": dropped}
                queries = [{"id": i, "start": s[i].tolist(), "goal": g[i].tolist(),
                            "optimal_cost": None if costs[i] is None else float(costs[i])}
                           for i in range(len(s))]
                common = {"suite": suite.name, "map": m.path, "cell_volume": cv,
                          "radius": radius}
                for lat in suite.lattices:
                    for nb in suite.neighbors:
                        for meth in suite.methods:
                            tasks += _split({**common, "lattice": lat, "neighbors": nb,
                                             "method": meth, "seed": 0}, queries)
                for planner_name in suite.ompl_planners:
                    for seed in suite.ompl_seeds:
                        tasks += _split({**common, "lattice": suite.ompl_lattice,
                                         "neighbors": "-", "method": f"ompl:{planner_name}",
                                         "seed": seed, "ompl_time": suite.ompl_time},
                                        queries, size=2)
    return tasks, record


def _split(head: dict, queries: list[dict], size: int = 8) -> list[dict]:
    return [{**head, "queries": queries[i:i + size]} for i in range(0, len(queries), size)]


def read_rows(path: Path) -> list[dict]:
    """Rows of a results file; a line cut short by a kill is ignored."""
    rows = []
    if path.is_file():
        for line in path.read_text().splitlines():
            try:
                rows.append(json.loads(line))
            except ValueError:
                continue
    return rows


class _Progress:
    def __init__(self, total: int, enabled: bool):
        self.total, self.done, self.enabled, self.t0 = total, 0, enabled, time.perf_counter()

    def step(self, k: int) -> None:
        self.done += k
        if not self.enabled:
            return
        frac = self.done / max(self.total, 1)
        el = time.perf_counter() - self.t0
        eta = el / frac - el if frac > 0 else 0.0
        bar = "#" * int(30 * frac)
        print(f"\r[{bar:<30}] {self.done}/{self.total} runs  {el:5.0f}s  eta {eta:4.0f}s",
              end="", file=sys.stderr, flush=True)

    def close(self) -> None:
        if self.enabled:
            print(file=sys.stderr)


def _drop_partial_line(path: Path) -> None:
    """Cut a last line left unfinished by a kill, so that appended rows start on a line."""
    if not path.is_file() or path.stat().st_size == 0:
        return
    with open(path, "rb+") as f:
        data = f.read()
        if data.endswith(b"\n"):
            return
        f.truncate(data.rfind(b"\n") + 1)


def run(tasks: list[dict], out: Path, *, jobs: int = 1, scheduler: str | None = None,
        resume: bool = True, progress: bool = True) -> list[dict]:
    """Execute tasks, appending each finished row to ``out`` (JSON lines).

    With ``resume`` rows already in ``out`` are skipped; without it ``out`` is restarted.
    Returns all rows of the file afterwards.
    """
    out.parent.mkdir(parents=True, exist_ok=True)
    if not resume and out.exists():
        out.unlink()
    _drop_partial_line(out)
    done = {row_key(r) for r in read_rows(out)}
    todo = []
    for t in tasks:
        left = [q for q in t["queries"]
                if row_key({**t, "query": q["id"]}) not in done]
        if left:
            todo.append({**t, "queries": left})
    total = sum(len(t["queries"]) for t in todo)
    bar = _Progress(total, progress)
    with open(out, "a") as f:
        def write(rows: list[dict]) -> None:
            for r in rows:
                f.write(json.dumps(r) + "\n")
            f.flush()
            os.fsync(f.fileno())
            bar.step(len(rows))

        if scheduler:
            from distributed import Client
            from distributed import as_completed as dask_completed

            with Client(scheduler) as client:
                futs = client.map(run_task, todo, pure=False)
                for _, rows in dask_completed(futs, with_results=True):
                    write(rows)
        elif jobs <= 1:
            for t in todo:
                write(run_task(t))
        else:
            with ProcessPoolExecutor(max_workers=jobs, mp_context=get_context("spawn")) as ex:
                futs = [ex.submit(run_task, t) for t in todo]
                for fut in as_completed(futs):
                    write(fut.result())
    bar.close()
    return read_rows(out)
