"""Building a world from a map: :func:`build_world` and the one resolver of map defaults.

:func:`resolve_defaults` decides, for every option not given, what the map says (radius,
cell volume, lattice by dimension, unknown-space policy, bounds); :func:`build_world` reads
the map, resolves, inflates and classifies unknown space; :func:`map_box` and
:func:`default_cell_volume` are the two rules it uses that callers ask for on their own.
"""

from __future__ import annotations

import time
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from planner.budget import require
from planner.checks import check_radius
from planner.errors import MapError, PlanError, PlannerError
from planner.io.load import load_obstacles
from planner.io.obstacles import UNKNOWN_POLICIES, Obstacles
from planner.io.sidecar import load_sidecar
from planner.lattice import Lattice
from planner.lattice.planar import planar_prism
from planner.maps import resolve
from planner.voxels.from_map import inflated_obstacles, unknown_region
from planner.world.assemble import assemble
from planner.world.file import check_options, is_world_file, load_world
from planner.world.frame import local_offset, shifted

__all__ = ["MapDefaults", "as_obstacles", "build_world", "default_cell_volume",
           "inflated_obstacles", "lift_planar", "map_box", "resolve_defaults", "sidecar"]

# Default planning resolution for raw clouds: about this many cells in the bounding box.
DEFAULT_CELLS = 2_000_000


def as_obstacles(source, format: str | None = None):
    """Obstacles from a file path, an (N, 3) point array or an Obstacles instance.

    ``format`` overrides the file extension (see :func:`planner.io.load_obstacles`);
    ``"poses"`` reads a pose list and merges its scans, keeping each scan's sensor origin
    for ray-cast free space.
    """
    if isinstance(source, Obstacles):
        return source
    if isinstance(source, str | Path):
        return load_obstacles(source, format)
    pts = np.asarray(source, dtype=float)
    if pts.ndim != 2 or pts.shape[1] != 3:
        raise MapError(f"obstacle points must have shape (N, 3), got {pts.shape}")
    if not len(pts):
        raise MapError("obstacle point cloud is empty")
    if not np.isfinite(pts).all():
        raise MapError("obstacle points contain NaN or infinite coordinates")
    return Obstacles(
        points=pts, boxes=np.zeros((0, 3)), box_size=0.0, bounds=None, resolution=None,
        source="<array>",
    )


def sidecar(source) -> dict:
    """Bundled maps carry a JSON sidecar with bounds and suggested resolution (checked: a
    malformed one is a one-line MapError, as in the CLI)."""
    if isinstance(source, str | Path) and Path(source).suffix.lower() != ".json":
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
    return _map_box(obst, sidecar(source) if obst.bounds is None else {})


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
    return vol / DEFAULT_CELLS


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
        Robot radius (m): cells a robot centre must not enter are blocked, exactly (see
        :func:`inflated_obstacles`). Default: the map's suggestion (its sidecar's
        ``robot_radius``); a map without one needs it given (PlanError otherwise; 0 for a
        point robot).
    bounds : array_like, shape (2, d), optional
        World box [min, max] (m) the robot centre must stay in. Default: the map's own
        bounds (.3dmap grid box, ROS map image, bundled map sidecar) or the obstacles'
        bounding box. A box far from the origin (UTM, ECEF) is planned in a local frame
        (:attr:`World.offset`, :mod:`planner.world.frame`): cells are then limited by the
        map's extent, not its distance from the origin.
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
    t0 = time.perf_counter()
    if isinstance(source, str | Path):  # a bundled map by name ("office") from any folder
        source = resolve(source)
    if is_world_file(source):
        world = load_world(source)
        check_options(world, lattice, cell_volume, radius, unknown, bounds)
        world.build_seconds = time.perf_counter() - t0
        return world
    side = sidecar(source)
    obst = as_obstacles(source, format)
    got = resolve_defaults(obst, side, lattice=lattice, cell_volume=cell_volume, radius=radius,
                           unknown=unknown, bounds=bounds)
    d, lat, radius, policy, bounds = obst.dim, got.lattice, got.radius, got.unknown, got.bounds
    if d == 2:
        obst, bounds, lat = lift_planar(obst), _lift_bounds(bounds), planar_prism(lat)
    offset = local_offset(lat, bounds)  # far from the origin: a local frame (world.frame)
    if offset.any():
        obst, bounds = shifted(obst, offset), bounds - offset
    if obst.has_free_space and d == 3:  # classified cell by cell: refuse before any work
        lo, hi = unknown_region(lat, bounds, radius)
        n = float(np.prod(hi - lo)) / lat.cell_volume
        per_cell = 24.0 if obst.origins is not None else 2.0  # cell lists; byte grids
        require(per_cell * n, f"the unknown-space classification of {obst.source} "
                f"(~{n:,.0f} cells in its box)")
    try:
        world = assemble(obst, lat, bounds, radius, policy, d == 2, source=obst.source,
                         obstacles=obst, dim=d, offset=offset)
    except PlannerError as exc:  # name the map, as the readers do
        if str(obst.source) in str(exc):
            raise
        raise type(exc)(f"{obst.source}: {exc}") from None
    world.build_seconds = time.perf_counter() - t0
    if isinstance(source, str | Path) and Path(source).is_file():
        world.source_file = str(source)
    return world


