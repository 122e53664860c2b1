"""The user-facing pipeline: points -> lattice indices -> voxel list -> world -> search -> path.

``plan`` is the one-call entry point; ``build_world`` is the build-once, query-many step.
"""

from __future__ import annotations

import json
import math
import time
import warnings
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np

from planner.errors import MapError, PlanError, PlannerError
from planner.lattice import Lattice

__all__ = [
    "PlanResult", "as_obstacles", "build_world", "default_cell_volume", "inflated_obstacles",
    "map_box", "plan", "unknown_on_path",
]

# Default planning resolution for raw clouds: about this many cells in the bounding box.
_DEFAULT_CELLS = 2_000_000


@dataclass
class PlanResult:
    """Outcome of one planning query.

    Attributes
    ----------
    found : bool
    path : ndarray, shape (K, 3)
        World coordinates (metres), start point first, goal point last; empty if not found.
    cells : ndarray, shape (K-2, 3), int64
        Lattice indices of the cells visited between start and goal.
    length : float
        Path length in metres (``inf`` when not found).
    cell_checks, expansions, generated : int
        Occupancy lookups, node expansions and generated nodes of the search.
    seconds : float
        Search wall time (excludes building the world).
    status : str
        ``"found"``, ``"unreachable"`` or ``"budget"`` (lattice methods, see
        :class:`planner.search.SearchResult`); OMPL: ``"found"``, ``"no path"``, ``"timeout"``
        or ``"crashed"``.
    guarantee : bool
        The path keeps the robot radius from every obstacle (world built with exact
        inflation): True for OMPL (exact motion checks) and for lattice methods unless
        ``corner_cutting`` lets moves cut blocked corners
        (:func:`planner.search.moves.carries_guarantee`).
    unknown_cells : int
        Distinct cells the path's segments touch that meet unknown space (0 whenever unknown
        space is blocked; may be > 0 under ``unknown="free"``).
    unknown_note : str
        How the world treats unknown space (:attr:`planner.World.unknown_note`).
    """

    found: bool
    path: np.ndarray
    cells: np.ndarray
    length: float
    cell_checks: int
    expansions: int
    generated: int
    seconds: float
    lattice: str
    cell_volume: float
    method: str
    neighbors: str
    reason: str = ""
    peak_bytes: int = 0
    build_seconds: float = 0.0
    extra: dict = field(default_factory=dict)
    status: str = "found"
    guarantee: bool = True
    unknown_cells: int = 0
    unknown_note: str = ""

    def to_dict(self) -> dict:
        """JSON-ready dict (arrays as nested lists, inf as None)."""
        d = asdict(self)
        d["path"] = self.path.tolist()
        d["cells"] = self.cells.tolist()
        d["length"] = self.length if math.isfinite(self.length) else None
        return d

    def to_json(self) -> str:
        return json.dumps(self.to_dict())


def as_obstacles(source, format: str | None = None):
    """Obstacles from a file path, an (N, 3) point array or an Obstacles instance.

    ``format`` overrides the file extension (see :func:`planner.io.load_obstacles`);
    ``"poses"`` reads a pose list and merges its scans, keeping each scan's sensor origin
    for ray-cast free space.
    """
    from planner import io

    if isinstance(source, io.Obstacles):
        return source
    if isinstance(source, str | Path):
        return io.load_obstacles(source, format)
    pts = np.asarray(source, dtype=float)
    if pts.ndim != 2 or pts.shape[1] != 3:
        raise MapError(f"obstacle points must have shape (N, 3), got {pts.shape}")
    if not len(pts):
        raise MapError("obstacle point cloud is empty")
    if not np.isfinite(pts).all():
        raise MapError("obstacle points contain NaN or infinite coordinates")
    return io.Obstacles(
        points=pts, boxes=np.zeros((0, 3)), box_size=0.0, bounds=None, resolution=None,
        source="<array>",
    )


def _sidecar(source) -> dict:
    """Bundled maps carry a JSON sidecar with bounds and suggested resolution (checked: a
    malformed one is a one-line MapError, as in the CLI)."""
    if isinstance(source, str | Path) and Path(source).suffix.lower() != ".json":
        from planner.io import load_sidecar

        return load_sidecar(source)
    return {}


