"""Exploration simulation: a robot plans through a map it does not know, senses, and replans.

The robot (radius ``r``) starts at a cell of an empty *known* world (unknown space treated as
free, the classic assumption) and walks its current D* Lite path one lattice move at a time.
After every move it senses, blocks the newly seen obstacles in the known world and, when
anything changed, repairs the plan with :class:`planner.search.incremental.DStarLite`. Each
replan is also solved from scratch with A* on the same map state in the same process, and
the two costs must agree (counted as ``mismatches``).

Sensor (exact, noise-free): rays from the robot's position over a field of view (``fov``:
horizontal total and vertical +- half-angle, degrees) at ``resolution`` degrees, up to
``sensor_range`` metres. The true map is the lattice occupied voxel list of the obstacle
points (radius 0), or of the cells overlapping the boxes of a box map (OctoMap leaves,
``.3dmap``); a ray stops at the occupied cell whose closed Voronoi cell it enters first (the
lattice segment walk plus the exact entry parameter of each touched cell). A hit reveals
every obstacle point in that cell, or every box that can overlap it (a lidar return from
that surface patch).

Known map: the revealed obstacles, inflated for the radius by the same rule as the true
world (:func:`planner.api.inflated_obstacles`: points exactly, boxes grown by the radius),
only around the newly revealed ones, so the known blocked cells are a subset of the true
world's. Hence a move the robot takes is safe on what it knew, and a goal unreachable in
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
from numba import njit

from planner._world_kernels import Occupancy, occ_free, walk_on, walk_scratch
from planner.errors import MapError, PlanError
from planner.fsutil import atomic_path
from planner.keys import pack
from planner.lattice import Lattice
from planner.world import World

__all__ = ["ExploreResult", "explore", "ray_directions", "cast_rays"]


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
    changed, dstar_checks, astar_checks, dstar_expansions, astar_expansions : ndarray (R,)
        Per replan: cells whose state changed, occupancy lookups, expansions.
    dstar_seconds, astar_seconds, dstar_cost, astar_cost : ndarray (R,) float
        Per replan: wall time of the repair (update + plan) and of the scratch A* (s),
        path costs (m, inf when unreachable).
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
    dstar_seconds: np.ndarray
    dstar_checks: np.ndarray
    dstar_expansions: np.ndarray
    dstar_cost: np.ndarray
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

    @property
    def replans(self) -> int:
        return len(self.changed)

    def ratios(self) -> dict:
        """Medians over the replans after the first (the first plan has nothing to reuse)
        of incremental / from-scratch time and cell checks, and the totals' ratios."""
        k = slice(1, None) if self.replans > 1 else slice(None)
        with np.errstate(divide="ignore", invalid="ignore"):
            rt = self.dstar_seconds[k] / self.astar_seconds[k]
            rc = self.dstar_checks[k] / self.astar_checks[k]
        return {"median_time_ratio": float(np.median(rt)) if len(rt) else math.nan,
                "median_checks_ratio": float(np.median(rc)) if len(rc) else math.nan,
                "total_time_ratio": _div(self.dstar_seconds.sum(), self.astar_seconds.sum()),
                "total_checks_ratio": _div(self.dstar_checks.sum(), self.astar_checks.sum())}

    def summary(self) -> dict:
        """Plain numbers for printing or JSON."""
        return {"lattice": self.lattice, "status": self.status,
                "distance_m": round(self.distance, 3), "moves": len(self.trajectory) - 1,
                "replans": self.replans, "mismatches": self.mismatches,
                "contacts": self.contacts, "points_seen": int(self.seen.sum()),
                "dstar_checks": int(self.dstar_checks.sum()),
                "astar_checks": int(self.astar_checks.sum()),
                "dstar_seconds": round(float(self.dstar_seconds.sum()), 4),
                "astar_seconds": round(float(self.astar_seconds.sum()), 4),
                **{k: round(v, 4) for k, v in self.ratios().items()}}

    def plot(self, path: str | Path) -> Path:
        """Summary figure (PNG): top view with the true and the seen obstacles and the
        trajectory; per-replan cell checks and times of D* Lite and A*. Written atomically.
        """
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        fig, (ax, ac, at) = plt.subplots(1, 3, figsize=(16, 5),
                                         gridspec_kw={"width_ratios": [1.6, 1, 1]})
        z = self.trajectory[:, 2]
        band = np.abs(self.points[:, 2] - np.median(z)) <= 0.5  # a slice at robot height
        pts = self.points[band]
        ax.scatter(pts[:, 0], pts[:, 1], s=0.3, c="0.8", label="true obstacles (slice)")
        sp = self.points[band & self.seen]
        ax.scatter(sp[:, 0], sp[:, 1], s=0.5, c="k", label="seen")
        ax.plot(self.trajectory[:, 0], self.trajectory[:, 1], "-", c="tab:red", lw=1.5,
                label=f"robot, {self.distance:.1f} m")
        ax.plot(*self.start[:2], "o", c="tab:green", label="start")
        ax.plot(*self.goal[:2], "*", c="tab:blue", ms=12, label="goal")
        ax.set_aspect("equal")
        ax.set_title(f"{self.lattice}: {self.status}, {self.replans} replans, "
                     f"{self.mismatches} mismatches, {self.contacts} contacts", fontsize=9)
        ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(0.0, -0.08), ncol=3,
                  frameon=False)
        i = np.arange(self.replans)
        for a, (d, s, what) in ((ac, (self.dstar_checks, self.astar_checks, "cell checks")),
                                (at, (self.dstar_seconds, self.astar_seconds, "seconds"))):
            a.semilogy(i, s, ".", c="0.5", label="A* from scratch")
            a.semilogy(i, d, ".", c="tab:red", label="D* Lite (update + plan)")
            a.set_xlabel("replan")
            a.set_title(f"{what} per replan", fontsize=9)
            a.legend(fontsize=7)
        fig.tight_layout()
        out = Path(path)
        with atomic_path(out) as tmp:
            fig.savefig(tmp, dpi=110, format="png")
        plt.close(fig)
        return out