@dataclass(frozen=True)
class MapDefaults:
    """What a map resolves to: every option given, else the map's own value, else the rule.

    Attributes
    ----------
    lattice : Lattice
        At its cell volume (m^3; a 2D lattice's cell area, m^2, for a 2D map).
    radius : float
        Robot radius (m).
    unknown : {"blocked", "free"}
        Unknown-space policy.
    bounds : ndarray, shape (2, d)
        World box ``[[xmin, ...], [xmax, ...]]`` (m).
    """

    lattice: Lattice
    radius: float
    unknown: str
    bounds: np.ndarray


def resolve_defaults(obst, side: dict, *, lattice=None, cell_volume=None, radius=None,
                     unknown=None, bounds=None) -> MapDefaults:
    """The one resolver of map defaults; :func:`build_world` (so :func:`planner.plan`, the
    CLI and the suite) and :func:`planner.explore.explore` all go through it.

    ===========  ==========================================================================
    option       when not given
    ===========  ==========================================================================
    lattice      ``fcc`` (3D maps), ``hex2d`` (2D maps)
    cell_volume  the sidecar's ``cell_volume``, the map's native resolution cubed (squared
                 in 2D), else about two million cells over the map's box
    radius       the sidecar's ``robot_radius``; none there: PlanError (give 0 for a point
                 robot)
    unknown      the map's ``unknown_default`` (blocked when it records observed free
                 space, else free)
    bounds       the map's own box (OctoMap, .3dmap, ROS map), the sidecar's, else the
                 obstacles' extent
    ===========  ==========================================================================

    Parameters
    ----------
    obst : Obstacles
        The loaded map.
    side : dict
        Its sidecar (:func:`planner.io.load_sidecar`; ``{}`` when none).

    Returns
    -------
    MapDefaults
    """
    d = obst.dim
    where = "" if bounds is not None else f"{obst.source}: "  # the map's own bounds
    b = _map_box(obst, side) if bounds is None else bounds
    try:
        b = np.asarray(b, dtype=float)
    except (TypeError, ValueError):
        b = np.zeros(0)
    if b.shape != (2, d) or not np.isfinite(b).all() or np.any(b[1] < b[0]):
        shown = b.tolist() if b.size else bounds
        raise MapError(f"{where}bounds must be [[xmin, ...], [xmax, ...]] with {d} numbers "
                       f"each, got {shown}")
    if radius is None:
        radius = side.get("robot_radius")
        if radius is None:
            raise PlanError(f"{obst.source}: the map suggests no robot radius; give one "
                            "(radius= in the API, --radius in the CLI; metres, 0 for a "
                            "point robot)")
    radius = check_radius(radius)
    policy = obst.unknown_default if unknown is None else unknown
    if policy not in UNKNOWN_POLICIES:
        raise MapError(f"unknown must be 'blocked' or 'free', got {unknown!r}")
    if policy == "blocked" and not obst.has_free_space:
        raise MapError(f"{obst.source}: the map says nothing about free space (a plain "
                       f"cloud), so --unknown blocked would block everything; use free")
    return MapDefaults(_lattice(lattice, cell_volume, side, obst, b), radius, policy, b)


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


def lift_planar(obst):
    """A 2D map as 3D obstacles in the plane z = 0: points at z = 0, squares as cubes centred
    on it. A prism cell of the plane and a cube both contain z = 0 in their z-ranges, so
    their distance is the 2D distance of the square and the 2D cell."""
    def pts(a):
        return np.concatenate([a, np.zeros((len(a), 1))], axis=1)

    return Obstacles(points=pts(obst.points), boxes=pts(obst.boxes), box_size=obst.box_size,
                        box_sizes=obst.box_sizes, free_boxes=pts(obst.free_boxes),
                        free_box_sizes=obst.free_box_sizes, bounds=None,
                        resolution=obst.resolution, source=obst.source,
                        unknown_default=obst.unknown_default, dim=3)


def _lift_bounds(bounds: np.ndarray) -> np.ndarray:
    return np.concatenate([bounds, np.zeros((2, 1))], axis=1)