def map_box(source, obst=None) -> np.ndarray:
    """The world box :func:`build_world` chooses for a map when given no ``bounds``: the
    map's own (OctoMap, .3dmap, ROS map), else its sidecar's, else the obstacles' extent.

    Parameters
    ----------
    source : str, Path, ndarray or Obstacles
        As for :func:`build_world`.
    obst : Obstacles, optional
        ``source`` already loaded (saves reading it again).

    Returns
    -------
    ndarray, shape (2, d)
        ``[[xmin, ...], [xmax, ...]]``, metres (not yet checked).
    """
    obst = as_obstacles(source) if obst is None else obst
    return _map_box(obst, _sidecar(source) if obst.bounds is None else {})


def _map_box(obst, side: dict) -> np.ndarray:
    """:func:`map_box` of a loaded map and its sidecar."""
    if obst.bounds is not None:
        return np.asarray(obst.bounds, dtype=float)
    if "bounds" in side:
        return np.asarray(side["bounds"], dtype=float)
    return _obstacle_bounds(obst)


def _obstacle_bounds(obst) -> np.ndarray:
    parts = [p for p in (obst.points, obst.boxes) if len(p)]
    allp = np.concatenate(parts)
    return np.stack([allp.min(axis=0), allp.max(axis=0)])


def default_cell_volume(obst, bounds: np.ndarray | None = None) -> float:
    """Native resolution cubed (squared for a 2D map: an area, m^2) where the map has one,
    else ~2 million cells in its box (m^3)."""
    if obst.resolution:
        return float(obst.resolution) ** obst.dim
    b = _obstacle_bounds(obst) if bounds is None else np.asarray(bounds, dtype=float)
    ext = b[1] - b[0]
    # A flat or linear cloud (one scan line, a floor) has no thickness: size its cells by its
    # largest extent instead, so that the default does not ask for millimetre cells.
    vol = float(np.prod(np.maximum(ext, max(1e-3, 0.01 * float(ext.max())))))
    _warn_far_points(obst, b)
    return vol / _DEFAULT_CELLS


def _warn_far_points(obst, b: np.ndarray) -> None:
    """Warn when a few far points (outliers) stretch the box the default cell volume is
    taken from: the cells then come out much larger than the bulk of the map suggests."""
    pts = obst.points
    if len(pts) < 100 or len(obst.boxes):
        return
    lo, hi = np.percentile(pts, [0.5, 99.5], axis=0)
    bulk = np.maximum(hi - lo, 1e-3)
    if np.any(np.maximum(b[1] - b[0], 1e-3) > 10 * bulk):
        warnings.warn(f"{obst.source}: a few far points stretch the map box to "
                      f"{np.round(b[1] - b[0], 3).tolist()} m while 99% of the points lie "
                      f"within {np.round(bulk, 3).tolist()} m; the default cell volume "
                      "follows the whole box (pass a cell volume or bounds)", RuntimeWarning,
                      stacklevel=3)


