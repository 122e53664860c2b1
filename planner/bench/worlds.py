"""Worlds of a rotated map for the benchmark (the paper's fairness rule).

A map and its queries turn together about the map centre; every lattice, neighbour set and
method of a suite sees the same sample of rotations.  :func:`rotated_world` builds the
:class:`planner.World` of one rotation:

- points rotate and are inflated exactly (:func:`planner.voxels.exact_inflation`);
- boxes become oriented solids, inflated exactly by
  :func:`planner.voxels.exact_box_inflation` with the map's rotation;
- the robot must stay in the *rotated* original world box: the World's bounds are the
  axis-aligned box around it, and every cell in those bounds whose centre lies outside the
  rotated box is blocked (the same "centre in the box" rule the World applies to its
  bounds, so rotation by the identity gives the unrotated world);
- unknown space (a map with free-space information whose policy is ``blocked``) is blocked
  the same way: a cell whose centre is not in an observed-free box is blocked.

The identity rotation is built by the same code, so that all rotations of a suite share one
set of rules.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from planner.bench.rotations import quaternion_matrix

__all__ = ["MapFrame", "map_frame", "rotated_world", "FreeSpace"]

_TOL = 1e-9  # relative, as World's bounds test
_CHUNK = 2_000_000


class FreeSpace:
    """Observed-free space of a map (its free boxes) as a dense grid at the native resolution.

    Parameters
    ----------
    obst : planner.io.Obstacles
        A map with ``free_boxes`` (in its own, unrotated frame).
    """

    def __init__(self, obst):
        from planner.io._validate import fill_boxes

        sizes = obst.free_box_sizes
        step = float(obst.resolution or sizes.min())
        cubes = fill_boxes(obst.free_boxes, sizes, step)
        self.step = step
        self.origin = cubes.min(axis=0) - step / 2
        idx = np.floor((cubes - self.origin) / step).astype(np.int64)
        self.shape = idx.max(axis=0) + 1
        self.grid = np.zeros(tuple(self.shape), dtype=bool)
        self.grid[tuple(idx.T)] = True

    def contains(self, points: np.ndarray) -> np.ndarray:
        """(N,) bool: each point (N, 3), metres, in the map frame lies in observed free space."""
        idx = np.floor((np.asarray(points, dtype=float) - self.origin) / self.step)
        ok = np.all((idx >= 0) & (idx < self.shape), axis=1)
        out = np.zeros(len(idx), dtype=bool)
        i = idx[ok].astype(np.int64)
        out[ok] = self.grid[tuple(i.T)]
        return out


@dataclass
class MapFrame:
    """A map in its own frame: obstacles, world box (m), centre of rotation, free space."""

    obstacles: object
    bounds: np.ndarray
    centre: np.ndarray
    free: FreeSpace | None

    @property
    def blocks_unknown(self) -> bool:
        return self.free is not None and self.obstacles.unknown_default == "blocked"


def map_frame(map_path: str) -> MapFrame:
    """Load a map and its world box as :func:`planner.build_world` would choose it."""
    from planner import api

    obst = api.as_obstacles(map_path)
    side = api._sidecar(map_path)
    if obst.bounds is not None:
        bounds = obst.bounds
    elif "bounds" in side:
        bounds = side["bounds"]
    else:
        bounds = api._obstacle_bounds(obst)
    bounds = np.asarray(bounds, dtype=float)
    free = FreeSpace(obst) if len(obst.free_boxes) else None
    return MapFrame(obst, bounds, bounds.mean(axis=0), free)


def to_map_frame(points: np.ndarray, R: np.ndarray, centre: np.ndarray) -> np.ndarray:
    """Rotated-world points (N, 3) back in the map's own frame."""
    return (np.asarray(points, dtype=float) - centre) @ R + centre


def rotated_bounds(bounds: np.ndarray, R: np.ndarray, centre: np.ndarray) -> np.ndarray:
    """(2, 3) axis-aligned box around the rotated world box (m)."""
    lo, hi = bounds
    corners = np.array([[(lo, hi)[i][0], (lo, hi)[j][1], (lo, hi)[k][2]]
                        for i in (0, 1) for j in (0, 1) for k in (0, 1)])
    c = (corners - centre) @ R.T + centre
    return np.stack([c.min(axis=0), c.max(axis=0)])