def _div(a, b) -> float:
    return float(a) / float(b) if b else math.nan


def ray_directions(fov=(360.0, 30.0), resolution: float = 3.0) -> np.ndarray:
    """Unit ray directions (R, 3): azimuths over ``fov[0]`` degrees (centred on +x) and
    elevations over +-``fov[1]`` degrees, both every ``resolution`` degrees."""
    try:
        h, v = (float(x) for x in fov)
        res = float(resolution)
    except (TypeError, ValueError):
        raise PlanError(f"fov must be (horizontal, vertical) degrees, got {fov!r}") from None
    if not (0 < h <= 360 and 0 <= v <= 90 and 0 < res <= 90):
        raise PlanError(f"need 0 < horizontal fov <= 360, 0 <= vertical half-fov <= 90 and "
                        f"0 < resolution <= 90 degrees, got {fov!r}, {resolution!r}")
    na = max(1, int(round(h / res)))
    az = np.arange(na) * (h / na) if h >= 360 else np.linspace(-h / 2, h / 2, na + 1)
    nv = int(round(v / res))
    el = np.linspace(-v, v, 2 * nv + 1) if nv else np.zeros(1)
    a, e = np.meshgrid(np.radians(az), np.radians(el), indexing="ij")
    a, e = a.ravel(), e.ravel()
    return np.ascontiguousarray(np.stack([np.cos(e) * np.cos(a), np.cos(e) * np.sin(a),
                                          np.sin(e)], axis=1))


@njit(cache=True)
def _entry(u0, u1, u2, av, dq, wv, nrel):  # pragma: no cover - compiled
    """Smallest t in [0, 1] at which a + t (b - a) is in the closed Voronoi cell at offset
    u from the walk's start cell (the clipping of ``_world_kernels._touches``)."""
    lo = 0.0
    for r in range(nrel):
        q = dq[r]
        if q < 0.0:
            t = (av[r] + (wv[r, 0] * u0 + wv[r, 1] * u1 + wv[r, 2] * u2)) * q
            if t > lo:
                lo = t
    return lo


