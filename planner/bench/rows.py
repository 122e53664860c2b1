"""The rows of a suite run: one JSON object per planned query, appended to
``results.jsonl`` as it finishes, and identified by :func:`row_key`."""

from __future__ import annotations

import json
import math
from pathlib import Path

from planner.errors import PlannerError

__all__ = ["row_key", "read_rows", "unique_rows", "drop_partial_line", "check_row",
           "ResultsError"]


class ResultsError(PlannerError):
    """A results file holding a line that is not a result row."""


_TEXT = ("map", "lattice", "neighbors", "method")
_NUMBER = ("cell_volume", "radius")
_INTEGER = ("seed", "query")
_OPTIONAL_NUMBER = ("length", "length_smoothed", "clearance", "seconds", "cell_checks",
                    "expansions", "peak_bytes", "optimal_cost", "distance", "run_seconds")
_OPTIONAL_FLAG = ("found", "collision_free")


def _number(v) -> bool:
    return isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v)


def _integer(v) -> bool:
    return isinstance(v, int) and not isinstance(v, bool)


def json_type(v) -> str:
    """The JSON name of a parsed value's type (``null``, ``array``, ...)."""
    return {dict: "object", list: "array", str: "string", bool: "boolean",
            type(None): "null"}.get(type(v), "number")


def check_row(r) -> str | None:
    """None when ``r`` is a result row (its key fields and measured values of the right
    types), else what is wrong with it."""
    if not isinstance(r, dict):
        return f"not a JSON object but {json_type(r)}"
    for keys, ok, want in ((_TEXT, lambda v: isinstance(v, str), "a string"),
                           (_NUMBER, _number, "a finite number"),
                           (_INTEGER, _integer, "an integer")):
        for k in keys:
            if k not in r:
                return f"no {k!r}"
            if not ok(r[k]):
                return f"{k!r} is not {want}"
    if "rotation" in r and not _integer(r["rotation"]):
        return "'rotation' is not an integer"
    for k in _OPTIONAL_NUMBER:
        # inf and nan are honest values here (the clearance of a map without obstacles)
        if r.get(k) is not None and (not isinstance(r[k], int | float)
                                     or isinstance(r[k], bool)):
            return f"{k!r} is not a number"
    for k in _OPTIONAL_FLAG:
        if r.get(k) is not None and not isinstance(r[k], bool):
            return f"{k!r} is not true or false"
    return None


def row_key(r: dict) -> str:
    """One run: map, resolution, radius, rotation (0 for rows of unrotated suites), lattice,
    neighbours, method, seed and query."""
    return "|".join(str(r.get(k, 0)) if k == "rotation" else str(r[k])
                    for k in ("map", "cell_volume", "radius", "rotation", "lattice",
                              "neighbors", "method", "seed", "query"))


def read_rows(path: Path) -> list[dict]:
    """Rows of a results file; a last line cut short by a kill is ignored.

    Raises
    ------
    ResultsError
        A complete line that is not a result row (:func:`check_row`), with its number.
    """
    rows: list[dict] = []
    if not path.is_file():
        return rows
    try:
        text = path.read_text(encoding="utf-8")
    except UnicodeDecodeError as exc:
        raise ResultsError(f"{path}: not a results file ({exc.reason}); --force starts "
                           f"again") from None
    lines = text.split("\n")
    for i, line in enumerate(lines, 1):
        if not line.strip():
            continue
        try:
            r = json.loads(line)
        except (ValueError, RecursionError):
            if i == len(lines):  # no newline after it: cut short by a kill
                continue
            r = ValueError
        why = "not JSON" if r is ValueError else check_row(r)
        if why:
            raise ResultsError(f"{path} line {i}: not a result row ({why}); remove the line "
                               f"or pass --force to start again")
        rows.append(r)
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


def drop_partial_line(path: Path) -> None:
    """Cut a last line left unfinished by a kill, so that appended rows start on a line."""
    if not path.is_file() or path.stat().st_size == 0:
        return
    with open(path, "rb+") as f:
        data = f.read()
        if data.endswith(b"\n"):
            return
        f.truncate(data.rfind(b"\n") + 1)
