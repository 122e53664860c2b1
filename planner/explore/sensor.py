"""Simulated range sensor for the exploration (:mod:`planner.explore`): exact, noise-free
rays cast through the lattice against the true map's occupied cells.

Rays leave the robot's position over a field of view (``fov``: horizontal total and
vertical +- half-angle, degrees) at ``resolution`` degrees, up to ``sensor_range`` metres.
The true map is the lattice occupied voxel list of the obstacle points (radius 0), or of
the cells overlapping the boxes of a box map (OctoMap leaves, ``.3dmap``); a ray stops at
the occupied cell whose closed Voronoi cell it enters first (the lattice segment walk plus
the exact entry parameter of each touched cell). A hit reveals every obstacle point in that
cell, or every box that can overlap it (a lidar return from that surface patch).
"""

from __future__ import annotations

import numpy as np

from planner._numba import njit_cached
from planner.budget import require
from planner.errors import PlanError
from planner.lattice import Lattice
from planner.occupancy.grid import Occupancy, occ_free
from planner.occupancy.keys import build_key_set, pack
from planner.occupancy.walk import walk_on, walk_scratch
from planner.voxels import box_keys

__all__ = ["Sensor", "cast_rays", "ray_directions"]


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
    nv = int(round(v / res))
    # per ray: its direction, the angle grids and the hit cell (float64 / int64 triples)
    rays = float(na + 1) * (2 * nv + 1)
    require(rays * 8 * 12, f"{rays:.3g} sensor rays (--resolution {res:g} degrees)",
            error=PlanError)
    az = np.arange(na) * (h / na) if h >= 360 else np.linspace(-h / 2, h / 2, na + 1)
    el = np.linspace(-v, v, 2 * nv + 1) if nv else np.zeros(1)
    a, e = np.meshgrid(np.radians(az), np.radians(el), indexing="ij")
    a, e = a.ravel(), e.ravel()
    return np.ascontiguousarray(np.stack([np.cos(e) * np.cos(a), np.cos(e) * np.sin(a),
                                          np.sin(e)], axis=1))


@njit_cached
def _entry(u0, u1, u2, av, dq, wv, nrel):  # pragma: no cover - compiled
    """Smallest t in [0, 1] at which a + t (b - a) is in the closed Voronoi cell at offset
    u from the walk's start cell (the clipping of ``planner.occupancy.walk._touches``)."""
    lo = 0.0
    for r in range(nrel):
        q = dq[r]
        if q < 0.0:
            t = (av[r] + (wv[r, 0] * u0 + wv[r, 1] * u1 + wv[r, 2] * u2)) * q
            if t > lo:
                lo = t
    return lo


@njit_cached
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


class Sensor:
    """The true map as the sensor sees it.

    Points (``box_sizes`` None): the occupied cells are those holding a point, and a hit
    reveals the points in the hit cell. Boxes (edge ``box_sizes[k]`` m each): the occupied
    cells are those overlapping a box (:func:`planner.voxels.box_keys`), so every ray
    through a box stops at or before it, and a hit reveals the boxes that can overlap the
    hit cell (centre within half the largest box diagonal plus the covering radius).
    """

    def __init__(self, points: np.ndarray, box_sizes: np.ndarray | None, lattice: Lattice,
                 walk, dirs: np.ndarray, reach: float):
        self.points, self.boxes = points, box_sizes is not None
        if self.boxes:
            from scipy.spatial import cKDTree

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
        self.occ = Occupancy(mode=1, grid=np.zeros(1, np.uint8), lo=np.zeros(3, np.int64),
                             dims=np.zeros(3, np.int64), table=build_key_set(uniq, size),
                             tmask=size - 1, gmat=g, blo=-big, bhi=big.copy())
        self.walk, self.dirs, self.reach = walk, dirs, float(reach)
        self.lattice = lattice
        self.hits = np.zeros((len(dirs), 3), np.int64)
        self.seen = np.zeros(len(points), bool)
        self.seen_step = np.full(len(points), -1, np.int64)
        self.ring = np.flatnonzero(np.abs(dirs[:, 2]) < 1e-12)  # the horizontal rays
        self.ring_azimuths = np.arctan2(dirs[self.ring, 1], dirs[self.ring, 0])
        self.ring_ranges: list[np.ndarray] = []

    def scan(self, cell: np.ndarray, step: int) -> np.ndarray:
        """Cast every ray from the centre of ``cell`` (after ``step`` moves); return the
        indices of the obstacles revealed for the first time."""
        origin = self.lattice.to_world(cell[None])[0]
        found = cast_rays(self.occ, self.walk, origin, cell, self.dirs, self.reach, self.hits)
        hr = self.hits[self.ring]
        reach = np.linalg.norm(self.lattice.to_world(hr)[:, :2] - origin[:2], axis=1)
        self.ring_ranges.append(np.where(found[self.ring], np.minimum(reach, self.reach),
                                         self.reach))
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
        self.seen_step[idx] = step
        return idx
