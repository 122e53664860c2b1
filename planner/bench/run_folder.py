"""Which folders a suite run may write into, and what it may remove there.

A run folder holds a marker, ``.planner-bench.json``, written before anything else: the
suite's name and its digest (:func:`suite_digest`, a SHA-256 of every setting that
decides which runs a suite makes, map paths included). A run writes into a folder only when
it is absent, empty, or marked as a run of a suite; it keeps finished rows (``--resume``,
``--report-only``) only when the marker's digest is this suite's, so rows of an edited
suite are never reported as the new suite's. A folder that is not a run folder is refused
untouched (not even a lock file is made). At the end only the world cache files the runs
make (``worlds/<20 hex digits>.npz``) are removed, never the folder's other contents.
"""

from __future__ import annotations

import contextlib
import dataclasses
import hashlib
import json
import math
import re
from pathlib import Path

from planner.bench.rows import json_type
from planner.bench.schema import SuiteError
from planner.fsutil import write_text_atomic

__all__ = ["MARKER", "suite_digest", "check_folder", "write_marker", "check_saved_queries",
           "remove_world_cache"]

MARKER = ".planner-bench.json"
_WORLD_FILE = re.compile(r"[0-9a-f]{20}\.npz")


def suite_digest(suite) -> str:
    """Hex SHA-256 of the settings that decide a suite's runs and rows (every field but the
    suite file's own path and the maps skipped as absent)."""
    fields = {k: v for k, v in dataclasses.asdict(suite).items()
              if k not in ("source", "skipped")}
    return hashlib.sha256(json.dumps(fields, sort_keys=True, default=str).encode()).hexdigest()


def _marker(folder: Path) -> dict | None:
    """The folder's marker, or None when it has none or it is not one of ours."""
    try:
        m = json.loads((folder / MARKER).read_text(encoding="utf-8"))
    except (OSError, ValueError, RecursionError):
        return None
    if not isinstance(m, dict) or not isinstance(m.get("digest"), str):
        return None
    return m


def check_folder(folder: Path, suite, *, resume: bool, force: bool) -> None:
    """Refuse a results folder this run must not write into (nothing is written here).

    Parameters
    ----------
    folder : Path
        The ``--out`` folder (or ``results/<name>``).
    resume : bool
        Finished rows are to be kept (``--resume``, ``--report-only``).
    force : bool
        Start again: a previous run's rows of another suite may be replaced.

    Raises
    ------
    SuiteError
        ``folder`` is a file, a folder that is neither empty nor a suite run's, or (kept
        rows) a run of a different suite.
    """
    if not folder.exists():
        return
    if not folder.is_dir():
        raise SuiteError(f"{folder}: --out must be a folder, this is a file")
    try:
        entries = [p.name for p in folder.iterdir()]
    except OSError as exc:
        raise SuiteError(f"{folder}: cannot list the results folder: {exc.strerror}") from None
    if not [e for e in entries if e != ".lock"]:
        return  # empty (a lock file left by a run refused before it wrote anything)
    mark = _marker(folder)
    if mark is None:
        raise SuiteError(f"{folder} exists and is not a planner bench results folder (no "
                         f"{MARKER}); nothing in it was touched: choose a new or empty --out")
    if mark["digest"] != suite_digest(suite) and not force:
        other = mark.get("suite") if isinstance(mark.get("suite"), str) else "?"
        raise SuiteError(f"{folder} holds runs of a different suite ({other!r}, settings "
                         f"digest {mark['digest'][:12]} vs {suite_digest(suite)[:12]}: the "
                         f"suite was edited); its rows are not this suite's: use another "
                         f"--out, or --force to start again there")


def write_marker(folder: Path, suite) -> None:
    """Mark ``folder`` as a run of ``suite`` (before any result is written)."""
    write_text_atomic(folder / MARKER, json.dumps(
        {"suite": suite.name, "digest": suite_digest(suite), "source": suite.source},
        indent=1) + "\n")


def _point(v) -> bool:
    return (isinstance(v, list) and len(v) in (2, 3) and all(
        isinstance(x, int | float) and not isinstance(x, bool) and math.isfinite(x)
        for x in v))


def _query_problem(q) -> str | None:
    if not isinstance(q, dict):
        return f"a query is {json_type(q)}, not an object"
    if not isinstance(q.get("id"), int) or isinstance(q.get("id"), bool):
        return "a query has no integer 'id'"
    if not (_point(q.get("start")) and _point(q.get("goal"))):
        return f"query {q['id']}: 'start' and 'goal' must be lists of finite numbers"
    c = q.get("optimal_cost")
    if c is not None and (not isinstance(c, int | float) or isinstance(c, bool)):
        return f"query {q['id']}: 'optimal_cost' must be a number or null"
    return None


def check_saved_queries(path: Path, saved) -> None:
    """Refuse a ``queries.json`` whose groups or queries are not what a run writes (naming
    the group); a group in an older form is sampled again, a damaged one is not guessed at.

    Raises
    ------
    SuiteError
        One line naming the file and the group.
    """
    if not isinstance(saved, dict):
        raise SuiteError(f"{path}: not a query record (a JSON object of groups, got "
                         f"{json_type(saved)}); delete it to sample again (seeded: the "
                         f"same queries)")
    for group, rec in saved.items():
        why = None
        if not isinstance(rec, dict):
            why = f"{json_type(rec)}, not an object"
        elif not isinstance(rec.get("queries", []), list):
            why = "'queries' is not a list"
        elif not (isinstance(rec.get("wanted", 0), int) and isinstance(rec.get("kept", 0), int)):
            why = "'wanted' and 'kept' must be integers"
        elif not isinstance(rec.get("dropped", {}), dict):
            why = "'dropped' is not an object"
        elif "quaternion_xyzw" in rec and not (
                isinstance(rec["quaternion_xyzw"], list) and len(rec["quaternion_xyzw"]) == 4
                and all(isinstance(x, int | float) and not isinstance(x, bool)
                        and math.isfinite(x) for x in rec["quaternion_xyzw"])):
            why = "'quaternion_xyzw' is not 4 finite numbers"
        else:
            why = next(filter(None, map(_query_problem, rec.get("queries", []))), None)
        if why:
            raise SuiteError(f"{path}: group {group[:120]!r}: {why}; delete the file to sample "
                             f"again (seeded: the same queries)")


def remove_world_cache(worlds: Path) -> None:
    """Remove the world files suite runs make (``<20 hex>.npz``) and their temporary files,
    then the folder if that leaves it empty; anything else in it is left alone."""
    if not worlds.is_dir():
        return
    for p in worlds.iterdir():
        made = _WORLD_FILE.fullmatch(p.name) or (
            p.name.startswith(".") and _WORLD_FILE.match(p.name[1:]) and ".tmp" in p.name)
        if made and p.is_file() and not p.is_symlink():
            with contextlib.suppress(OSError):
                p.unlink()
    with contextlib.suppress(OSError):
        worlds.rmdir()  # only when empty
