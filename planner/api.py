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
    "plan",
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
        (:func:`planner.search.stencils.carries_guarantee`).
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
    ``"poses"`` reads a pose list and merges its scans (:func:`planner.io.load_posed_scans`).
    """
    from planner import io

    if isinstance(source, io.Obstacles):
        return source
    if isinstance(source, str | Path) and format == "poses":
        pts = io.load_posed_scans(source)
        return io.Obstacles(points=pts, boxes=np.zeros((0, 3)), box_size=0.0, bounds=None,
                            resolution=None, source=str(source))
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


def _obstacle_bounds(obst) -> np.ndarray:
    parts = [p for p in (obst.points, obst.boxes) if len(p)]
    allp = np.concatenate(parts)
    return np.stack([allp.min(axis=0), allp.max(axis=0)])


def default_cell_volume(obst, bounds: np.ndarray | None = None) -> float:
    """Native resolution cubed where the map has one, else ~2 million cells in its box (m^3)."""
    if obst.resolution:
        return float(obst.resolution) ** 3
    b = _obstacle_bounds(obst) if bounds is None else np.asarray(bounds, dtype=float)
    vol = float(np.prod(np.maximum(b[1] - b[0], 1e-3)))
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
    lattice: str | Lattice = "fcc",
    *,
    cell_volume: float | None = None,
    radius: float = 0.0,
    bounds: np.ndarray | None = None,
    format: str | None = None,
):
    """Build the planning world once; query it many times with :func:`plan`.

    Parameters
    ----------
    source : str, Path, ndarray (N, 3) or Obstacles
        Map file (any format :func:`planner.io.load_obstacles` reads) or obstacle points (m).
    lattice : str or Lattice
        Lattice name (``cubic``, ``bcc``, ``fcc``, ``mcc``, ``hex``) or a Lattice instance
        (its own scale is then used and ``cell_volume`` must be None).
    cell_volume : float, optional
        Cell volume in m^3. Default: the map's native resolution cubed (OctoMap, .3dmap),
        the bundled map's suggestion, or about two million cells over the map's box.
    radius : float
        Robot radius (m): cells a robot centre must not enter are blocked (see
        :meth:`planner.voxels.OccupiedVoxelList.inflate` for the guarantee).
    bounds : array_like, shape (2, 3), optional
        World box [min, max] (m) the robot centre must stay in. Default: the map's own
        bounds (.3dmap grid box, bundled map sidecar) or the obstacles' bounding box.
    format : str, optional
        File format overriding the extension, or ``"poses"`` for a pose list of scans.

    Returns
    -------
    World
    """
    from planner.world import World

    t0 = time.perf_counter()
    side = _sidecar(source)
    obst = as_obstacles(source, format)
    where = "" if bounds is not None else f"{obst.source}: "  # the map's own bounds
    if bounds is None:
        if obst.bounds is not None:
            bounds = obst.bounds
        elif "bounds" in side:
            bounds = side["bounds"]
        else:
            bounds = _obstacle_bounds(obst)
    bounds = np.asarray(bounds, dtype=float)
    if bounds.shape != (2, 3) or not np.isfinite(bounds).all() or np.any(bounds[1] < bounds[0]):
        raise MapError(f"{where}bounds must be [[xmin, ymin, zmin], [xmax, ymax, zmax]], got "
                       f"{bounds.tolist()}")
    if (isinstance(radius, bool) or not isinstance(radius, int | float | np.floating)
            or not math.isfinite(radius) or radius < 0):
        raise PlanError(f"radius must be a non-negative number of metres, got {radius!r}")
    if isinstance(lattice, Lattice):
        if cell_volume is not None:
            lat = lattice.scaled(cell_volume)
        else:
            lat = lattice
    else:
        if cell_volume is None:
            cell_volume = side.get("cell_volume") or default_cell_volume(obst, bounds)
        lat = Lattice.named(lattice, cell_volume=cell_volume)
    try:
        cells = inflated_obstacles(obst, lat, radius).indices
    except PlannerError as exc:  # name the map, as the readers do
        if str(obst.source) in str(exc):
            raise
        raise type(exc)(f"{obst.source}: {exc}") from None
    return World(lat, cells, bounds, source=obst.source, radius=float(radius), obstacles=obst,
                 build_seconds=time.perf_counter() - t0)


def inflated_obstacles(obst, lattice: Lattice, radius: float):
    """The cells a robot centre of radius ``radius`` (m) must not enter, as tight as is cheap.

    Points: exactly the cells whose closed Voronoi cell is closer than ``radius`` to a point
    (:func:`planner.voxels.exact_inflation`). Boxes (``.3dmap`` voxels): the cells that
    overlap the box grown by ``radius`` on every side, a superset of the exact set (the
    grown box contains every point within ``radius`` of the box). Either way a path whose
    segments touch only free cells keeps distance >= ``radius`` from every obstacle, and
    the stencil inflation of :meth:`OccupiedVoxelList.inflate` is only needed when the
    points are gone (a saved voxel list).

    Returns
    -------
    OccupiedVoxelList
    """
    from planner.keys import unpack
    from planner.voxels import OccupiedVoxelList, box_keys, exact_inflation

    keys = []
    if len(obst.points):
        keys.append(exact_inflation(obst.points, lattice, radius).keys)
    if len(obst.boxes):
        keys.append(box_keys(obst.boxes, obst.box_size + 2 * radius, lattice))
    if not keys:
        raise MapError(f"{obst.source}: no obstacles")
    return OccupiedVoxelList.from_indices(unpack(np.concatenate(keys), lattice.dim), lattice)


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
    from planner.paths import path_length
    from planner.world import World, as_point

    as_point(start, "start")  # malformed input fails before any map is built
    as_point(goal, "goal")
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
        lattice=lat.name or "custom", cell_volume=lat.cell_volume, method=method,
        neighbors=neighbors, build_seconds=world.build_seconds or 0.0,
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
        peak_bytes=res.peak_bytes, extra={"cost_between_centres": res.cost},
        guarantee=res.guarantee, **common,
    )


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
        status="found" if r.found else r.status, guarantee=True, **common,
    )
