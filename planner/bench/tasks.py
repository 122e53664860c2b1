"""A suite expanded into tasks: the queries are sampled once per map x cell volume x
radius x rotation group (or reused from an earlier run's record), then split into batches
for every lattice, neighbour set and method."""

from __future__ import annotations

from concurrent.futures import ProcessPoolExecutor, as_completed
from multiprocessing import get_context
from pathlib import Path

from planner.bench.queries import sample_queries, scenario_queries
from planner.bench.stopping import Interrupted, signals_raise, stop_processes, worker_init
from planner.bench.suite import Suite
from planner.errors import PlannerError
from planner.progress import Progress

__all__ = ["plan_tasks"]


def _build_cached(spec: tuple) -> None:
    """Build one world into the cache (a pool task: the world stays in its file)."""
    from planner.bench.worlds import cached_world  # lazy: scipy

    cached_world(*spec)


def _prebuild(specs: list[tuple], jobs: int, progress: bool = False) -> None:
    """Build the worlds the query sampler needs in ``jobs`` processes, into the cache.

    SIGINT / SIGTERM raise :class:`Interrupted` and stop the builders at once (finished
    worlds stay in the cache for ``--resume``).
    """
    ex = ProcessPoolExecutor(max_workers=jobs, mp_context=get_context("spawn"),
                             initializer=worker_init)
    try:
        with signals_raise(), Progress(len(specs), "worlds", label="building",
                                       enabled=progress) as bar:
            bar.step(0)
            for fut in as_completed([ex.submit(_build_cached, s) for s in specs]):
                fut.result()
                bar.step()
    except Interrupted as exc:
        ex.shutdown(wait=False, cancel_futures=True)
        stop_processes(exc.processes)
        raise
    ex.shutdown()


def plan_tasks(suite: Suite, log=print, saved: dict | None = None,
               world_cache: str | None = None, jobs: int = 1,
               progress: bool = False) -> tuple[list[dict], dict]:
    """Expand a suite into tasks; sample the queries once per map x volume x radius x
    rotation group.

    ``world_cache``: a folder where the worlds built for sampling are kept for the workers
    (:func:`planner.bench.worlds.cached_world`); None builds them again in every process.
    With it and ``jobs`` > 1 the sampler's worlds are built in ``jobs`` processes first.

    ``saved`` is a record returned earlier (kept in ``queries.json`` beside the results):
    its groups' queries are reused as they are, so ``--resume`` does not sample again.

    ``progress``: the worlds built (in the pool, then for sampling: one per lattice and
    group) with an ETA on stderr (:class:`planner.progress.Progress`).

    Returns the tasks and, per group, the query record (kept, dropped by reason, queries).
    """
    from planner.bench.rotations import sample_rotations  # lazy: scipy
    from planner.bench.worlds import cached_world, map_frame  # lazy: scipy

    rotated = suite.rotation != "none"
    quats = sample_rotations(suite.rotation, suite.rotations, seed=suite.seed)
    tasks, record = [], {}
    def group_name(m, cv, radius, ri):
        return f"{Path(m.path).name} cell {cv:g} m^3 radius {radius:g} m" + (
            f" rotation {ri}" if rotated else "")

    n_wanted = {m.path: m.queries or suite.queries for m in suite.maps}
    to_sample = sum(len(suite.lattices) for m in suite.maps if not m.scenarios
                    for cv in m.cell_volumes for radius in m.radii for ri in range(len(quats))
                    if not _reusable((saved or {}).get(group_name(m, cv, radius, ri)),
                                     n_wanted[m.path]))
    with Progress(to_sample, "worlds", label="sampling queries", enabled=progress) as bar:
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
                    with bar.paused():
                        log(f"building {len(specs)} worlds of {Path(m.path).name} in {jobs} "
                            f"processes ...")
                        _prebuild(specs, jobs, progress)
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
                        if _reusable(old, n):
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
                            with bar.paused():
                                log(f"sampling {n} queries for {group} ...")
                            bar.step(0)
                            worlds = {}
                            for lat in suite.lattices:
                                worlds[lat] = cached_world(world_cache, m.path, lat, cv, radius,
                                                           tuple(quat.tolist()))
                                bar.step()
                            nb = "full" if "full" in suite.neighbors else suite.neighbors[0]
                            s, g, dropped = sample_queries(worlds, frame.bounds, n, suite.seed,
                                                           suite.min_distance, free=frame.free,
                                                           neighbors=nb)
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


def _reusable(old: dict | None, n: int) -> bool:
    """A saved group record holds the queries to reuse (same number wanted, current form)."""
    return bool(old and old.get("wanted") == n and "queries" in old
                and old.get("frame") == "map" and "quaternion_xyzw" in old)


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
