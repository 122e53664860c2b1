"""Running a suite: tasks fan out to local processes or a Dask cluster; every finished row
is appended to ``results.jsonl`` at once, so a killed run loses nothing finished and
``resume`` skips what is done.

Ctrl-C (SIGINT) and SIGTERM cancel the pending work and stop the workers: :func:`run`
raises :class:`Interrupted` after the finished rows are on disk.
"""

from __future__ import annotations

import contextlib
import json
import os
import signal
import sys
import time
from concurrent.futures import ProcessPoolExecutor, as_completed
from multiprocessing import get_context
from pathlib import Path

import numpy as np

from planner.bench.queries import sample_queries, scenario_queries
from planner.bench.rotations import IDENTITY_XYZW
from planner.bench.suite import Suite
from planner.errors import PlannerError
from planner.path import path_length

_WORLDS: dict = {}
_CLEARANCE: dict = {}
LATTICE_METHODS = ("astar", "dijkstra", "theta", "lazy-theta")


def _frame(map_path: str):
    from planner.bench.worlds import cached_frame

    return cached_frame(map_path)


def _world(task: dict):
    """Per-process cache: a worker builds (or loads, see
    :func:`planner.bench.worlds.cached_world`) each world once for all its queries."""
    from planner.bench.worlds import cached_world

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
    from planner.bench.metrics import Clearance

    if map_path not in _CLEARANCE:
        _CLEARANCE.clear()
        o = _frame(map_path).obstacles
        _CLEARANCE[map_path] = Clearance(o.points, o.boxes, o.box_sizes)
    return _CLEARANCE[map_path]


def row_key(r: dict) -> str:
    """One run: map, resolution, radius, rotation (0 for rows of unrotated suites), lattice,
    neighbours, method, seed and query."""
    return "|".join(str(r.get(k, 0)) if k == "rotation" else str(r[k])
                    for k in ("map", "cell_volume", "radius", "rotation", "lattice",
                              "neighbors", "method", "seed", "query"))


def run_task(task: dict) -> list[dict]:
    """Run one task (a world configuration, a method and a batch of queries).

    A plain function of plain data so that it pickles to processes and Dask workers.
    """
    from planner import planning as api
    from planner import search
    from planner.analysis.metadata import row_commit

    if task["method"] == "explore":  # a robot sensing its way, not one planned path
        from planner.bench.explore_rows import explore_rows

        return explore_rows(task)
    world = _world(task)
    clear = _clearance(task["map"])
    step = 0.25 * world.lattice.packing_radius
    rows = []
    for q in task["queries"]:
        base = {k: task[k] for k in ("suite", "map", "cell_volume", "radius", "lattice",
                                     "neighbors", "method", "seed")}
        base.update(commit=row_commit(), rotation=task.get("rotation", 0),
                    quaternion_xyzw=list(task.get("quaternion_xyzw", IDENTITY_XYZW)))
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
            row.update(length=path_length(raw), length_smoothed=path_length(smooth),
                       clearance=min(c_raw, c_smooth),
                       collision_free=bool(min(c_raw, c_smooth) >= task["radius"] - tol),
                       waypoints=len(raw))
        rows.append(row)
    return rows


def _build_cached(spec: tuple) -> None:
    """Build one world into the cache (a pool task: the world stays in its file)."""
    from planner.bench.worlds import cached_world

    cached_world(*spec)


def _prebuild(specs: list[tuple], jobs: int) -> None:
    """Build the worlds the query sampler needs in ``jobs`` processes, into the cache.

    SIGINT / SIGTERM raise :class:`Interrupted` and stop the builders at once (finished
    worlds stay in the cache for ``--resume``).
    """
    ex = ProcessPoolExecutor(max_workers=jobs, mp_context=get_context("spawn"),
                             initializer=_worker_init)
    try:
        with _signals_raise():
            for fut in as_completed([ex.submit(_build_cached, s) for s in specs]):
                fut.result()
    except Interrupted as exc:
        ex.shutdown(wait=False, cancel_futures=True)
        _stop(exc.processes)
        raise
    ex.shutdown()