@njit(cache=True)
def cast_rays(occupied, walk, origin, s, dirs, reach, hits):  # pragma: no cover - compiled
    """Cast rays from ``origin`` (m, in cell ``s``) along ``dirs`` (R, 3) for ``reach`` m
    against the occupied cells (an :class:`Occupancy` whose *blocked* cells are the
    obstacles). ``hits[r]`` (R, 3) gets the first occupied cell along ray r; returns (R,)
    bool, False where the ray ends in free space."""
    rel, rhs, wv = walk.rel, walk.rhs, walk.wv
    nrel = rel.shape[0]
    c0 = walk.g @ s.astype(np.float64)
    av = np.empty(nrel)
    dq = np.empty(nrel)
    b = np.empty(3)
    found = np.zeros(dirs.shape[0], np.bool_)
    step = np.sqrt(2.0 * rhs.min())
    scale = 1.0
    vis, vgen, queue = walk_scratch(reach, step, walk.full.shape[0])
    gen = 0
    for k in range(dirs.shape[0]):
        for j in range(3):
            b[j] = origin[j] + reach * dirs[k, j]
        for r in range(nrel):
            x = ((origin[0] - c0[0]) * rel[r, 0] + (origin[1] - c0[1]) * rel[r, 1]
                 + (origin[2] - c0[2]) * rel[r, 2])
            av[r] = rhs[r] * (1.0 + 1e-9) - x
            y = ((b[0] - origin[0]) * rel[r, 0] + (b[1] - origin[1]) * rel[r, 1]
                 + (b[2] - origin[2]) * rel[r, 2])
            dq[r] = 1.0 / y if y != 0.0 else 0.0
        while True:
            gen += 1
            qt, _, _, ok = walk_on(occupied, walk, origin, b, s, False, vis, vgen, gen, queue)
            if ok:
                break
            scale *= 2.0  # scratch too small for this ray: grow it (stamps restart)
            vis, vgen, queue = walk_scratch(scale * reach + 1.0, step, walk.full.shape[0])
            gen = 0
        best = np.inf
        for n in range(qt):
            u0, u1, u2 = queue[n, 0], queue[n, 1], queue[n, 2]
            if occ_free(occupied, s[0] + u0, s[1] + u1, s[2] + u2):
                continue
            t = _entry(u0, u1, u2, av, dq, wv, nrel)
            if t < best:
                best = t
                hits[k, 0] = s[0] + u0
                hits[k, 1] = s[1] + u1
                hits[k, 2] = s[2] + u2
        found[k] = best < np.inf
    return found


class _Sensor:
    """The true map as the sensor sees it.

    Points (``box_sizes`` None): the occupied cells are those holding a point, and a hit
    reveals the points in the hit cell. Boxes (edge ``box_sizes[k]`` m each): the occupied
    cells are those overlapping a box (:func:`planner.voxels.box_keys`), so every ray
    through a box stops at or before it, and a hit reveals the boxes that can overlap the
    hit cell (centre within half the largest box diagonal plus the covering radius).
    """

    def __init__(self, points: np.ndarray, box_sizes: np.ndarray | None, lattice: Lattice,
                 walk, dirs: np.ndarray, reach: float):
        from planner._world_kernels import build_key_set

        self.points, self.boxes = points, box_sizes is not None
        if self.boxes:
            from scipy.spatial import cKDTree

            from planner.voxels import box_keys

            # each box at its own size (OctoMap's pruned leaves are larger than the rest)
            uniq = np.unique(np.concatenate([box_keys(points[box_sizes == b], b, lattice)
                                             for b in np.unique(box_sizes)]))
            self.tree = cKDTree(points)
            self.near = 0.5 * np.sqrt(3) * float(box_sizes.max()) + lattice.covering_radius
        else:
            keys = pack(lattice.quantize(points))
            self.order = np.argsort(keys, kind="stable")
            self.sorted = keys[self.order]
            uniq = np.unique(keys)
        size = 16
        while size < 2 * len(uniq):
            size *= 2
        big = np.full(3, np.inf)
        g = np.array(lattice.generator, dtype=float, order="C")
        self.occ = Occupancy(1, np.zeros(1, np.uint8), np.zeros(3, np.int64),
                             np.zeros(3, np.int64), build_key_set(uniq, size), size - 1, g,
                             -big, big.copy())
        self.walk, self.dirs, self.reach = walk, dirs, float(reach)
        self.lattice = lattice
        self.hits = np.zeros((len(dirs), 3), np.int64)
        self.seen = np.zeros(len(points), bool)

    def scan(self, cell: np.ndarray) -> np.ndarray:
        """Cast every ray from the centre of ``cell``; return the indices of the obstacles
        revealed for the first time."""
        origin = self.lattice.to_world(cell[None])[0]
        found = cast_rays(self.occ, self.walk, origin, cell, self.dirs, self.reach, self.hits)
        hit = np.unique(self.hits[found], axis=0)
        if not len(hit):
            return np.zeros(0, np.int64)
        if self.boxes:
            near = self.tree.query_ball_point(self.lattice.to_world(hit), self.near)
            idx = np.unique(np.concatenate([np.asarray(x, np.int64) for x in near]))
        else:
            keys = pack(hit)
            lo = np.searchsorted(self.sorted, keys, "left")
            hi = np.searchsorted(self.sorted, keys, "right")
            idx = self.order[np.concatenate([np.arange(a, b)
                                             for a, b in zip(lo, hi, strict=True)])]
        idx = idx[~self.seen[idx]]
        self.seen[idx] = True
        return idx