def build_world(
    source,
    lattice: str | Lattice | None = None,
    *,
    cell_volume: float | None = None,
    radius: float | None = None,
    bounds: np.ndarray | None = None,
    format: str | None = None,
    unknown: str | None = None,
):
    """Build the planning world once; query it many times with :func:`plan`.

    Parameters
    ----------
    source : str, Path, ndarray (N, 3) or Obstacles
        Map file (any format :func:`planner.io.load_obstacles` reads), a saved world
        (``.npz`` from ``planner world``: loaded, not rebuilt; an option that differs from
        what it was built with is a MapError) or obstacle points (m).
    lattice : str or Lattice, optional
        Lattice name (``cubic``, ``bcc``, ``fcc``, ``mcc``, ``hex``; 2D maps: ``square``,
        ``hex2d``) or a Lattice instance (its own scale is then used unless ``cell_volume``
        is given). Default ``fcc`` (2D maps: ``hex2d``).
    cell_volume : float, optional
        Cell volume in m^3 (2D maps: cell area in m^2). Default: the map's native
        resolution cubed (squared in 2D), the bundled map's suggestion, or about two
        million cells over the map's box.
    radius : float, optional
        Robot radius (m, default 0): cells a robot centre must not enter are blocked,
        exactly (see :func:`inflated_obstacles`).
    bounds : array_like, shape (2, d), optional
        World box [min, max] (m) the robot centre must stay in. Default: the map's own
        bounds (.3dmap grid box, ROS map image, bundled map sidecar) or the obstacles'
        bounding box.
    format : str, optional
        File format overriding the extension, or ``"poses"`` for a pose list of scans.
    unknown : {"blocked", "free"}, optional
        How unknown space is treated (default: the map's ``unknown_default``: blocked when
        the map says what was observed free, else free). ``"blocked"``: a cell is usable only
        if its closed Voronoi cell stays ``radius`` away from unknown space (as from
        obstacles). ``"free"``: paths may cross unknown cells; results count them.

    Returns
    -------
    World
    """
    from planner.voxels.from_map import unknown_region, unknown_space
    from planner.world import World
    from planner.world.file import check_options, is_world_file, load_world

    t0 = time.perf_counter()
    if isinstance(source, str | Path):  # a bundled map by name ("office") from any folder
        from planner.maps import resolve

        source = resolve(source)
    if is_world_file(source):
        world = load_world(source)
        check_options(world, lattice, cell_volume, radius, unknown, bounds)
        world.build_seconds = time.perf_counter() - t0
        return world
    radius = 0.0 if radius is None else radius
    side = _sidecar(source)
    obst = as_obstacles(source, format)
    where = "" if bounds is not None else f"{obst.source}: "  # the map's own bounds
    if bounds is None:
        bounds = _map_box(obst, side)
    d = obst.dim
    bounds = np.asarray(bounds, dtype=float)
    if bounds.shape != (2, d) or not np.isfinite(bounds).all() or np.any(bounds[1] < bounds[0]):
        raise MapError(f"{where}bounds must be [[xmin, ...], [xmax, ...]] with {d} numbers "
                       f"each, got {bounds.tolist()}")
    if (isinstance(radius, bool) or not isinstance(radius, int | float | np.floating)
            or not math.isfinite(radius) or radius < 0):
        raise PlanError(f"radius must be a non-negative number of metres, got {radius!r}")
    policy = obst.unknown_default if unknown is None else unknown
    if policy not in ("blocked", "free"):
        raise MapError(f"unknown must be 'blocked' or 'free', got {unknown!r}")
    if policy == "blocked" and not obst.has_free_space:
        raise MapError(f"{obst.source}: the map says nothing about free space (a plain "
                       f"cloud), so --unknown blocked would block everything; use free")
    lat = _lattice(lattice, cell_volume, side, obst, bounds)
    if d == 2:
        from planner.lattice.planar import planar_prism

        obst, bounds, lat = _lift(obst), _lift_bounds(bounds), planar_prism(lat)
    if obst.has_free_space and d == 3:  # classified cell by cell: refuse before any work
        from planner.budget import require

        lo, hi = unknown_region(lat, bounds, radius)
        n = float(np.prod(hi - lo)) / lat.cell_volume
        require(24.0 * n, f"the unknown-space classification of {obst.source} (~{n:,.0f} "
                "cells in its box)")
    try:
        cells = inflated_obstacles(obst, lat, radius).indices
    except PlannerError as exc:  # name the map, as the readers do
        if str(obst.source) in str(exc):
            raise
        raise type(exc)(f"{obst.source}: {exc}") from None
    unknown_cells = None
    if obst.has_free_space:
        unknown_cells, near = unknown_space(obst, lat, bounds, radius, d == 2,
                                             policy == "blocked", cells)
        if near is not None:
            cells = np.concatenate([cells, near])
    if d == 2:  # only the plane z = 0 is in bounds
        cells = cells[cells[:, 2] == 0]
    if unknown_cells is not None and d == 2:
        unknown_cells = unknown_cells[unknown_cells[:, 2] == 0]
    world = World(lat, cells, bounds, source=obst.source, radius=float(radius), obstacles=obst,
                  build_seconds=time.perf_counter() - t0, unknown_cells=unknown_cells,
                  unknown_policy=policy, dim=d)
    if isinstance(source, str | Path) and Path(source).is_file():
        world.source_file = str(source)
    return world