def plan_tasks(suite: Suite, log=print, saved: dict | None = None,
               world_cache: str | None = None, jobs: int = 1) -> tuple[list[dict], dict]:
    """Expand a suite into tasks; sample the queries once per map x volume x radius x
    rotation group.

    ``world_cache``: a folder where the worlds built for sampling are kept for the workers
    (:func:`planner.bench.worlds.cached_world`); None builds them again in every process.
    With it and ``jobs`` > 1 the sampler's worlds are built in ``jobs`` processes first.

    ``saved`` is a record returned earlier (kept in ``queries.json`` beside the results):
    its groups' queries are reused as they are, so ``--resume`` does not sample again.

    Returns the tasks and, per group, the query record (kept, dropped by reason, queries).
    """
    from planner.bench.rotations import sample_rotations
    from planner.bench.worlds import cached_world, map_frame

    rotated = suite.rotation != "none"
    quats = sample_rotations(suite.rotation, suite.rotations, seed=suite.seed)
    tasks, record = [], {}
    def group_name(m, cv, radius, ri):
        return f"{Path(m.path).name} cell {cv:g} m^3 radius {radius:g} m" + (
            f" rotation {ri}" if rotated else "")

    n_wanted = {m.path: m.queries or suite.queries for m in suite.maps}
    for m in suite.maps:
        frame = map_frame(m.path) if not m.scenarios else None
        if world_cache and jobs > 1 and not m.scenarios:
            specs = [(world_cache, m.path, lat, cv, radius, tuple(q.tolist()))
                     for cv in m.cell_volumes for radius in m.radii
                     for ri, q in enumerate(quats)
                     if (saved or {}).get(group_name(m, cv, radius, ri), {}).get("wanted")
                     != n_wanted[m.path]
                     for lat in suite.lattices]
            if specs:
                log(f"building {len(specs)} worlds of {Path(m.path).name} in {jobs} "
                    f"processes ...")
                _prebuild(specs, jobs)
        for cv in m.cell_volumes:
            for radius in m.radii:
                for ri, quat in enumerate(quats):
                    group = group_name(m, cv, radius, ri)
                    common = {"suite": suite.name, "map": m.path, "cell_volume": cv,
                              "radius": radius, "rotation": ri,
                              "quaternion_xyzw": quat.tolist(),
                              "rotated": rotated, "world_cache": world_cache}
                    n = m.queries or suite.queries
                    old = (saved or {}).get(group)
                    if (old and old.get("wanted") == n and "queries" in old
                            and old.get("frame") == "map" and "quaternion_xyzw" in old):
                        record[group] = old
                        tasks += _group_tasks(suite, common, old["queries"])
                        continue
                    if m.scenarios:
                        if rotated:
                            raise PlannerError(f"{m.scenarios}: scenario queries cannot be "
                                               f"rotated; use rotation = \"none\"")
                        s, g, costs = scenario_queries(m.scenarios, n, suite.seed)
                        dropped = {}
                    else:
                        log(f"sampling {n} queries for {group} ...")
                        worlds = {lat: cached_world(world_cache, m.path, lat, cv, radius,
                                                    tuple(quat.tolist()))
                                  for lat in suite.lattices}
                        s, g, dropped = sample_queries(worlds, frame.bounds, n, suite.seed,
                                                       suite.min_distance, free=frame.free)
                        costs = [None] * len(s)
                    queries = [{"id": i, "start": s[i].tolist(), "goal": g[i].tolist(),
                                "optimal_cost": None if costs[i] is None else float(costs[i])}
                               for i in range(len(s))]
                    record[group] = {"kept": len(s), "wanted": n, "dropped": dropped,
                                     "frame": "map",
                                     "queries": queries, "map": m.path, "cell_volume": cv,
                                     "radius": radius, "rotation": ri,
                                     "quaternion_xyzw": quat.tolist()}
                    tasks += _group_tasks(suite, common, queries)
    return tasks, record


