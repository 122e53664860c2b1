"""One ``planner bench`` run: read the suite, lock the results folder, sample (or reuse) the
queries, run, and write the summary, figures and report.

Rows are appended to ``OUT/results.jsonl`` as they finish; ``resume`` skips finished runs
and reuses the queries saved in ``OUT/queries.json``.  Ctrl-C or SIGTERM stops the run
cleanly: a report flagged *partial* is written and the exit status is 130 / 143.
"""

from __future__ import annotations

import contextlib
import fcntl
import json
import os
import sys
from collections.abc import Iterator
from pathlib import Path

from planner.bench import rows as rowfile
from planner.bench import runner, summary
from planner.bench.run_folder import (
    MARKER,
    check_folder,
    check_saved_queries,
    remove_world_cache,
    write_marker,
)
from planner.bench.stopping import Interrupted
from planner.bench.suite import Suite, SuiteError, load_suite
from planner.bench.tasks import plan_tasks
from planner.errors import PlannerError
from planner.export.arena import write_arena_db
from planner.fsutil import write_text_atomic

__all__ = ["run_suite"]


@contextlib.contextmanager
def results_lock(out: Path) -> Iterator[None]:
    """Hold an exclusive lock on the results folder ``out`` (``out/.lock``).

    Raises
    ------
    PlannerError
        Another run holds it (one line, with that run's process id).
    """
    created = not out.exists()
    out.mkdir(parents=True, exist_ok=True)
    try:  # made here, or left by an earlier run
        fd = os.open(out / ".lock", os.O_RDWR | os.O_CREAT | os.O_EXCL, 0o644)
        made_lock = True
    except FileExistsError:
        fd = os.open(out / ".lock", os.O_RDWR)
        made_lock = False
    held = refused = False
    try:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            other = os.pread(fd, 32, 0).decode(errors="replace").strip() or "?"
            raise PlannerError(f"{out}: results folder in use by another planner bench run "
                               f"(pid {other}); wait for it or use another --out") from None
        held = True
        os.ftruncate(fd, 0)
        os.pwrite(fd, str(os.getpid()).encode(), 0)
        yield
    except (PlannerError, OSError):
        refused = True
        raise
    finally:
        if held and refused:
            # a run refused before any result leaves nothing of its own behind (the world
            # cache and its marker included: an edited suite is another suite)
            with contextlib.suppress(OSError):
                if created and not (out / "results.jsonl").exists():
                    remove_world_cache(out / "worlds")
                    (out / MARKER).unlink(missing_ok=True)
                if made_lock or [q.name for q in out.iterdir()] == [".lock"]:
                    os.unlink(out / ".lock")
                if created:
                    out.rmdir()  # only when empty
        os.close(fd)  # closing releases the lock


def _paper(suite: Suite, out: Path, jobs: int) -> int:
    from planner.analysis.paper import reproduce  # lazy: numba, scipy

    args = dict(suite.paper)
    if "volumes" in args:
        args["volumes"] = tuple(float(v) for v in args["volumes"])
    return reproduce(out, jobs=jobs, **args)


def _why_empty(rec: dict) -> str:
    """Why a query group kept no query, from its sampler record (one line)."""
    why = ", ".join(f"{k} {v}" for k, v in rec.get("dropped", {}).items()) or "none"
    return f"of {rec.get('wanted')} wanted; dropped: {why}"