def explore(
    source,
    start,
    goal,
    *,
    lattice: str | Lattice = "fcc",
    radius: float | None = None,
    cell_volume: float | None = None,
    bounds=None,
    sensor_range: float = 4.0,
    fov=(360.0, 30.0),
    resolution: float = 3.0,
    neighbors: str = "full",
    max_steps: int = 100_000,
) -> ExploreResult:
    """Explore from ``start`` to ``goal`` (points, m) in a map the robot does not know.

    Parameters
    ----------
    source : str, Path, ndarray (N, 3) or Obstacles
        The true map (as :func:`planner.build_world` takes it). Point maps are sensed by
        the cells holding their points; box maps (``.3dmap``, OctoMap leaves) by the cells
        overlapping their boxes, and a seen box is inflated as a box.
    start, goal : array_like, shape (3,)
        Metres; must be free in the true inflated world.
    lattice, cell_volume, bounds
        As :func:`planner.build_world` (defaults: the map's).
    radius : float, optional
        Robot radius (m); default the bundled map's ``robot_radius``, else 0.
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

    Returns
    -------
    ExploreResult
    """
    from planner import io
    from planner.api import _sidecar, as_obstacles, build_world, inflated_obstacles
    from planner.search import search
    from planner.search.incremental import DStarLite
    from planner.world import _walk

    side = _sidecar(source)
    if radius is None:
        radius = float(side.get("robot_radius", 0.0))
    if not (isinstance(sensor_range, int | float) and math.isfinite(sensor_range)
            and sensor_range > 0):
        raise PlanError(f"sensor_range must be a positive number of metres, got "
                        f"{sensor_range!r}")
    if isinstance(max_steps, bool) or not isinstance(max_steps, int) or max_steps < 0:
        raise PlanError(f"max_steps must be a non-negative integer, got {max_steps!r}")
    dirs = ray_directions(fov, resolution)
    obst = as_obstacles(source)
    if cell_volume is None and not isinstance(lattice, Lattice):
        cell_volume = side.get("cell_volume")
    # The true world is what a sensor can hit: the obstacles. A map's unobserved space (an
    # OctoMap's unknown leaves) is not an obstacle here, so it counts as free.
    truth = build_world(obst, lattice, cell_volume=cell_volume, radius=radius,
                        bounds=side.get("bounds") if bounds is None else bounds,
                        unknown="free")
    lat = truth.lattice
    boxes = len(obst.boxes) > 0 and (not len(obst.points) or np.array_equal(obst.points,
                                                                           obst.boxes))
    pts = obst.boxes if boxes else obst.points
    if not len(pts):
        raise MapError(f"{obst.source}: no obstacles to sense")
    start_p, s = truth.endpoint(start, "start")
    goal_p, gcell = truth.endpoint(goal, "goal")
    known = World(lat, np.zeros((0, 3), np.int64), truth.bounds, radius=truth.radius,
                  source=f"explored {obst.source}")
    sensor = _Sensor(pts, obst.box_sizes if boxes else None, lat, _walk(lat), dirs,
                     sensor_range)
    _warm_up(lat, neighbors, DStarLite)
    dl = DStarLite(known, s, gcell, neighbors=neighbors)
    rec = {k: [] for k in ("changed", "ds", "dc", "de", "dcost", "as", "ac", "ae", "acost")}
    cur = s.copy()
    traj = [cur.copy()]
    status, distance, contacts, mismatches, path, at = "budget", 0.0, 0, 0, None, 0
    sense_secs = 0.0
    for _step in range(max_steps + 1):
        t0 = time.perf_counter()
        new = sensor.scan(cur)
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
            t0 = time.perf_counter()
            dl.update(changed, blocked=True)
            r = dl.plan()
            d_secs = time.perf_counter() - t0
            a = _scratch_astar(search, known, cur, gcell, neighbors)
            rec["changed"].append(len(changed))
            rec["ds"].append(d_secs)
            rec["dc"].append(r.cell_checks)
            rec["de"].append(r.expansions)
            rec["dcost"].append(r.cost)
            for k, v in zip(("as", "ac", "ae", "acost"), a, strict=True):
                rec[k].append(v)
            if not _same(r.cost, a[3]):
                mismatches += 1
            if r.status == "blocked":
                status = "stuck"
                break
            if not r.found:
                status = "unreachable"
                break
            path, at = r.cells, 0
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
    arr = {k: np.array(v) for k, v in rec.items()}
    return ExploreResult(
        lattice=lat.name or "custom", status=status, distance=distance,
        trajectory=lat.to_world(np.array(traj)), changed=arr["changed"].astype(np.int64),
        dstar_seconds=arr["ds"].astype(float), dstar_checks=arr["dc"].astype(np.int64),
        dstar_expansions=arr["de"].astype(np.int64), dstar_cost=arr["dcost"].astype(float),
        astar_seconds=arr["as"].astype(float), astar_checks=arr["ac"].astype(np.int64),
        astar_expansions=arr["ae"].astype(np.int64), astar_cost=arr["acost"].astype(float),
        mismatches=mismatches, contacts=contacts, start=start_p, goal=goal_p, points=pts,
        seen=sensor.seen, rays=len(dirs) * len(traj), sense_seconds=sense_secs)