def _group_tasks(suite: Suite, common: dict, queries: list[dict]) -> list[dict]:
    tasks = []
    for lat in suite.lattices:
        for nb in suite.neighbors:
            for meth in suite.methods:
                head = {**common, "lattice": lat, "neighbors": nb, "method": meth, "seed": 0}
                if meth == "explore":  # one long run per task
                    tasks += _split({**head, "explore": suite.explore}, queries, size=1)
                else:
                    tasks += _split(head, queries)
    for planner_name in suite.ompl_planners:
        for seed in suite.ompl_seeds:
            tasks += _split({**common, "lattice": suite.ompl_lattice,
                             "neighbors": "-", "method": f"ompl:{planner_name}",
                             "seed": seed, "ompl_time": suite.ompl_time},
                            queries, size=2)
    return tasks


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


def unique_rows(rows: list[dict]) -> list[dict]:
    """One row per run key (the last one written), in first-seen order.

    >>> r = {"map": "m", "cell_volume": 1, "radius": 0, "lattice": "fcc", "neighbors": "full",
    ...      "method": "astar", "seed": 0, "query": 3}
    >>> len(unique_rows([r, dict(r), {**r, "query": 4}]))
    2
    """
    by: dict[str, dict] = {}
    for r in rows:
        by[row_key(r)] = r
    return list(by.values())


class _Progress:
    """Progress on stderr: a redrawn bar on a terminal, a line per ~10% otherwise (logs)."""

    def __init__(self, total: int, enabled: bool, stream=None):
        self.stream = stream or sys.stderr
        self.total, self.done, self.enabled, self.t0 = total, 0, enabled, time.perf_counter()
        self.tty = enabled and self.stream.isatty()
        self.next_tenth = 1

    def step(self, k: int) -> None:
        self.done += k
        if not self.enabled:
            return
        frac = self.done / max(self.total, 1)
        el = time.perf_counter() - self.t0
        eta = el / frac - el if frac > 0 else 0.0
        text = f"{self.done}/{self.total} runs  {el:5.0f}s  eta {eta:4.0f}s"
        if self.tty:
            bar = "#" * int(30 * frac)
            print(f"\r[{bar:<30}] {text}", end="", file=self.stream, flush=True)
        elif frac * 10 >= self.next_tenth:
            self.next_tenth = int(frac * 10) + 1
            print(f"progress {frac:4.0%}: {text}", file=self.stream, flush=True)

    def close(self) -> None:
        if self.tty:
            print(file=self.stream)


def _drop_partial_line(path: Path) -> None:
    """Cut a last line left unfinished by a kill, so that appended rows start on a line."""
    if not path.is_file() or path.stat().st_size == 0:
        return
    with open(path, "rb+") as f:
        data = f.read()
        if data.endswith(b"\n"):
            return
        f.truncate(data.rfind(b"\n") + 1)


class Interrupted(Exception):
    """The run was stopped by SIGINT or SIGTERM; finished rows are saved."""

    def __init__(self, signum: int, processes: list | None = None):
        super().__init__(f"interrupted by {signal.Signals(signum).name}")
        self.signum = signum
        self.processes = processes or []  # every descendant when the signal came

    @property
    def exit_code(self) -> int:
        """128 + the signal number: 130 for SIGINT, 143 for SIGTERM."""
        return 128 + self.signum


@contextlib.contextmanager
def _signals_raise():
    """Turn SIGINT and SIGTERM into :class:`Interrupted` while the block runs."""
    def handler(signum, frame):
        for s in (signal.SIGINT, signal.SIGTERM):  # a second signal must not interrupt cleanup
            signal.signal(s, signal.SIG_IGN)
        # the whole tree now: once the pool's workers die, their own children (an OMPL
        # worker) are re-parented and could no longer be found
        raise Interrupted(signum, _descendants())

    old = {s: signal.signal(s, handler) for s in (signal.SIGINT, signal.SIGTERM)}
    try:
        yield
    finally:
        for s, h in old.items():
            signal.signal(s, h)