def _lattice(lattice, cell_volume, side, obst, bounds) -> Lattice:
    """The lattice asked for, at the cell volume (area in 2D) asked for or the map's."""
    if isinstance(lattice, Lattice):
        if lattice.dim != obst.dim:
            raise MapError(f"{obst.source}: a {obst.dim}D map needs a {obst.dim}D lattice, "
                           f"got a {lattice.dim}D one")
        return lattice.scaled(cell_volume) if cell_volume is not None else lattice
    if lattice is None:
        lattice = "fcc" if obst.dim == 3 else "hex2d"
    if cell_volume is None:
        cell_volume = side.get("cell_volume") or default_cell_volume(obst, bounds)
    lat = Lattice.named(lattice, cell_volume=cell_volume)
    if lat.dim != obst.dim:
        raise MapError(f"{obst.source}: a {obst.dim}D map needs a {obst.dim}D lattice "
                       f"({'square, hex2d' if obst.dim == 2 else 'cubic, bcc, fcc, mcc, hex'}),"
                       f" got {lattice!r}")
    return lat


def _lift(obst):
    """A 2D map as 3D obstacles in the plane z = 0: points at z = 0, squares as cubes centred
    on it. A prism cell of the plane and a cube both contain z = 0 in their z-ranges, so
    their distance is the 2D distance of the square and the 2D cell."""
    from planner import io

    def pts(a):
        return np.concatenate([a, np.zeros((len(a), 1))], axis=1)

    return io.Obstacles(points=pts(obst.points), boxes=pts(obst.boxes), box_size=obst.box_size,
                        box_sizes=obst.box_sizes, free_boxes=pts(obst.free_boxes),
                        free_box_sizes=obst.free_box_sizes, bounds=None,
                        resolution=obst.resolution, source=obst.source,
                        unknown_default=obst.unknown_default, dim=3)


def inflated_obstacles(obst, lattice: Lattice, radius: float):
    """:func:`planner.voxels.from_map.inflated_obstacles` (its home; kept here, where
    earlier versions had it)."""
    from planner.voxels.from_map import inflated_obstacles as cells

    return cells(obst, lattice, radius)


def _lift_bounds(bounds: np.ndarray) -> np.ndarray:
    return np.concatenate([bounds, np.zeros((2, 1))], axis=1)


