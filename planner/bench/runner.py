"""Running a suite: tasks fan out to local processes or a Dask cluster; every finished row
is appended to ``results.jsonl`` at once, so a killed run loses nothing finished and
``resume`` skips what is done.

Ctrl-C (SIGINT) and SIGTERM cancel the pending work and stop the workers: :func:`run`
raises :class:`~planner.bench.stopping.Interrupted` after the finished rows are on disk.
"""

from __future__ import annotations

import contextlib
import json
import os
from concurrent.futures import ProcessPoolExecutor, as_completed
from multiprocessing import get_context
from pathlib import Path

from planner.bench.rows import drop_partial_line, read_rows, row_key
from planner.bench.stopping import (
    Interrupted,
    interruption,
    signals_raise,
    stop_processes,
    worker_init,
)
from planner.bench.task import run_task
from planner.errors import PlannerError
from planner.progress import Progress

__all__ = ["run"]


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
    drop_partial_line(out)
    done = {row_key(r) for r in read_rows(out)}
    todo = []
    for t in tasks:
        left = [q for q in t["queries"]
                if row_key({**t, "query": q["id"]}) not in done]
        if left:
            todo.append({**t, "queries": left})
    total = sum(len(t["queries"]) for t in todo)
    bar = Progress(total, "runs", enabled=progress, quiet=0.0)
    with open(out, "a") as f, signals_raise():
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
        except (Interrupted, SystemError) as exc:
            stop = interruption(exc)
            if stop is None:
                raise
            stop_processes(stop.processes)  # local workers and their own workers (OMPL)
            if stop is exc:
                raise
            raise stop from None
        finally:
            bar.close()
    return read_rows(out)


def _run_pool(todo: list[dict], jobs: int, write) -> None:
    # not multiprocessing.Pool: its daemonic workers may not start OMPL's worker processes
    ex = ProcessPoolExecutor(max_workers=jobs, mp_context=get_context("spawn"),
                             initializer=worker_init)
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

    try:
        client = Client(scheduler, timeout="20s")
    except (OSError, TimeoutError, ValueError) as exc:
        raise PlannerError(f"--scheduler {scheduler}: cannot connect to the Dask scheduler: "
                           f"{' '.join(str(exc).split()) or type(exc).__name__}") from None
    with client:
        futs = client.map(run_task, todo, pure=False)
        try:
            for fut, rows in dask_completed(futs, with_results=True, raise_errors=False):
                if fut.status == "error" and isinstance(rows, BaseException):
                    raise rows  # the task's own error, as a local run would raise it
                if fut.status != "finished" or not isinstance(rows, list):
                    # cancelled: the scheduler or the worker holding it went away
                    raise PlannerError(f"--scheduler {scheduler}: a task was lost ("
                                       f"{fut.status}: {type(rows).__name__}); the scheduler "
                                       f"or its workers stopped; finished rows are saved, "
                                       f"--resume runs the rest")
                write(rows)
        except BaseException:
            with contextlib.suppress(Exception):
                client.cancel(futs)
            raise