def _warm_up(lat: Lattice, neighbors: str, dstar) -> None:
    """Compile (or load) the D* Lite kernels on a tiny world of the same lattice, so that no
    replan's time includes JIT compilation (:func:`planner.search.search` warms up A*
    itself before its clock starts)."""
    r = lat.covering_radius
    tiny = World(lat, np.zeros((0, 3), np.int64), [[-4 * r] * 3, [4 * r] * 3])
    a = lat.quantize(np.zeros((1, 3)))[0]
    b = lat.quantize(np.array([[2.5 * r, 0.0, 0.0]]))[0]
    mid = lat.quantize(np.array([[1.2 * r, 0.0, 0.0]]))
    dl = dstar(tiny, a, b, neighbors=neighbors)
    dl.plan()
    dl.update(tiny.set_cells(mid, True), blocked=True)
    dl.plan()


def _scratch_astar(search, world, cur, goal, neighbors) -> tuple[float, int, int, float]:
    """(wall seconds, cell checks, expansions, cost) of A* from scratch; a blocked end is
    unreachable (one lookup each, as A*'s endpoint check)."""
    t0 = time.perf_counter()
    try:
        r = search(world, cur, goal, method="astar", neighbors=neighbors)
    except PlanError:
        return time.perf_counter() - t0, 2, 0, math.inf
    return time.perf_counter() - t0, r.cell_checks, r.expansions, r.cost


def _same(a: float, b: float) -> bool:
    return (math.isinf(a) and math.isinf(b)) or abs(a - b) <= 1e-9