def run_suite(name: str, *, out: str | None = None, jobs: int = 1,
              scheduler: str | None = None, resume: bool = False, progress: bool = True,
              report_only: bool = False, force: bool = False) -> int:
    """Run the suite ``name`` (bundled name or TOML path); returns the exit status.

    0 when the suite completed, 130 / 143 after SIGINT / SIGTERM (partial report written).
    A folder that already holds results needs ``resume`` (keep them, run the rest) or
    ``force`` (start again).

    Raises
    ------
    PlannerError
        Unreadable suite, no map files, a results folder in use, nothing to report.
    """
    suite = load_suite(name)
    folder = Path(out) if out else Path("results") / suite.name  # a label, never a path
    if jobs < 1:
        raise SuiteError(f"--jobs must be at least 1, got {jobs}")
    # before the lock file: a folder that is not this suite's run is refused untouched
    check_folder(folder, suite, resume=resume or report_only, force=force)
    if suite.kind == "paper":
        with results_lock(folder):
            check_folder(folder, suite, resume=resume or report_only, force=force)
            write_marker(folder, suite)
            return _paper(suite, folder, jobs)
    if not suite.maps:
        raise SuiteError(f"suite {suite.name}: no map files found "
                         f"(skipped: {', '.join(suite.skipped) or 'none'})")
    log = (lambda m: print(m, file=sys.stderr)) if progress else (lambda m: None)
    with results_lock(folder):
        check_folder(folder, suite, resume=resume or report_only, force=force)
        results = folder / "results.jsonl"
        if (results.is_file() and results.stat().st_size and not
                (resume or force or report_only)):
            raise SuiteError(f"{folder} already holds results; pass --resume to keep them "
                             "and run the rest, or --force to start again")
        if resume or report_only:
            rowfile.read_rows(results)  # every row checked before anything runs
        write_marker(folder, suite)
        saved_path = folder / "queries.json"
        saved = None
        if (resume or report_only) and saved_path.is_file():
            try:
                saved = json.loads(saved_path.read_text())
            except (ValueError, RecursionError):
                saved = None  # a damaged record: sample again (seeded: the same queries)
            else:
                check_saved_queries(saved_path, saved)
        try:
            tasks, record = plan_tasks(suite, log=log, saved=saved,
                                       world_cache=str(folder / "worlds"),
                                       jobs=1 if scheduler else jobs, progress=progress)
        except Interrupted as exc:  # while building worlds: nothing run yet
            print(f"\nplanner bench: {exc} while building the worlds; built ones are kept "
                  f"in {folder / 'worlds'} for --resume", file=sys.stderr)
            return exc.exit_code
        empty = [g for g, r in record.items() if not r.get("queries")]
        if len(empty) == len(record):  # nothing to run: refused, leaving nothing behind
            raise SuiteError(f"suite {suite.name}: no query kept for {empty[0]} "
                             f"({_why_empty(record[empty[0]])}); lower min_distance or "
                             "check the map")
        for g in empty:  # a finding (e.g. inflation closes every door), not a failure
            print(f"WARNING: no query kept for {g} ({_why_empty(record[g])}); it is left "
                  "out of the comparisons and listed in the report", file=sys.stderr)
        write_text_atomic(saved_path, json.dumps(record, indent=1))
        results = folder / "results.jsonl"
        interrupted = None
        if report_only:
            rows = rowfile.read_rows(results)
            if not rows:
                raise PlannerError(f"{results}: no finished runs to report")
        else:
            try:
                rows = runner.run(tasks, results, jobs=jobs, scheduler=scheduler,
                                  resume=resume, progress=progress)
            except Interrupted as exc:
                interrupted = exc
                rows = rowfile.read_rows(results)
        rows = rowfile.unique_rows(rows)
        wanted = {rowfile.row_key({**t, "query": q["id"]}) for t in tasks for q in t["queries"]}
        missing = len(wanted - {rowfile.row_key(r) for r in rows})
        summ = summary.summarize(rows) if rows else []
        summary.write_csv(folder / "summary.csv", summ)
        write_arena_db(folder / "planner_arena.db", rows, suite=suite.name)  # Planner Arena
        # figures take seconds: an interrupted run leaves them to --report-only
        figs = summary.plot(rows, folder) if rows and interrupted is None else []
        cmd = f"planner bench {name}" + (f" --out {out}" if out else "")
        partial = None
        if missing:
            why = str(interrupted) if interrupted else "runs missing from results.jsonl"
            partial = (f"{why}: {len(wanted) - missing} of {len(wanted)} runs finished; "
                       f"`{cmd} --resume` completes it")
        rep = summary.write_report(folder, suite, rows, summ, record, figs, cmd,
                                   partial=partial, jobs=jobs)
    if not partial:  # the worlds are only kept for --resume
        remove_world_cache(folder / "worlds")
    if interrupted is not None:
        print(f"\nplanner bench: {partial}; partial report: {rep}", file=sys.stderr)
        return interrupted.exit_code
    print(summary.format_summary(summ))
    print(f"\nreport: {rep}" + (f" (PARTIAL: {partial})" if partial else ""))
    return 0