def _descendants() -> list:
    try:
        import psutil
    except ImportError:  # pragma: no cover - psutil comes with dask[distributed]
        return []
    out = []
    for p in psutil.Process().children(recursive=True):
        with contextlib.suppress(psutil.Error):
            # multiprocessing's resource tracker ends by itself with this process; killing it
            # makes it print a traceback
            if not any("resource_tracker" in part for part in p.cmdline()):
                out.append(p)
    return out


def _stop(processes: list, wait: float = 2.0) -> None:
    """Kill ``processes`` (psutil) and wait up to ``wait`` s until they are gone.

    SIGKILL, not SIGTERM: workers hold no output (every finished row is already on disk), and
    an OMPL worker forked by a forkserver prints a traceback when terminated.  Never reaps
    them (no ``wait()``): multiprocessing reaps its own workers, and a worker reaped behind
    its back looks alive to it forever.
    """
    import psutil

    def alive(p) -> bool:
        try:
            return p.is_running() and p.status() != psutil.STATUS_ZOMBIE
        except psutil.Error:
            return False

    for p in processes:
        with contextlib.suppress(psutil.Error):
            p.kill()
    deadline = time.monotonic() + wait
    while time.monotonic() < deadline and any(alive(p) for p in processes):
        time.sleep(0.05)


def _worker_init() -> None:
    """Workers leave signals to the parent, which stops them (a terminal's Ctrl-C reaches the
    whole process group)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)


def run(tasks: list[dict], out: Path, *, jobs: int = 1, scheduler: str | None = None,
        resume: bool = True, progress: bool = True) -> list[dict]:
    """Execute tasks, appending each finished row to ``out`` (JSON lines).

    With ``resume`` rows already in ``out`` are skipped; without it ``out`` is restarted.
    Returns all rows of the file afterwards.

    Raises
    ------
    Interrupted
        On SIGINT / SIGTERM: pending work is cancelled, local workers are terminated (Dask
        futures cancelled) and every row finished so far is on disk.
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
    with open(out, "a") as f, _signals_raise():
        def write(rows: list[dict]) -> None:
            for r in rows:
                f.write(json.dumps(r) + "\n")
            f.flush()
            os.fsync(f.fileno())
            bar.step(len(rows))

        try:
            if scheduler:
                _run_dask(todo, scheduler, write)
            elif jobs <= 1:
                for t in todo:
                    write(run_task(t))
            else:
                _run_pool(todo, jobs, write)
        except Interrupted as exc:
            _stop(exc.processes)  # local workers and their own workers (OMPL)
            raise
        finally:
            bar.close()
    return read_rows(out)


def _run_pool(todo: list[dict], jobs: int, write) -> None:
    # not multiprocessing.Pool: its daemonic workers may not start OMPL's worker processes
    ex = ProcessPoolExecutor(max_workers=jobs, mp_context=get_context("spawn"),
                             initializer=_worker_init)
    try:
        futs = [ex.submit(run_task, t) for t in todo]
        for fut in as_completed(futs):
            write(fut.result())
    except BaseException:
        ex.shutdown(wait=False, cancel_futures=True)  # running ones are stopped by the caller
        raise
    ex.shutdown()


def _run_dask(todo: list[dict], scheduler: str, write) -> None:
    from distributed import Client
    from distributed import as_completed as dask_completed

    with Client(scheduler) as client:
        futs = client.map(run_task, todo, pure=False)
        try:
            for _, rows in dask_completed(futs, with_results=True):
                write(rows)
        except BaseException:
            client.cancel(futs)
            raise
