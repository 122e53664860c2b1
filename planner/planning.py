"""Planning a path: :func:`plan` (the one-call entry point), :class:`PlanResult` and
:func:`describe`. Worlds are built by :func:`planner.world.build.build_world` (the
build-once, query-many step), whose resolver gives ``plan`` the map's defaults.
"""

from __future__ import annotations

import json
import math
import time
from dataclasses import asdict, dataclass, field

import numpy as np

from planner import ompl, search
from planner.errors import PlanError
from planner.lattice import Lattice
from planner.ompl import check_seed
from planner.path import SHORT_PATH, path_length
from planner.search.run import search_points
from planner.world import World, as_point
from planner.world.build import build_world
from planner.world.caveats import NO_ORIGIN, world_warnings

__all__ = ["NO_ORIGIN", "PlanResult", "build_world", "describe", "distinct", "joined", "plan",
           "unknown_on_path", "world_warnings"]


@dataclass
class PlanResult:
    """Outcome of one planning query.

    Attributes
    ----------
    found : bool
    path : ndarray, shape (K, 3)
        Points in the map's frame (metres; a world with a local frame adds its
        :attr:`World.offset` back, recorded in ``extra["local_offset"]``), start point first,
        goal point last; empty if not found.
    cells : ndarray, shape (C, 3), int64
        Lattice indices of the cells the search visited, the start's first and the goal's
        last; ``path`` joins its ends to them (:func:`joined`), so ``K <= C + 2``.
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


def plan(
    map_or_points,
    start,
    goal,
    *,
    lattice: str | Lattice | None = None,
    cell_volume: float | None = None,
    radius: float | None = None,
    unknown: str | None = None,
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
        A map file or bundled map name, obstacle points, or a world from
        :func:`build_world` (then ``lattice``, ``cell_volume``, ``radius``, ``unknown`` and
        ``bounds`` are taken from it).
    start, goal : array_like, shape (3,) or (2,) on a 2D map
        Metres.
    lattice, cell_volume, radius, unknown, bounds
        As for :func:`build_world`, with the same defaults (the map's radius, lattice by
        dimension, ...: :func:`planner.world.build.resolve_defaults`); a map without a
        suggested radius needs ``radius``.
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
    pts = map_or_points.end_coords(start, goal) if isinstance(map_or_points, World) else None
    if pts is None:  # points (arrays, tuples, lists of 3 reals) inside the bounds: checked
        as_point(start, "start", 2)  # malformed input fails before any map is built
        as_point(goal, "goal", 2)
    if not isinstance(method, str):
        raise PlanError(f"method must be a string, got {method!r}")
    if method.startswith("ompl:"):
        check_seed(seed)
    if isinstance(map_or_points, World):
        world = map_or_points
    else:
        world = build_world(map_or_points, lattice, cell_volume=cell_volume, radius=radius,
                            bounds=bounds, unknown=unknown)
    res = None
    if pts is not None and backend == "numba" and not method.startswith("ompl:"):
        res = search_points(world, pts, method=method, neighbors=neighbors,
                            corner_cutting=corner_cutting, max_expansions=max_expansions,
                            memory_budget=memory_budget)
    if res is not None:
        s, g = pts[:3], pts[3:]  # checked: the points' coordinates as Python floats
    else:
        s, s_cell, g, g_cell = world.endpoints(start, goal)  # local points
        if method.startswith("ompl:"):
            return _plan_ompl(world, start, goal, method.split(":", 1)[1], time_limit, seed,
                              _common(world, method, neighbors))
        res = search.search(
            world, s_cell, g_cell, method=method, neighbors=neighbors,
            corner_cutting=corner_cutting, backend=backend, max_expansions=max_expansions,
            memory_budget=memory_budget,
        )
        s, g = s.tolist(), g.tolist()
    if not res.found:
        return PlanResult(
            found=False, path=np.zeros((0, 3)), cells=np.zeros((0, 3), np.int64),
            length=math.inf, cell_checks=res.cell_checks, expansions=res.expansions,
            generated=res.generated, seconds=res.seconds, reason=res.reason,
            peak_bytes=res.peak_bytes, status=res.status, guarantee=res.guarantee,
            **_common(world, method, neighbors),
        )
    path_cells = res.cells
    checks = res.cell_checks
    seconds = res.seconds
    # the lookups joining the ends (joined): in extra, not in the search's count
    path, joins, length = _joined_path(world, s, path_cells, g)
    raw_length = length
    if shortcut and method in ("astar", "dijkstra"):
        t0 = time.perf_counter()
        before = world.cell_checks
        path_cells = search.shortcut(world, path_cells)
        checks += world.cell_checks - before
        seconds += time.perf_counter() - t0
        path, more, length = _joined_path(world, s, path_cells, g)
        joins += more
    lat = world.lattice
    out = PlanResult(
        found=True, path=path, cells=path_cells, length=length, cell_checks=checks,
        expansions=res.expansions, generated=res.generated, seconds=seconds,
        lattice=lat.name or "custom",
        cell_volume=lat.cell_area if world.dim == 2 else lat.cell_volume, method=method,
        neighbors=neighbors, peak_bytes=res.peak_bytes,
        build_seconds=world.build_seconds or 0.0,
        extra={"cost_between_centres": res.cost, "raw_length": raw_length,
               "smoothed_length": length if shortcut else None, "join_checks": joins},
        guarantee=res.guarantee, unknown_cells=unknown_on_path(world, path),
        unknown_note=world.unknown_note,
    )
    return _in_map_frame(out, world) if world.local_frame else out


def _common(world: World, method: str, neighbors: str) -> dict:
    """The :class:`PlanResult` fields saying what was planned on, by name."""
    lat = world.lattice
    return dict(lattice=lat.name or "custom",
                cell_volume=lat.cell_area if world.dim == 2 else lat.cell_volume,
                method=method, neighbors=neighbors, build_seconds=world.build_seconds or 0.0,
                unknown_note=world.unknown_note)


def _in_map_frame(res: PlanResult, world) -> PlanResult:
    """A result planned in a world's local frame with its path in the map's frame, and the
    offset recorded (``extra["local_offset"]``, m)."""
    res.path = world.to_map(res.path)
    res.extra["local_offset"] = world.offset.tolist()
    return res


def _joined_path(world: World, s, cells: np.ndarray, g) -> tuple[np.ndarray, int, float]:
    """:func:`joined` of the path from start point ``s`` through the centres of ``cells``
    ((K, 3) int64) to goal point ``g`` (``s``, ``g``: three Python floats, m), the lookups
    it made (also added to ``world.cell_checks``) and its length (m, :func:`path_length`'s
    float). The centres come from :meth:`Lattice.to_world` (BLAS's floats, which a compiled
    loop does not reproduce), all the rest from one compiled call; the joined path is a
    view of the first rows of the array it fills."""
    path = np.empty((len(cells) + 2, 3))
    world.lattice.to_world(cells, out=path[1:-1])
    m, n, length = world.checker.join(path, *s, *g)
    world.cell_checks += n
    if m <= SHORT_PATH:  # rows_length's float; numpy sums longer paths in another order
        return path[:m], n, length
    return path[:m], n, path_length(path[:m], 0.0)


def joined(world, path: np.ndarray) -> np.ndarray:
    """The path a robot drives from a lattice path ``path`` (K + 2, 3): the start point, the
    centres of the K cells searched (the start's cell first, the goal's last), the goal
    point (m, the world's frame).

    The start joins the second cell's centre directly when that segment passes the
    search's own validity rule (:meth:`World.segment_free`: every cell it touches is free),
    so the path does not first hop to the centre of the start's cell, often backwards; the
    goal joins the last cell but one likewise. Otherwise the hop stays (it lies in the
    cell, which is free). Consecutive points equal to 1 um are merged (a start at a cell
    centre). Each check counts in :attr:`World.cell_checks`.

    Returns
    -------
    ndarray, shape (K', 3), K' <= K + 2
        Starts exactly at ``path[0]`` and ends exactly at ``path[-1]``.

    On a :class:`World` these steps run in one compiled call
    (:func:`planner.world.join.join_path`); any other object with a ``segment_free``
    takes them here, in Python.
    """
    if isinstance(world, World):  # one compiled call, on a copy
        p = np.array(path, dtype=np.float64, order="C")
        if p.ndim == 2 and p.shape[1] == 3 and len(p) >= 2 and np.isfinite(p).all():
            m, looked, _ = world.checker.join(p, *p[0].tolist(), *p[-1].tolist())
            world.cell_checks += looked
            return p[:m]
    n = len(path)
    if n < 3:
        return distinct(path)
    first = world.segment_free(path[0], path[2])  # start -> the second cell's centre
    last = False  # one cell (n = 3): its centre goes with the first join, or stays
    if n > 3:
        prev = 0 if n == 4 and first else n - 3  # the point before the goal's cell centre
        last = world.segment_free(path[prev], path[-1])
    if first or last:
        path = path[[i for i in range(n) if not (i == 1 and first or i == n - 2 and last)]]
    return distinct(path)


def distinct(path: np.ndarray) -> np.ndarray:
    """``path`` (K, d) with each point equal to the one before it to 1 um dropped (the
    last point is kept: a path ends exactly at its goal)."""
    if len(path) < 2:
        return path
    if len(path) <= SHORT_PATH:  # np.round's values (rint of um), without its temporaries
        r = [tuple(round(v * 1e6) for v in row) for row in path.tolist()]
        same = [r[i + 1] == r[i] for i in range(len(r) - 1)]
        if not any(same):
            return path
        same = np.array(same)
    else:
        r = np.round(path, 6)
        same = np.all(r[1:] == r[:-1], axis=1)
    if not same.any():
        return path
    keep = np.concatenate([[True], ~same])
    keep[-1] = True
    if same[-1]:  # the goal replaces the point before it
        keep[-2] = len(path) == 2
    return path[keep]


def describe(res: PlanResult, world=None) -> str:
    """One human-readable line about a :class:`PlanResult` (what ``planner plan`` prints);
    with its ``world``, a ``WARNING:`` line follows for each of :func:`world_warnings` (a
    cloud without a sensor origin, whose unseen space counted as free)."""
    ompl = res.method.startswith("ompl:")
    planar = world is not None and world.dim == 2
    size = (f"cell area {res.cell_volume:.6g} m^2, edge {res.cell_volume ** 0.5:.4g} m"
            if planar else
            f"cell volume {res.cell_volume:.6g} m^3, edge {res.cell_volume ** (1 / 3):.4g} m")
    head = f"{res.lattice} ({size}), {res.method}" + (
        " (continuous, validated on this lattice's world)" if ompl else f", {res.neighbors}")
    unseen = "".join(f"\nWARNING: {w}" for w in world_warnings(world))
    if not res.found:
        return f"{head}: no path ({res.reason}); {res.cell_checks} cell checks{unseen}"
    work = "" if ompl else f", {res.expansions} expansions"
    note = (f"; {res.reason}" if res.reason else "") + unseen
    return (
        f"{head}: length {res.length:.3f} m, {len(res.path)} waypoints, "
        f"{res.cell_checks} cell checks{work}, "
        f"{res.seconds * 1e3:.1f} ms search (+{res.build_seconds:.2f} s map build){note}"
    )


def unknown_on_path(world, path: np.ndarray) -> int:
    """Distinct cells meeting unknown space that the polyline ``path`` ((K, 3), m) touches
    (every cell whose closed Voronoi cell a segment touches)."""
    if not world.has_unknown or len(path) == 0:
        return 0
    parts = [world.segment_cells(a, b) for a, b in zip(path[:-1], path[1:], strict=True)]
    cells = np.concatenate(parts) if parts else world.lattice.quantize(path[:1])
    cells = np.unique(cells, axis=0)
    return int(world.is_unknown(cells).sum())


def _plan_ompl(world, s, g, planner_name, time_limit, seed, common) -> PlanResult:
    """An OMPL plan from ``s`` to ``g`` (map frame, as the path it returns)."""
    r = ompl.plan_ompl(world, s, g, planner=planner_name, time_limit=time_limit, seed=seed)
    path = r.path_simplified if r.path_simplified is not None else r.path
    d = r.to_dict()
    return PlanResult(
        found=r.found, path=path if r.found else np.zeros((0, 3)),
        cells=np.zeros((0, 3), np.int64), length=r.length if r.found else math.inf,
        cell_checks=r.cell_checks, expansions=0, generated=0, seconds=r.seconds,
        reason=r.reason, extra={k: v for k, v in d.items() if k not in ("path", "path_simplified")},
        status="found" if r.found else r.status, guarantee=True,
        unknown_cells=unknown_on_path(world, world.to_local(path)) if r.found else 0,
        **common,
    )
