"""Worlds of a rotated map for the benchmark (the paper's fairness rule).

Turning the map by R against a fixed lattice is the same as turning the lattice by R^T
against the fixed map: a cell ``w`` of the lattice ``G`` is blocked by the turned map
``R O`` exactly when the cell ``w`` of the lattice ``R^T G`` is blocked by ``O``. So a
rotated world is :func:`planner.build_world` on the map as it is, with the generator
``R^T G`` (:func:`rotated_lattice`): the same integer cells, moves and stencils, and every
rule of an unrotated world (exact point and box inflation, unknown space blocked by its
closed Voronoi cells, the map box as bounds) holds unchanged in every rotation. Queries,
paths and clearances stay in the map's own frame. (The rotation is about the origin; a
rotation about another point differs by a translation of the lattice, which the paper's
rule does not fix either.)
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation

from planner.bench.rotations import IDENTITY_XYZW
from planner.errors import PlannerError
from planner.fsutil import atomic_path
from planner.io.validate import fill_boxes
from planner.lattice import Lattice

__all__ = ["MapFrame", "map_frame", "rotated_lattice", "rotated_world", "FreeSpace"]


class FreeSpace:
    """Observed-free space of a map (its free boxes) as a dense grid at the native resolution.

    Parameters
    ----------
    obst : planner.io.Obstacles
        A map with ``free_boxes``.
    """

    def __init__(self, obst):
        sizes = obst.free_box_sizes
        step = float(obst.resolution or sizes.min())
        cubes = fill_boxes(obst.free_boxes, sizes, step)
        self.step = step
        self.origin = cubes.min(axis=0) - step / 2
        idx = np.floor((cubes - self.origin) / step).astype(np.int64)
        self.shape = idx.max(axis=0) + 1
        self.grid = np.zeros(tuple(self.shape), dtype=bool)
        self.grid[tuple(idx.T)] = True
        self._flat: np.ndarray | None = None  # free voxels' flat indices, on first sample

    def sample(self, rng: np.random.Generator, n: int) -> np.ndarray:
        """(n, 3) points (m) uniform in observed free space (a uniform free voxel, then a
        uniform point in it: the voxels are equal)."""
        if self._flat is None:
            self._flat = np.flatnonzero(self.grid)
        pick = self._flat[rng.integers(0, len(self._flat), n)]
        idx = np.stack(np.unravel_index(pick, self.grid.shape), axis=1)
        pts = self.origin + (idx + rng.random((n, 3))) * self.step
        if self.shape[2] == 1 and self.origin[2] == -self.step / 2:  # a 2D map's plane
            pts[:, 2] = 0.0
        return pts

    def contains(self, points: np.ndarray) -> np.ndarray:
        """(N,) bool: each point (N, 3), metres, lies in observed free space."""
        idx = np.floor((np.asarray(points, dtype=float) - self.origin) / self.step)
        ok = np.all((idx >= 0) & (idx < self.shape), axis=1)
        out = np.zeros(len(idx), dtype=bool)
        i = idx[ok].astype(np.int64)
        out[ok] = self.grid[tuple(i.T)]
        return out


@dataclass
class MapFrame:
    """A map in its own frame: obstacles, world box (m), observed free space."""

    obstacles: object
    bounds: np.ndarray
    free: FreeSpace | None


def map_frame(map_path: str) -> MapFrame:
    """Load a map and its world box as :func:`planner.build_world` would choose it."""
    from planner.world.build import as_obstacles, lift_planar, map_box  # lazy: numba

    obst = as_obstacles(map_path)
    bounds = map_box(map_path, obst)
    if obst.dim == 2:  # planned in the plane z = 0: queries and clearances there too
        obst = lift_planar(obst)
        bounds = np.column_stack([bounds, np.zeros(2)])
    free = FreeSpace(obst) if len(obst.free_boxes) else None
    return MapFrame(obst, bounds, free)


_FRAMES: dict = {}


def cached_frame(map_path: str) -> MapFrame:
    """:func:`map_frame`, kept per process for the map last asked for (a worker's tasks
    come grouped by map)."""
    if map_path not in _FRAMES:
        _FRAMES.clear()
        _FRAMES[map_path] = map_frame(map_path)
    return _FRAMES[map_path]


def rotated_lattice(lattice: str, cell_volume: float, quaternion):
    """The named lattice turned by R^T, R the rotation of unit ``quaternion`` (x, y, z, w):
    generator ``R^T G`` (3, 3), same name and cell volume (m^3)."""
    lat = Lattice.named(lattice, cell_volume=cell_volume)
    q = np.asarray(quaternion, dtype=float)
    if np.allclose(q, IDENTITY_XYZW, atol=0, rtol=0):
        return lat  # the identity keeps the named lattice and its fast quantizer
    r = Rotation.from_quat(q).as_matrix()
    if lat.dim == 2:  # a 2D lattice turns in its plane: yaw only
        if not np.allclose(r[2], [0.0, 0.0, 1.0], atol=1e-12):
            raise PlannerError(f"{lattice}: a 2D lattice turns about z only (rotation = "
                               f"\"yaw\" or \"none\" for 2D maps)")
        r = r[:2, :2]
    return Lattice(r.T @ lat.generator, name=lattice)


def rotated_world(map_path: str, lattice: str, cell_volume: float, radius: float,
                  quaternion) -> object:
    """The World of the map at ``map_path`` turned by ``quaternion`` (x, y, z, w) against
    the lattice (module docstring): :func:`planner.build_world` with
    :func:`rotated_lattice`.

    Returns
    -------
    planner.World
        In the map's own frame, bounds the map's box.
    """
    from planner.world.build import build_world  # lazy: numba

    return build_world(map_path, rotated_lattice(lattice, cell_volume, quaternion),
                       radius=radius)


def cached_world(cache_dir: str | None, map_path: str, lattice: str, cell_volume: float,
                 radius: float, quaternion) -> object:
    """The :func:`rotated_world` of one configuration, built once per suite run and shared
    through files.

    The query sampler and every worker need the same worlds; building them is the dominant
    cost of a rotated suite, so the blocked and unknown cells and bounds are kept in
    ``cache_dir`` (compressed ``.npz`` of the sorted keys' steps, written atomically) and
    reloaded; None builds every time.
    """
    import hashlib
    from pathlib import Path

    from planner.occupancy.keys import pack, unique_keys, unpack  # lazy: numba
    from planner.world import World  # lazy: numba

    if cache_dir is None:
        return rotated_world(map_path, lattice, cell_volume, radius, quaternion)
    tag = repr(("map frame", map_path, lattice, float(cell_volume), float(radius),
                [round(float(v), 15) for v in quaternion]))
    f = Path(cache_dir) / (hashlib.sha1(tag.encode()).hexdigest()[:20] + ".npz")
    if f.is_file():
        try:
            with np.load(f) as z:
                return World(rotated_lattice(lattice, cell_volume, quaternion),
                             unpack(np.cumsum(z["key_steps"]), 3), z["bounds"],
                             source=str(z["source"]), radius=float(radius),
                             unknown_cells=unpack(np.cumsum(z["unknown_steps"]), 3),
                             unknown_policy=str(z["unknown_policy"]),
                             build_seconds=float(z["build_seconds"]),
                             offset=z["offset"] if "offset" in z.files else None)
        except (OSError, ValueError, KeyError):
            pass  # a damaged file: build again
    w = rotated_world(map_path, lattice, cell_volume, radius, quaternion)
    f.parent.mkdir(parents=True, exist_ok=True)

    def steps(cells):  # sorted keys as steps: small numbers that compress well
        return np.diff(unique_keys(pack(cells)), prepend=np.int64(0))

    with atomic_path(f) as tmp, open(tmp, "wb") as fh:
        np.savez_compressed(fh, key_steps=steps(w.blocked), unknown_steps=steps(w.unknown),
                            bounds=w.bounds,
                            source=np.array(str(w.source or "")),
                            unknown_policy=np.array(w.unknown_policy),
                            build_seconds=w.build_seconds or 0.0,
                            offset=w.offset)  # a local frame (planner.world.frame)
    return w
