"""What the viewer draws: cell layers, raw points and paths, reduced to what a browser can hold.

A world holds millions of cells (geb079 at 0.08 m on BCC with a 0.2 m radius: about 3.5 M
blocked and 3.5 M unknown), too many to embed or draw. Two reductions, both stated in the
page:

1. *Surface culling* (lossless from outside): a cell all of whose face neighbours are in the
   same layer is hidden by them, so it is dropped. A height slice through a solid region
   therefore shows its shell, not its inside.
2. *Decimation*: when a layer still holds more than ``max_cells`` cells, a uniform random
   subset (fixed seed) of ``max_cells`` is kept.

Each layer is drawn as ONE point buffer (a single draw call, so orbiting stays responsive).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from planner.errors import PlannerError
from planner.occupancy.keys import pack

__all__ = ["Layer", "Scene", "PathTrace", "surface_cells", "build_scene"]

DEFAULT_MAX_CELLS = 400_000
DEFAULT_MAX_POINTS = 200_000


@dataclass
class Layer:
    """One set of points drawn in one colour scheme.

    ``cells`` (N, 3) int lattice indices (drawn at ``generator @ cell``) or ``points`` (N, 3)
    float metres; ``total`` is the count before culling and decimation, ``surface`` after
    culling only.
    """

    name: str
    total: int
    surface: int
    cells: np.ndarray | None = None
    points: np.ndarray | None = None

    @property
    def shown(self) -> int:
        return len(self.cells if self.cells is not None else self.points)


@dataclass
class PathTrace:
    """A path to draw: ``points`` (K, 3) metres, with its label."""

    label: str
    points: np.ndarray


@dataclass
class Scene:
    """Everything the page needs, in metres (``generator`` (3, 3): columns are the basis)."""

    title: str
    generator: np.ndarray
    cell_size: float
    bounds: np.ndarray
    layers: list[Layer] = field(default_factory=list)
    paths: list[PathTrace] = field(default_factory=list)
    start: np.ndarray | None = None
    goal: np.ndarray | None = None
    notes: list[str] = field(default_factory=list)


def _member(keys_sorted: np.ndarray, query: np.ndarray) -> np.ndarray:
    if not len(keys_sorted):
        return np.zeros(len(query), dtype=bool)
    pos = np.minimum(np.searchsorted(keys_sorted, query), len(keys_sorted) - 1)
    return keys_sorted[pos] == query


def surface_cells(cells: np.ndarray, offsets: np.ndarray) -> np.ndarray:
    """(N,) bool: the cell has a face neighbour (``cells + offset`` for an offset in
    ``offsets`` (F, 3)) outside the set ``cells`` (N, 3) int."""
    if not len(cells):
        return np.zeros(0, dtype=bool)
    keys = np.unique(pack(cells))
    out = np.zeros(len(cells), dtype=bool)
    for off in np.asarray(offsets, dtype=np.int64):
        todo = ~out
        out[todo] = ~_member(keys, pack(cells[todo] + off))
    return out


def _reduce(name: str, cells: np.ndarray, offsets: np.ndarray, max_cells: int,
            rng: np.random.Generator) -> Layer:
    cells = np.unique(np.asarray(cells, dtype=np.int64).reshape(-1, 3), axis=0)
    shell = cells[surface_cells(cells, offsets)]
    surface = len(shell)
    if surface > max_cells:
        shell = shell[np.sort(rng.choice(surface, max_cells, replace=False))]
    return Layer(name, total=len(cells), surface=surface, cells=shell)


def _raw_points(obstacles, max_points: int, rng: np.random.Generator) -> Layer | None:
    if obstacles is None:
        return None
    parts = [np.asarray(a, dtype=float).reshape(-1, a.shape[1]) for a in
             (obstacles.points, obstacles.boxes) if a is not None and len(a)]
    if not parts:
        return None
    pts = np.concatenate([p if p.shape[1] == 3 else np.column_stack(
        [p, np.zeros(len(p))]) for p in parts])
    total = len(pts)
    if total > max_points:
        pts = pts[np.sort(rng.choice(total, max_points, replace=False))]
    return Layer("raw points", total=total, surface=total, points=pts)


def build_scene(world, paths: list[PathTrace] | None = None, *, start=None, goal=None,
                title: str | None = None, max_cells: int = DEFAULT_MAX_CELLS,
                max_points: int = DEFAULT_MAX_POINTS, seed: int = 0) -> Scene:
    """The :class:`Scene` of a :class:`planner.World` and its paths.

    Parameters
    ----------
    world : planner.World
        Its blocked cells (those not unknown), unknown cells and raw obstacles are drawn.
    paths : list of PathTrace, optional
        Paths in metres in the map's frame, (K, 3) each (K, 2 on a 2D map: drawn at z = 0);
        drawn in the world's local frame (:attr:`planner.World.offset`).
    start, goal : array_like, shape (3,) or (2,), optional
        Markers in the map's frame (None: the first path's ends).
    max_cells, max_points : int
        Most cells per layer and most raw points embedded (module docstring).
    """
    if max_cells < 1 or max_points < 1:
        raise PlannerError("max_cells and max_points must be positive")
    rng = np.random.default_rng(seed)
    lat = world.lattice
    faces = lat.neighbors("face")
    unknown = world.unknown
    blocked = world.blocked
    if len(unknown) and len(blocked):
        blocked = blocked[~world.is_unknown(blocked)]
    # drawn in the world's local frame (float32 in the browser: UTM coordinates would lose
    # centimetres), said in a note
    traces = [PathTrace(p.label, world.to_local(_as3(p.points))) for p in (paths or [])
              if len(p.points)]
    if start is not None:
        start = world.to_local(_as3(np.atleast_2d(start))[0])
    if goal is not None:
        goal = world.to_local(_as3(np.atleast_2d(goal))[0])
    if start is None and traces:
        start = traces[0].points[0]
    if goal is None and traces:
        goal = traces[0].points[-1]
    scene = Scene(title=title or "lattice planner view", generator=np.asarray(lat.generator),
                  cell_size=float(world.cell_size), bounds=world.bounds, paths=traces,
                  start=None if start is None else _as3(np.atleast_2d(start))[0],
                  goal=None if goal is None else _as3(np.atleast_2d(goal))[0])
    if world.local_frame:
        scene.notes.append("local frame: map coordinates are these plus "
                           + ", ".join(f"{v:.3f}" for v in world.offset) + " m")
    raw = _raw_points(world.obstacles, max_points, rng)
    if raw is not None:
        scene.layers.append(raw)
    scene.layers.append(_reduce("blocked cells", blocked, faces, max_cells, rng))
    if len(unknown):
        scene.layers.append(_reduce("unknown cells", unknown, faces, max_cells, rng))
    for layer in scene.layers:
        if layer.shown < layer.surface or layer.surface < layer.total:
            what = "points" if layer.points is not None else "cells"
            scene.notes.append(f"{layer.name}: {layer.shown:,} of {layer.total:,} {what} shown"
                               + ("" if layer.points is not None else
                                  f" ({layer.surface:,} on the surface)"))
    return scene


def _as3(p) -> np.ndarray:
    p = np.asarray(p, dtype=float)
    if p.ndim == 2 and p.shape[1] == 2:
        p = np.column_stack([p, np.zeros(len(p))])
    if p.ndim != 2 or p.shape[1] != 3:
        raise PlannerError(f"a path must be (K, 3) or (K, 2) points, got shape {p.shape}")
    return p
