"""The rows of a suite run: one JSON object per planned query, appended to
``results.jsonl`` as it finishes, and identified by :func:`row_key`."""

from __future__ import annotations

import json
from pathlib import Path

__all__ = ["row_key", "read_rows", "unique_rows", "drop_partial_line"]


def row_key(r: dict) -> str:
    """One run: map, resolution, radius, rotation (0 for rows of unrotated suites), lattice,
    neighbours, method, seed and query."""
    return "|".join(str(r.get(k, 0)) if k == "rotation" else str(r[k])
                    for k in ("map", "cell_volume", "radius", "rotation", "lattice",
                              "neighbors", "method", "seed", "query"))


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


def drop_partial_line(path: Path) -> None:
    """Cut a last line left unfinished by a kill, so that appended rows start on a line."""
    if not path.is_file() or path.stat().st_size == 0:
        return
    with open(path, "rb+") as f:
        data = f.read()
        if data.endswith(b"\n"):
            return
        f.truncate(data.rfind(b"\n") + 1)
