"""Write the viewer page of a world and its paths (the functions :mod:`planner.view` exports)."""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np

from planner.errors import PlannerError
from planner.view.page import render_html, write_html
from planner.view.scene import DEFAULT_MAX_CELLS, PathTrace, build_scene

__all__ = ["read_path_file", "render_view", "write_view"]


def read_path_file(path: str | os.PathLike) -> tuple[str, np.ndarray]:
    """A path written by ``planner plan --out P.json``: (label, (K, 3) points in metres)."""
    p = Path(path)
    try:
        rec = json.loads(p.read_text())
        pts = np.asarray(rec["path"], dtype=float)
    except (OSError, ValueError, KeyError, TypeError) as exc:
        why = exc.strerror if isinstance(exc, OSError) else "not a path file from planner plan"
        raise PlannerError(f"{p}: cannot read a path: {why}") from None
    if pts.ndim != 2 or pts.shape[1] not in (2, 3) or not len(pts):
        raise PlannerError(f"{p}: the path holds no (x, y[, z]) waypoints")
    return f"{rec.get('lattice') or p.stem} ({p.name})", pts


def _scene(world, paths, title, max_cells, start, goal):
    traces = [PathTrace(k, np.asarray(v, dtype=float)) for k, v in (paths or {}).items()]
    name = Path(str(world.source or "")).name or "world"
    title = title or f"{name}: {world.lattice.name or 'custom'} lattice, radius {world.radius:g} m"
    return build_scene(world, traces, start=start, goal=goal, title=title, max_cells=max_cells)


def render_view(world, paths: dict | None = None, *, title: str | None = None,
                max_cells: int = DEFAULT_MAX_CELLS, start=None, goal=None) -> str:
    """The page (HTML text) of ``world`` with ``paths`` (label -> (K, 3) metres)."""
    return render_html(_scene(world, paths, title, max_cells, start, goal))


def write_view(out: str | os.PathLike, world, paths: dict | None = None, *,
               title: str | None = None, max_cells: int = DEFAULT_MAX_CELLS, start=None,
               goal=None) -> None:
    """Write the page of ``world`` and ``paths`` to ``out`` (``.html``) atomically."""
    write_html(out, _scene(world, paths, title, max_cells, start, goal))
