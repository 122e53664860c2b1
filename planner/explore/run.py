"""Exploration simulation: a robot plans through a map it does not know, senses, and replans.

The robot (radius ``r``) starts at a cell of an empty *known* world (unknown space treated as
free, the classic assumption) and walks its current path one lattice move at a time.
After every move it senses, blocks the newly seen obstacles in the known world and, when
anything changed, replans with the replanner named by ``replanner`` (:data:`REPLANNERS`):
``"astar"`` (the default) keeps the path unless a newly blocked cell touches its rest and
then runs A* from the robot's cell (:class:`planner.search.replanner.AStarReplanner`);
``"dstar"`` repairs with D* Lite (:class:`planner.search.dstar.lite.DStarLite`). Each
replan is also solved from scratch with A* on the same map state in the same process, and
the two costs must agree (counted as ``mismatches``).

Sensor: :mod:`planner.explore.sensor` (exact rays through the lattice against the true map's
occupied cells; a hit reveals the obstacles of the cell it stops in).

Known map: the revealed obstacles, inflated for the radius by the same rule as the true
world (:func:`planner.voxels.from_map.inflated_obstacles`: points exactly, boxes grown by the
radius), only around the newly revealed ones, so the known blocked cells are a subset of the
true world's. Hence a move the robot takes is safe on what it knew, and a goal unreachable in
the known world is unreachable in the true one. Every executed move is also walked in the
true inflated world: a blocked cell there is a ``contact`` (an obstacle within ``r`` that
the sensor had not seen).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from planner import io
from planner.budget import require
from planner.errors import MapError, PlanError
from planner.explore.figures import animate_gif, summary_png
from planner.explore.sensor import Sensor, cast_rays, ray_directions
from planner.lattice import Lattice
from planner.maps import resolve
from planner.occupancy.walk import walk_of
from planner.progress import Progress
from planner.voxels.from_map import inflated_obstacles
from planner.world import World
from planner.world.build import (
    as_obstacles,
    build_world,
    lift_planar,
    resolve_defaults,
    sidecar,
)

__all__ = ["ExploreResult", "REPLANNERS", "explore", "ray_directions", "cast_rays"]

#: the replanners :func:`explore` takes by name (module docstring), the default first
REPLANNERS = ("astar", "dstar")


@dataclass
class ExploreResult:
    """One exploration run.

    Attributes
    ----------
    status : str
        ``"reached"``, ``"unreachable"`` (no path even through unknown space: proved),
        ``"stuck"`` (the robot's own cell became blocked: it touched an unseen obstacle)
        or ``"budget"`` (``max_steps`` moves made).
    distance : float
        Length travelled between cell centres (m).
    trajectory : ndarray (T, 3)
        Cell centres visited, start first (m).
    replanner : str
        The replanner that ran (a key of :data:`REPLANNERS`).
    changed, replan_checks, astar_checks, replan_expansions, astar_expansions : ndarray (R,)
        Per replan: cells whose state changed, occupancy lookups, expansions.
    replan_seconds, astar_seconds, replan_cost, astar_cost : ndarray (R,) float
        Per replan: the replanner's and A*'s own time
        (:attr:`planner.search.SearchResult.seconds`: their compiled calls, without the
        Python that checks arguments and builds results; for D* Lite the changes' repair,
        the search and the path; for ``"astar"`` the path check and, when it searched,
        the search) (s); path costs (m, inf when unreachable). The two run in turn right
        after the map update, the replanner first on even replans: the first of the two
        finds caches cold. :attr:`searched` says which replans searched.
    mismatches : int
        Replans whose two costs differ by more than 1e-9 m (or only one is unreachable).
    contacts : int
        Executed moves that touch a cell of the true inflated world.
    """

    lattice: str
    status: str
    distance: float
    trajectory: np.ndarray
    changed: np.ndarray
    replan_seconds: np.ndarray
    replan_checks: np.ndarray
    replan_expansions: np.ndarray
    replan_cost: np.ndarray
    astar_seconds: np.ndarray
    astar_checks: np.ndarray
    astar_expansions: np.ndarray
    astar_cost: np.ndarray
    mismatches: int
    contacts: int
    start: np.ndarray
    goal: np.ndarray
    points: np.ndarray = field(repr=False)  # (N, 3) true obstacle points (m)
    seen: np.ndarray = field(repr=False)  # (N,) bool: revealed by the sensor
    rays: int = 0  # rays cast in total
    sense_seconds: float = 0.0
    radius: float = 0.0  # robot radius (m)
    # For the animation: per replan, the moves made before it and its path (K, 3) m;
    # per obstacle the move count at which it was first seen (-1 never); per scan (one per
    # trajectory point) the ranges (m) of the horizontal rays at ``ring_azimuths`` (rad).
    replan_step: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64),
                                    repr=False)
    paths: list = field(default_factory=list, repr=False)
    seen_step: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64),
                                  repr=False)
    ring_ranges: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)), repr=False)
    ring_azimuths: np.ndarray = field(default_factory=lambda: np.zeros(0), repr=False)
    # Per replan, the wall time of the calls a user makes (s): the replanner's ``update``
    # and ``plan``, A*'s ``search`` (argument and endpoint checks, result, Python included).
    replan_wall_seconds: np.ndarray = field(default_factory=lambda: np.zeros(0), repr=False)
    astar_wall_seconds: np.ndarray = field(default_factory=lambda: np.zeros(0), repr=False)
    # The same calls' CPU time (s, the thread's: a run on a shared machine is not charged
    # for the time the thread waited; what the whole-run ratio is read from)
    replan_cpu_seconds: np.ndarray = field(default_factory=lambda: np.zeros(0), repr=False)
    astar_cpu_seconds: np.ndarray = field(default_factory=lambda: np.zeros(0), repr=False)
    replanner: str = "astar"
    replan_phase_seconds: np.ndarray = field(default_factory=lambda: np.zeros((0, 4)), repr=False)

    @property
    def replans(self) -> int:
        return len(self.changed)

    @property
    def searched(self) -> np.ndarray:
        """(R,) bool: the replans that searched (a kept path makes no cell check)."""
        return self.replan_checks > 0

    def ratios(self) -> dict:
        """Medians over the replans after the first (the first plan has nothing to reuse)
        of replanner / from-scratch time and cell checks, and the totals' ratios: the
        whole run's replanning against A* from scratch at every replan on the same map
        states, first plan included (``total_time_ratio``: engine time;
        ``total_cpu_ratio``: the thread's CPU time of the calls a user makes)."""
        k = slice(1, None) if self.replans > 1 else slice(None)
        with np.errstate(divide="ignore", invalid="ignore"):
            rt = self.replan_seconds[k] / self.astar_seconds[k]
            rc = self.replan_checks[k] / self.astar_checks[k]
            rw = self.replan_wall_seconds[k] / self.astar_wall_seconds[k]
        return {"median_time_ratio": float(np.median(rt)) if len(rt) else math.nan,
                "median_wall_ratio": float(np.median(rw)) if len(rw) else math.nan,
                "median_checks_ratio": float(np.median(rc)) if len(rc) else math.nan,
                "total_time_ratio": _div(self.replan_seconds.sum(), self.astar_seconds.sum()),
                "total_wall_ratio": _div(self.replan_wall_seconds.sum(),
                                         self.astar_wall_seconds.sum()),
                "total_cpu_ratio": _div(self.replan_cpu_seconds.sum(),
                                        self.astar_cpu_seconds.sum()),
                "total_checks_ratio": _div(self.replan_checks.sum(), self.astar_checks.sum())}

    def summary(self) -> dict:
        """Plain numbers for printing or JSON."""
        return {"lattice": self.lattice, "status": self.status,
                "distance_m": round(self.distance, 3), "moves": len(self.trajectory) - 1,
                "replanner": self.replanner, "replans": self.replans,
                "searched": int(self.searched.sum()), "mismatches": self.mismatches,
                "contacts": self.contacts, "points_seen": int(self.seen.sum()),
                "replan_checks": int(self.replan_checks.sum()),
                "astar_checks": int(self.astar_checks.sum()),
                "replan_seconds": round(float(self.replan_seconds.sum()), 4),
                "astar_seconds": round(float(self.astar_seconds.sum()), 4),
                **{k: round(v, 4) for k, v in self.ratios().items()}}

    def plot(self, path: str | Path) -> Path:
        """Summary figure (PNG): top view with the true and the seen obstacles and the
        trajectory; per-replan cell checks and times of the replanner and A*. Written
        atomically.
        """
        return summary_png(self, path)

    def animate(self, path: str | Path, max_frames: int = 150, fps: float = 6.0) -> Path:
        """Animated GIF of the run, one frame per replan (evenly subsampled to at most
        ``max_frames``): observed area, seen obstacles, trajectory, current plan, goal
        (:func:`planner.explore.figures.animate_gif`). Written atomically."""
        return animate_gif(self, path, max_frames=max_frames, fps=fps)


def _div(a, b) -> float:
    return float(a) / float(b) if b else math.nan


def explore(
    source,
    start,
    goal,
    *,
    lattice: str | Lattice | None = None,
    radius: float | None = None,
    cell_volume: float | None = None,
    bounds=None,
    sensor_range: float = 4.0,
    fov=(360.0, 30.0),
    resolution: float = 3.0,
    neighbors: str = "full",
    max_steps: int = 100_000,
    progress: bool = False,
    replanner: str = "astar",
    phases: bool = False,
) -> ExploreResult:
    """Explore from ``start`` to ``goal`` (points, m) in a map the robot does not know.

    Parameters
    ----------
    source : str, Path, ndarray (N, 3) or Obstacles
        The true map (as :func:`planner.build_world` takes it, bundled names too). Point
        maps are sensed by the cells holding their points; box maps (``.3dmap``, OctoMap
        leaves) by the cells overlapping their boxes, and a seen box is inflated as a box.
    start, goal : array_like, shape (3,)
        Metres; must be free in the true inflated world.
    lattice, cell_volume, bounds
        As :func:`planner.build_world` (defaults: the map's).
    radius : float, optional
        Robot radius (m); default the map's ``robot_radius`` (a map without one needs it).
    sensor_range : float
        Ray length (m).
    fov : (float, float)
        Horizontal field of view (degrees, total) and vertical half-angle (degrees).
    resolution : float
        Angle between neighbouring rays (degrees).
    neighbors : str
        Move set of both searches.
    max_steps : int
        Give up (status ``"budget"``) after this many moves.
    progress : bool
        Show on stderr the moves made of those made plus those left on the current plan,
        with an ETA (:class:`planner.progress.Progress`; the estimate grows when a replan
        finds a longer way).
    replanner : {"astar", "dstar"}
        :data:`REPLANNERS` (module docstring). ``"astar"``: over whole runs on the bundled
        office and on geb079 it costs a fraction of A* at every replan, D* Lite more
        (``benchmarks/explore_speed.py``).
    phases : bool
        ``"dstar"`` only: replan_phase_seconds (R, 4), from ``DStarLite.plan_phases``.

    Returns
    -------
    ExploreResult
    """
    from planner.search import search  # lazy: numba
    if replanner not in REPLANNERS:
        raise PlanError(f"unknown replanner {replanner!r}; expected one of "
                        f"{', '.join(REPLANNERS)}")
    if phases and replanner != "dstar":
        raise PlanError("phases=True times D* Lite's phases: it needs replanner='dstar'")
    planner_class = _replanner_class(replanner)
    if isinstance(source, str | Path):  # a bundled map by name ("office"), as build_world
        source = resolve(source)
    side = sidecar(source)
    if not (isinstance(sensor_range, int | float) and math.isfinite(sensor_range)
            and sensor_range > 0):
        raise PlanError(f"sensor_range must be a positive number of metres, got "
                        f"{sensor_range!r}")
    if isinstance(max_steps, bool) or not isinstance(max_steps, int) or max_steps < 0:
        raise PlanError(f"max_steps must be a non-negative integer, got {max_steps!r}")
    dirs = ray_directions(fov, resolution)
    obst = as_obstacles(source)
    # The true world is what a sensor can hit: the obstacles. A map's unobserved space (an
    # OctoMap's unknown leaves) is not an obstacle here, so it counts as free.
    got = resolve_defaults(obst, side, lattice=lattice, cell_volume=cell_volume,
                           radius=radius, unknown="free", bounds=bounds)
    radius = got.radius
    truth = build_world(obst, got.lattice, radius=radius, bounds=got.bounds, unknown="free")
    lat = truth.lattice
    if obst.dim == 2:  # sensed in the plane z = 0 the world is planned in: a planar scanner
        obst = lift_planar(obst)
        dirs = ray_directions((fov[0], 0.0), resolution)
    boxes = len(obst.boxes) > 0 and (not len(obst.points) or np.array_equal(obst.points,
                                                                           obst.boxes))
    pts = obst.boxes if boxes else obst.points
    if not len(pts):
        raise MapError(f"{obst.source}: no obstacles to sense")
    if truth.local_frame:
        raise MapError(f"{obst.source}: explore needs a map near its frame's origin; this "
                       f"one lies {np.abs(truth.offset).max():.0f} m away (shift its points)")
    start_p, s = truth.endpoint(start, "start")
    goal_p, gcell = truth.endpoint(goal, "goal")
    known = World(lat, np.zeros((0, 3), np.int64), truth.bounds, radius=truth.radius,
                  source=f"explored {obst.source}")
    sensor = Sensor(pts, obst.box_sizes if boxes else None, lat, walk_of(lat), dirs,
                     _sensor_reach(sensor_range, truth, pts, lat))
    _warm_up(lat, neighbors, planner_class)
    # The first search on a world touches the pages of its pooled A* scratch (the dense
    # slot array, :mod:`planner.search.astar._pool`), charged to whichever search runs
    # first: both the replanner's and A*'s would pay it once. Touched here, off the clocks.
    search(known, s, gcell, method="astar", neighbors=neighbors)
    dl = planner_class(known, s, gcell, neighbors=neighbors)
    rec = {k: [] for k in ("changed", "ds", "dc", "de", "dcost", "as", "ac", "ae", "acost",
                           "step", "dw", "aw", "dcpu", "acpu")}
    paths, phase_secs = [], []
    cur = s.copy()
    traj = [cur.copy()]
    status, distance, contacts, mismatches, path, at = "budget", 0.0, 0, 0, None, 0
    sense_secs = 0.0
    bar = Progress(1, "moves", label=f"exploring on {lat.name or 'custom'}",
                   enabled=progress)
    with bar:  # ends the live line also when a search raises
        for _step in range(max_steps + 1):
            t0 = time.perf_counter()
            new = sensor.scan(cur, _step)
            changed = np.zeros((0, 3), np.int64)
            if len(new):
                seen = io.Obstacles(
                    points=obst.points[new] if len(obst.points) else np.zeros((0, 3)),
                    boxes=obst.boxes[new] if boxes else np.zeros((0, 3)),
                    box_size=obst.box_size, box_sizes=obst.box_sizes[new] if boxes else None,
                    bounds=None, resolution=None, source=obst.source)
                cells = inflated_obstacles(seen, lat, radius).indices
                changed = known.set_cells(cells, True)
            sense_secs += time.perf_counter() - t0
            if path is None or len(changed):
                # Whichever search runs first after the map update finds its code and data
                # out of cache (tens of us): the order alternates, so each pays it on half
                # the replans.
                a_first = len(rec["ds"]) % 2 == 1
                if a_first:
                    a = _scratch_astar(search, known, cur, gcell, neighbors)
                c0, t0 = time.thread_time(), time.perf_counter()
                dl.update(changed, blocked=True)
                r, secs = dl.plan_phases() if phases else (dl.plan(), None)
                rec["dw"].append(time.perf_counter() - t0)
                rec["dcpu"].append(time.thread_time() - c0)
                phase_secs += [secs] if phases else []
                if not a_first:
                    a = _scratch_astar(search, known, cur, gcell, neighbors)
                rec["changed"].append(len(changed))
                rec["step"].append(_step)
                paths.append(lat.to_world(r.cells) if len(r.cells) else np.zeros((0, 3)))
                rec["ds"].append(r.seconds)
                rec["dc"].append(r.cell_checks)
                rec["de"].append(r.expansions)
                rec["dcost"].append(r.cost)
                for k, v in zip(("as", "aw", "acpu", "ac", "ae", "acost"), a, strict=True):
                    rec[k].append(v)
                if not _same(r.cost, a[5]):
                    mismatches += 1
                if r.status == "blocked":
                    status = "stuck"
                    break
                if not r.found:
                    status = "unreachable"
                    break
                path, at = r.cells, 0
                bar.set_total(len(traj) - 1 + len(path) - 1)
            if np.array_equal(cur, gcell):
                status = "reached"
                break
            if _step == max_steps:
                break
            nxt = path[at + 1]
            a_p, b_p = lat.to_world(np.stack([cur, nxt]))
            if not known.segment_free(a_p, b_p):  # cannot happen: the plan is on this map
                raise PlanError(f"internal: planned move {cur} -> {nxt} is blocked")
            if not truth.segment_free(a_p, b_p):
                contacts += 1
            distance += float(np.linalg.norm(b_p - a_p))
            cur, at = nxt.copy(), at + 1
            traj.append(cur.copy())
            dl.move_start(cur)
            bar.step()
    arr = {k: np.array(v) for k, v in rec.items()}
    return ExploreResult(
        lattice=lat.name or "custom", status=status, distance=distance,
        trajectory=lat.to_world(np.array(traj)), changed=arr["changed"].astype(np.int64),
        replan_seconds=arr["ds"].astype(float), replan_checks=arr["dc"].astype(np.int64),
        replan_expansions=arr["de"].astype(np.int64), replan_cost=arr["dcost"].astype(float),
        astar_seconds=arr["as"].astype(float), astar_checks=arr["ac"].astype(np.int64),
        astar_expansions=arr["ae"].astype(np.int64), astar_cost=arr["acost"].astype(float),
        mismatches=mismatches, contacts=contacts, start=start_p, goal=goal_p, points=pts,
        seen=sensor.seen, rays=len(dirs) * len(traj), sense_seconds=sense_secs,
        radius=float(truth.radius), replan_step=arr["step"].astype(np.int64), paths=paths,
        seen_step=sensor.seen_step, ring_azimuths=sensor.ring_azimuths,
        replan_wall_seconds=arr["dw"].astype(float), astar_wall_seconds=arr["aw"].astype(float),
        replan_cpu_seconds=arr["dcpu"].astype(float), astar_cpu_seconds=arr["acpu"].astype(float),
        replanner=replanner,
        replan_phase_seconds=np.array(phase_secs).reshape(-1, 4),
        ring_ranges=np.array(sensor.ring_ranges).reshape(len(sensor.ring_ranges),
                                                         len(sensor.ring)))


def _replanner_class(name: str):
    """The class of the replanner named ``name`` (:data:`REPLANNERS`)."""
    from planner.search.dstar.lite import DStarLite  # lazy: numba
    from planner.search.replanner import AStarReplanner  # lazy: numba

    return {"astar": AStarReplanner, "dstar": DStarLite}[name]


def _warm_up(lat: Lattice, neighbors: str, dstar) -> None:
    """Compile (or load) the replanner's kernels on a tiny world of the same lattice, so
    that no replan's time includes JIT compilation (:func:`planner.search.search` warms up
    A* itself before its clock starts)."""
    r = lat.covering_radius
    tiny = World(lat, np.zeros((0, 3), np.int64), [[-4 * r] * 3, [4 * r] * 3])
    a = lat.quantize(np.zeros((1, 3)))[0]
    b = lat.quantize(np.array([[2.5 * r, 0.0, 0.0]]))[0]
    mid = lat.quantize(np.array([[1.2 * r, 0.0, 0.0]]))
    dl = dstar(tiny, a, b, neighbors=neighbors)
    dl.plan()
    dl.update(tiny.set_cells(mid, True), blocked=True)
    dl.plan()


def _scratch_astar(search, world, cur, goal, neighbors
                   ) -> tuple[float, float, float, int, int, float]:
    """(seconds, wall seconds, CPU seconds, cell checks, expansions, cost) of A* from
    scratch: the engine's own timing of the search (``SearchResult.seconds``), the wall
    and the thread's CPU time of the ``search`` call; a blocked end is unreachable (one
    lookup each, as A*'s endpoint check; the engine's time is the wall time of that
    refusal)."""
    c0, t0 = time.thread_time(), time.perf_counter()
    try:
        r = search(world, cur, goal, method="astar", neighbors=neighbors)
    except PlanError:
        wall = time.perf_counter() - t0
        return wall, wall, time.thread_time() - c0, 2, 0, math.inf
    wall = time.perf_counter() - t0
    return r.seconds, wall, time.thread_time() - c0, r.cell_checks, r.expansions, r.cost


def _same(a: float, b: float) -> bool:
    return (math.isinf(a) and math.isinf(b)) or abs(a - b) <= 1e-9


def _sensor_reach(sensor_range: float, truth, pts: np.ndarray, lat) -> float:
    """The range a ray is cast over (m): ``sensor_range``, cut to the diagonal of the box
    holding the world and every obstacle (nothing lies farther), and checked against the
    memory budget (each ray's walk scratch grows with its length)."""
    lo = np.minimum(truth.bounds[0], pts.min(axis=0))
    hi = np.maximum(truth.bounds[1], pts.max(axis=0))
    reach = min(float(sensor_range), float(np.linalg.norm(hi - lo)) + 2 * lat.covering_radius)
    walk = walk_of(lat)
    step = float(np.sqrt(2.0 * walk.rhs.min()))
    # walk_scratch: two int64 tables of twice the estimate, a queue of a quarter of it
    est = (reach / step + 4) * (len(walk.full) + 1)
    require(est * 8 * (4 + 3 / 4), f"the ray walk of --sensor-range {sensor_range:g} m "
            f"({reach:.3g} m inside the map)", error=PlanError)
    return reach
