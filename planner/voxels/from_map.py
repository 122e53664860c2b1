"""From a map's obstacles and free space to lattice cells: the cells a robot centre must
not enter (:func:`inflated_obstacles`) and the cells meeting unknown space
(:func:`unknown_space`), as :func:`planner.build_world` assembles a world from them."""

from __future__ import annotations

import numpy as np

from planner.errors import MapError
from planner.lattice import Lattice
from planner.occupancy.keys import unique_keys, unpack
from planner.voxels.boxes import box_frame, overlap_keys
from planner.voxels.inflate import (
    box_inflation_grid,
    exact_box_inflation,
    exact_inflation,
    point_inflation_grid,
)
from planner.voxels.unknown import (
    ray_free_keys,
    unknown_box_grid,
    unknown_box_keys,
    unknown_box_space,
    unknown_cell_keys,
    unknown_inflation,
)
from planner.voxels.voxel_list import OccupiedVoxelList

__all__ = ["inflated_obstacles", "inflation_parts", "unknown_grid", "unknown_region",
           "unknown_space"]


def _cells_near(keys: np.ndarray, lat: Lattice, bounds: np.ndarray) -> np.ndarray:
    """Indices (N, 3) of the cells of packed ``keys`` whose centre lies within a covering
    radius of the bounds box (m, (2, 3)), unpacked in chunks: a large radius dilates
    unknown space far past the box, and only cells in it can ever be searched."""
    lo, hi = bounds[0] - lat.covering_radius, bounds[1] + lat.covering_radius
    parts = [np.zeros((0, 3), dtype=np.int64)]
    for i in range(0, len(keys), 1 << 22):
        w = unpack(keys[i: i + (1 << 22)], 3)
        c = lat.to_world(w)
        parts.append(w[np.all((c >= lo) & (c <= hi), axis=1)])
    return np.concatenate(parts)


def unknown_region(lat: Lattice, bounds: np.ndarray, radius: float
                    ) -> tuple[np.ndarray, np.ndarray]:
    """The box (m) classified for unknown space: the bounds padded by the reach of a robot
    centre's cell (radius + twice the covering radius)."""
    pad = radius + 2 * lat.covering_radius
    return bounds[0] - pad, bounds[1] + pad


def unknown_space(obst, lat: Lattice, bounds: np.ndarray, radius: float, planar: bool,
                   blocked: bool, occupied: np.ndarray) -> tuple[np.ndarray, np.ndarray | None]:
    """The (U, 3) cells meeting unknown space (:func:`_unknown_keys`) and, when unknown
    space is blocked, the (N, 3) cells it blocks near the bounds (:func:`_cells_near`;
    grid maps: less the ``occupied`` ones, (M, 3), blocked already)."""
    if obst.origins is None and len(obst.free_boxes):  # a grid map: on dense grids
        lo, hi, res = _box_region(obst, lat, bounds, radius, planar)
        near = np.stack([bounds[0] - lat.covering_radius, bounds[1] + lat.covering_radius])
        got = unknown_box_space(obst.boxes, obst.box_sizes, obst.free_boxes,
                                obst.free_box_sizes, res, lat, lo, hi,
                                radius if blocked else None, near, occupied)
        if got is not None:
            return got
    ukeys = _unknown_keys(obst, lat, bounds, radius, planar)
    near = _cells_near(unknown_inflation(ukeys, lat, radius), lat, bounds) if blocked else None
    return unpack(ukeys, 3), near


def _box_region(obst, lat: Lattice, bounds: np.ndarray, radius: float, planar: bool
                ) -> tuple[np.ndarray, np.ndarray, float]:
    """:func:`unknown_region` and the voxel edge (m) of a map with free boxes."""
    lo, hi = unknown_region(lat, bounds, radius)
    res = obst.resolution or float(np.min(np.concatenate([obst.box_sizes,
                                                          obst.free_box_sizes])))
    if planar:
        lo[2], hi[2] = -res / 2, res / 2  # a lifted 2D map: one layer of voxels
    return lo, hi, res