def plan(
    map_or_points,
    start,
    goal,
    *,
    lattice: str | Lattice = "fcc",
    cell_volume: float | None = None,
    radius: float = 0.0,
    method: str = "astar",
    neighbors: str = "full",
    corner_cutting: bool = False,
    bounds: np.ndarray | None = None,
    backend: str = "numba",
    shortcut: bool = False,
    time_limit: float = 1.0,
    seed: int = 0,
    max_expansions: int | None = None,
    memory_budget: int | None = None,
) -> PlanResult:
    """Plan a path from ``start`` to ``goal`` (world points, metres).

    Parameters
    ----------
    map_or_points : str, Path, ndarray (N, 3), Obstacles or World
        A map file, obstacle points, or a world from :func:`build_world` (then
        ``lattice``, ``cell_volume``, ``radius`` and ``bounds`` are taken from it).
    start, goal : array_like, shape (3,)
    method : str
        ``astar``, ``dijkstra``, ``theta``, ``lazy-theta`` on the lattice, or
        ``ompl:<planner>`` (e.g. ``ompl:rrtconnect``) for the continuous baseline.
    neighbors : str
        ``full`` (every touching cell), ``face`` (the paper's Delta adjacency) or
        ``face+k`` / ``full+k`` (k further shells).
    corner_cutting : bool
        Check only each move's target cell instead of every cell its segment touches.
        Results then carry ``guarantee=False`` (no clearance guarantee) unless the move
        set makes both rules equal.
    shortcut : bool
        Post-process the lattice path by line-of-sight shortcutting.
    time_limit, seed
        OMPL planning time (s) and RNG seed (an integer in [0, 2**32)).
    max_expansions, memory_budget
        Search budget (:func:`planner.search.search`): status ``"budget"`` when exceeded.
        Defaults: the nodes that fit in an eighth of the physical memory.

    Returns
    -------
    PlanResult
    """
    from planner import search
    from planner.path import path_length
    from planner.world import World, as_point

    as_point(start, "start", 2)  # malformed input fails before any map is built
    as_point(goal, "goal", 2)
    if not isinstance(method, str):
        raise PlanError(f"method must be a string, got {method!r}")
    if method.startswith("ompl:"):
        from planner.ompl import check_seed

        check_seed(seed)
    if isinstance(map_or_points, World):
        world = map_or_points
    else:
        world = build_world(
            map_or_points, lattice, cell_volume=cell_volume, radius=radius, bounds=bounds
        )
    lat = world.lattice
    common = dict(
        lattice=lat.name or "custom",
        cell_volume=lat.cell_area if world.dim == 2 else lat.cell_volume, method=method,
        neighbors=neighbors, build_seconds=world.build_seconds or 0.0,
        unknown_note=world.unknown_note,
    )
    s, s_cell = world.endpoint(start, "start")
    g, g_cell = world.endpoint(goal, "goal")
    if method.startswith("ompl:"):
        return _plan_ompl(world, s, g, method.split(":", 1)[1], time_limit, seed, common)
    res = search.search(
        world, s_cell, g_cell, method=method, neighbors=neighbors,
        corner_cutting=corner_cutting, backend=backend, max_expansions=max_expansions,
        memory_budget=memory_budget,
    )
    if not res.found:
        return PlanResult(
            found=False, path=np.zeros((0, 3)), cells=np.zeros((0, 3), np.int64),
            length=math.inf, cell_checks=res.cell_checks, expansions=res.expansions,
            generated=res.generated, seconds=res.seconds, reason=res.reason,
            peak_bytes=res.peak_bytes, status=res.status, guarantee=res.guarantee, **common,
        )
    path_cells = res.cells
    checks = res.cell_checks
    seconds = res.seconds
    raw_length = path_length(np.concatenate([s[None], lat.to_world(path_cells), g[None]]), 0.0)
    if shortcut and method in ("astar", "dijkstra"):
        t0 = time.perf_counter()
        before = world.cell_checks
        path_cells = search.shortcut(world, path_cells)
        checks += world.cell_checks - before
        seconds += time.perf_counter() - t0
    path = np.concatenate([s[None], lat.to_world(path_cells), g[None]])
    length = path_length(path, 0.0)
    return PlanResult(
        found=True, path=path, cells=path_cells, length=length, cell_checks=checks,
        expansions=res.expansions, generated=res.generated, seconds=seconds,
        peak_bytes=res.peak_bytes,
        extra={"cost_between_centres": res.cost, "raw_length": raw_length,
               "smoothed_length": length if shortcut else None},
        guarantee=res.guarantee, unknown_cells=unknown_on_path(world, path), **common,
    )


def unknown_on_path(world, path: np.ndarray) -> int:
    """Distinct cells meeting unknown space that the polyline ``path`` ((K, 3), m) touches
    (every cell whose closed Voronoi cell a segment touches)."""
    if not world.n_unknown or len(path) == 0:
        return 0
    parts = [world.segment_cells(a, b) for a, b in zip(path[:-1], path[1:], strict=True)]
    cells = np.concatenate(parts) if parts else world.lattice.quantize(path[:1])
    cells = np.unique(cells, axis=0)
    return int(world.is_unknown(cells).sum())


def _plan_ompl(world, s, g, planner_name, time_limit, seed, common) -> PlanResult:
    from planner import ompl

    r = ompl.plan_ompl(world, s, g, planner=planner_name, time_limit=time_limit, seed=seed)
    path = r.path_simplified if r.path_simplified is not None else r.path
    d = r.to_dict()
    return PlanResult(
        found=r.found, path=path if r.found else np.zeros((0, 3)),
        cells=np.zeros((0, 3), np.int64), length=r.length if r.found else math.inf,
        cell_checks=r.cell_checks, expansions=0, generated=0, seconds=r.seconds,
        reason=r.reason, extra={k: v for k, v in d.items() if k not in ("path", "path_simplified")},
        status="found" if r.found else r.status, guarantee=True,
        unknown_cells=unknown_on_path(world, path) if r.found else 0, **common,
    )
