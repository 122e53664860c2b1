"""Simulated range scans in an OctoMap at known poses, for scan-matching ground truth.

Rays are cast against the map's continuous geometry, its occupied leaf boxes, not against
any lattice's cells, so the simulation favours no lattice: the leaves (cubes of 1, 2 or 4
finest voxels per side, aligned on the octree's own grid) are rasterised on that grid and a
voxel walk returns the exact distance at which each ray enters its first occupied box.

The sensor is a 32-beam spinning LiDAR (beams evenly spread from -30.67 to +10.67 degrees of
elevation, as on a Velodyne HDL-32E) with Gaussian range noise (0.02 m standard deviation by
default, the HDL-32E's stated accuracy) and a 30 m maximum range.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from planner.errors import MapError
from planner.match import _kernels

__all__ = ["BoxMap", "lidar_directions", "sample_pose_pairs"]

BEAMS = np.linspace(-30.67, 10.67, 32)  # elevation of each beam, degrees
MAX_RANGE = 30.0


def lidar_directions(azimuth_step: float = 0.2) -> np.ndarray:
    """(K, 3) unit ray directions in the sensor frame, ``azimuth_step`` degrees apart."""
    az = np.radians(np.arange(0.0, 360.0, azimuth_step))
    el = np.radians(BEAMS)
    a, e = np.meshgrid(az, el, indexing="ij")
    d = np.stack([np.cos(e) * np.cos(a), np.cos(e) * np.sin(a), np.sin(e)], axis=-1)
    return np.ascontiguousarray(d.reshape(-1, 3))


class BoxMap:
    """The occupied and free leaf boxes of an OctoMap on its own voxel grid.

    Parameters
    ----------
    obstacles : planner.io.Obstacles
        As read from a ``.bt`` file: ``boxes`` (M, 3) centres, ``box_sizes`` (M,) edges (m),
        ``free_boxes`` / ``free_box_sizes`` likewise, and ``resolution`` (m).
    """

    def __init__(self, obstacles):
        if not len(obstacles.boxes):
            raise MapError(f"{obstacles.source}: no occupied boxes to cast rays against")
        self.h = float(obstacles.resolution)
        self.free = np.asarray(obstacles.free_boxes, dtype=float)
        self.free_sizes = np.asarray(obstacles.free_box_sizes, dtype=float)
        c = np.asarray(obstacles.boxes, dtype=float)
        s = np.asarray(obstacles.box_sizes, dtype=float)
        lo_all = c - s[:, None] / 2
        self.lo = lo_all.min(axis=0) - self.h
        hi = (c + s[:, None] / 2).max(axis=0) + self.h
        shape = np.ceil((hi - self.lo) / self.h).astype(int)
        self.grid = np.zeros(tuple(shape), dtype=np.bool_)
        first = np.rint((lo_all - self.lo) / self.h).astype(int)
        span = np.rint(s / self.h).astype(int)
        for n in np.unique(span):  # leaves of one size at a time, n voxels per side
            f = first[span == n]
            for dx in range(n):
                for dy in range(n):
                    for dz in range(n):
                        self.grid[f[:, 0] + dx, f[:, 1] + dy, f[:, 2] + dz] = True

    def scan(self, pose: np.ndarray, directions: np.ndarray, noise: float,
             rng: np.random.Generator) -> np.ndarray:
        """Points (K', 3) in the sensor frame (metres) seen from ``pose`` (4x4, sensor ->
        map): the hits within range, ranges perturbed by N(0, noise^2)."""
        world_dirs = np.ascontiguousarray(directions @ pose[:3, :3].T)
        dist = np.empty(len(directions))
        _kernels.cast_rays(np.ascontiguousarray(pose[:3, 3]), world_dirs, self.grid,
                           self.lo, self.h, MAX_RANGE, dist)
        hit = np.isfinite(dist) & (dist > 0)
        r = dist[hit] + rng.normal(0.0, noise, int(hit.sum()))
        return directions[hit] * r[:, None]

    def clearance_ok(self, p: np.ndarray, clearance: float) -> bool:
        """Whether ``p`` (3,) lies in observed free space at least ``clearance`` (m) from
        every occupied voxel (checked on the grid)."""
        k = int(np.ceil(clearance / self.h))
        i = np.floor((p - self.lo) / self.h).astype(int)
        if (i - k < 0).any() or (i + k + 1 > np.array(self.grid.shape)).any():
            return False
        if self.grid[i[0] - k:i[0] + k + 1, i[1] - k:i[1] + k + 1, i[2] - k:i[2] + k + 1].any():
            return False
        inside = (np.abs(self.free - p) <= self.free_sizes[:, None] / 2).all(axis=1)
        return bool(inside.any())


def sample_pose_pairs(box_map: BoxMap, separations, per_separation: int,
                      rng: np.random.Generator, height: tuple = (0.6, 1.4),
                      clearance: float = 0.4) -> list[tuple[float, np.ndarray, np.ndarray]]:
    """Pairs of sensor poses (4x4, sensor -> map) ``separation`` metres apart in free space.

    The first pose is a random free position (``height`` range above the map's floor) with
    a random heading and a few degrees of roll and pitch; the second moves ``separation``
    in a random horizontal direction and turns by up to 15 degrees of yaw.

    Returns
    -------
    list of (separation, pose_a, pose_b)
    """
    cand = box_map.free[(box_map.free_sizes >= 0.16)]
    floor = box_map.lo[2] + box_map.h
    cand = cand[(cand[:, 2] >= floor + height[0]) & (cand[:, 2] <= floor + height[1])]
    if not len(cand):
        raise MapError("no free space at sensor height to place simulated scans")
    out = []
    for sep in separations:
        found, tries = 0, 0
        while found < per_separation:
            tries += 1
            if tries > 5000:
                raise MapError(f"found no free pose pair {sep} m apart")
            p = cand[rng.integers(len(cand))]
            yaw = rng.uniform(-180, 180)
            heading = np.radians(rng.uniform(-180, 180))
            q = p + sep * np.array([np.cos(heading), np.sin(heading), 0.0])
            if not (box_map.clearance_ok(p, clearance) and box_map.clearance_ok(q, clearance)):
                continue
            a, b = np.eye(4), np.eye(4)
            a[:3, :3] = Rotation.from_euler("xyz", [*rng.uniform(-3, 3, 2), yaw],
                                            degrees=True).as_matrix()
            a[:3, 3] = p
            b[:3, :3] = Rotation.from_euler(
                "xyz", [*rng.uniform(-3, 3, 2), yaw + rng.uniform(-15, 15)],
                degrees=True).as_matrix()
            b[:3, 3] = q
            out.append((float(sep), a, b))
            found += 1
    return out