def _outside_cells(lat, frame: MapFrame, R: np.ndarray, box: np.ndarray) -> np.ndarray:
    """Cells with centre in ``box`` (the World's bounds) but outside the rotated map box, or
    (when the map blocks unknown space) outside observed free space; (M, 3) int64."""
    G = lat.generator
    Ginv = np.linalg.inv(G)
    tol = _TOL * max(float(np.abs(box).max()), lat.covering_radius)
    blo, bhi = box[0] - tol, box[1] + tol
    corners = np.array([[(blo, bhi)[i][0], (blo, bhi)[j][1], (blo, bhi)[k][2]]
                        for i in (0, 1) for j in (0, 1) for k in (0, 1)])
    w = corners @ Ginv.T
    ilo, ihi = np.floor(w.min(axis=0)).astype(np.int64), np.ceil(w.max(axis=0)).astype(np.int64)
    mlo, mhi = frame.bounds[0] - tol, frame.bounds[1] + tol
    out = []
    plane = (ihi[1] - ilo[1] + 1) * (ihi[2] - ilo[2] + 1)
    step = max(1, _CHUNK // max(int(plane), 1))
    j, k = np.meshgrid(np.arange(ilo[1], ihi[1] + 1), np.arange(ilo[2], ihi[2] + 1),
                       indexing="ij")
    jk = np.stack([j.ravel(), k.ravel()], axis=1)
    for i0 in range(ilo[0], ihi[0] + 1, step):
        ii = np.arange(i0, min(i0 + step, ihi[0] + 1))
        cells = np.concatenate([np.repeat(ii, len(jk))[:, None], np.tile(jk, (len(ii), 1))],
                               axis=1)
        c = cells @ G.T
        keep = np.all((c >= blo) & (c <= bhi), axis=1)
        cells, c = cells[keep], c[keep]
        m = to_map_frame(c, R, frame.centre)
        bad = ~np.all((m >= mlo) & (m <= mhi), axis=1)
        if frame.blocks_unknown:
            bad |= ~frame.free.contains(m)
        out.append(cells[bad])
    return np.concatenate(out) if out else np.zeros((0, 3), dtype=np.int64)


def rotated_world(frame: MapFrame, lattice: str, cell_volume: float, radius: float,
                  quaternion) -> object:
    """The World of ``frame``'s map turned by ``quaternion`` (w, x, y, z) about its centre.

    Returns
    -------
    planner.World
        Bounds: the axis-aligned box around the rotated world box; cells outside the rotated
        box (and unknown cells, see the module docstring) are blocked.
    """
    from planner.keys import pack, unpack
    from planner.lattice import Lattice
    from planner.voxels import exact_box_inflation, exact_inflation
    from planner.world import World

    t0 = time.perf_counter()
    R = quaternion_matrix(quaternion)
    lat = Lattice.named(lattice, cell_volume=cell_volume)
    rot, t = frame.obstacles.rotated(R, frame.centre)
    keys = []
    if len(rot.points):
        keys.append(exact_inflation(rot.points, lat, radius).keys)
    o = frame.obstacles
    if len(o.boxes):
        half = o.box_sizes[:, None] / 2
        keys.append(exact_box_inflation(o.boxes - half, o.boxes + half, lat, radius,
                                        rotation=R, translation=t).keys)
    box = rotated_bounds(frame.bounds, R, frame.centre)
    keys.append(pack(_outside_cells(lat, frame, R, box)))
    cells = unpack(np.unique(np.concatenate(keys)), 3)
    return World(lat, cells, box, source=o.source, radius=float(radius), obstacles=rot,
                 build_seconds=time.perf_counter() - t0)


def cached_world(cache_dir: str | None, frame: MapFrame, map_path: str, lattice: str,
                 cell_volume: float, radius: float, quaternion, rotated: bool):
    """The World of one configuration, built once per suite run and shared through files.

    The query sampler and every worker need the same worlds; building them is the dominant
    cost of a rotated suite, so the blocked cells and bounds are kept in ``cache_dir``
    (compressed ``.npz`` of the sorted keys' steps, written atomically) and reloaded.
    ``rotated`` False builds with :func:`planner.build_world` (an unrotated suite), else
    :func:`rotated_world`.
    """
    import hashlib

    from planner.api import build_world
    from planner.fsutil import atomic_path
    from planner.keys import pack, unpack
    from planner.lattice import Lattice
    from planner.world import World

    def build():
        if rotated:
            return rotated_world(frame, lattice, cell_volume, radius, quaternion)
        return build_world(map_path, lattice, cell_volume=cell_volume, radius=radius)

    if cache_dir is None:
        return build()
    from pathlib import Path

    tag = repr((map_path, lattice, float(cell_volume), float(radius),
                [round(float(v), 15) for v in quaternion], bool(rotated)))
    f = Path(cache_dir) / (hashlib.sha1(tag.encode()).hexdigest()[:20] + ".npz")
    if f.is_file():
        try:
            with np.load(f) as z:
                lat = Lattice.named(lattice, cell_volume=cell_volume)
                obst = frame.obstacles
                if rotated:
                    obst = obst.rotated(quaternion_matrix(quaternion), frame.centre)[0]
                keys = np.cumsum(z["key_steps"])
                return World(lat, unpack(keys, 3), z["bounds"], source=frame.obstacles.source,
                             radius=float(radius), obstacles=obst,
                             build_seconds=float(z["build_seconds"]))
        except (OSError, ValueError, KeyError):
            pass  # a damaged file: build again
    w = build()
    f.parent.mkdir(parents=True, exist_ok=True)
    with atomic_path(f) as tmp, open(tmp, "wb") as fh:
        # sorted keys as steps compress ~100x (a rotated OctoMap blocks millions of unknown cells)
        keys = np.unique(pack(w.blocked))
        np.savez_compressed(fh, key_steps=np.diff(keys, prepend=np.int64(0)), bounds=w.bounds,
                            build_seconds=w.build_seconds or 0.0)
    return w