def _unknown_keys(obst, lat: Lattice, bounds: np.ndarray, radius: float, planar: bool
                  ) -> np.ndarray:
    """Keys of the cells meeting unknown space over :func:`unknown_region`."""
    lo, hi = unknown_region(lat, bounds, radius)
    parts = []
    if len(obst.free_boxes):
        lo, hi, res = _box_region(obst, lat, bounds, radius, planar)
        parts.append(unknown_box_keys(obst.boxes, obst.box_sizes, obst.free_boxes,
                                      obst.free_box_sizes, res, lat, lo, hi))
    if obst.origins is not None:
        free = ray_free_keys(obst.points, obst.origins, obst.point_origin, lat)
        occ = exact_inflation(obst.points, lat, 0.0).keys
        cell_unknown = unknown_cell_keys(free, occ, lat, lo, hi)
        # Both sources: unknown only where neither says free (intersection).
        parts = [np.intersect1d(parts[0], cell_unknown)] if parts else [cell_unknown]
    return parts[0]


def inflated_obstacles(obst, lattice: Lattice, radius: float):
    """The cells a robot centre of radius ``radius`` (m) must not enter: exactly the cells
    whose closed Voronoi cell comes closer than ``radius`` to an obstacle point
    (:func:`planner.voxels.exact_inflation`) or an occupied box, each at its own size
    (:func:`planner.voxels.exact_box_inflation`; an OctoMap leaf is a box, inflated once).
    A path whose segments touch only cells outside this set keeps distance >= ``radius``
    from every obstacle. With ``radius`` 0: the cells containing a point or overlapping a
    box.

    Returns
    -------
    OccupiedVoxelList
    """
    keys = []
    if len(obst.points):
        keys.append(exact_inflation(obst.points, lattice, radius).keys)
    if len(obst.boxes):
        half = obst.box_sizes[:, None] / 2
        keys.append(exact_box_inflation(obst.boxes - half, obst.boxes + half, lattice,
                                        radius).keys)
    if not keys:
        raise MapError(f"{obst.source}: no obstacles")
    return OccupiedVoxelList._from_keys(lattice, unique_keys(np.concatenate(keys)))


def inflation_parts(obst, lattice: Lattice, radius: float):
    """The cells of :func:`inflated_obstacles` in parts, without one list of them all: for
    the points, then for the boxes, ``(grid, lo, dims)`` (a byte grid over an index box,
    nonzero = blocked; ``radius`` > 0) or ``(cells,)`` ((N, 3) int64; ``radius`` 0).
    A generator: one part's grid is made when the previous one is consumed."""
    if not len(obst.points) and not len(obst.boxes):
        raise MapError(f"{obst.source}: no obstacles")
    if len(obst.points):
        if radius > 0:
            yield point_inflation_grid(obst.points, lattice, radius)
        else:
            yield (lattice.quantize(obst.points),)
    if len(obst.boxes):
        half = obst.box_sizes[:, None] / 2
        lo, hi = obst.boxes - half, obst.boxes + half
        if radius > 0:
            yield box_inflation_grid(lo, hi, lattice, radius)
        else:
            centres, h, rot = box_frame(lo, hi, None, None, lattice.dim)
            yield (unpack(overlap_keys(centres, h, rot, lattice), lattice.dim),)


def unknown_grid(obst, lat: Lattice, bounds: np.ndarray, radius: float, planar: bool,
                 blocked: bool) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """:func:`unknown_space` of a grid map (free boxes, no sensor rays) as one byte grid
    (:func:`planner.voxels.unknown.unknown_box_grid`: bit 1 unknown, bit 2 within
    ``radius`` of it when ``blocked``); None for another map or when it does not fit."""
    if obst.origins is not None or not len(obst.free_boxes):
        return None
    lo, hi, res = _box_region(obst, lat, bounds, radius, planar)
    return unknown_box_grid(obst.boxes, obst.box_sizes, obst.free_boxes, obst.free_box_sizes,
                            res, lat, lo, hi, radius if blocked else None)
