"""Assembling a world from a map without a list of every blocked cell.

:func:`assemble` is the step of :func:`planner.build_world` after the defaults are
resolved: it makes the world's compact cell sets first (:mod:`planner.occupancy.bits`, one
bit per cell of the index box) and writes the inflation kernels' byte grids straight into
them (:meth:`planner.World.block_marked`): the obstacle inflation
(:func:`planner.voxels.from_map.inflation_parts`) and, for a grid map, unknown space and its
inflation (:func:`planner.voxels.from_map.unknown_grid`). Sensor-ray maps and worlds too
large for bit sets take the cell lists of :func:`planner.voxels.from_map.unknown_space`,
the same cells either way.

The cells are exactly those of the list path (:func:`reference_cells`, kept as the
reference the tests compare with): in bounds, a cell is blocked iff it is within the
radius of an obstacle or (unknown space blocked) of unknown space.
"""

from __future__ import annotations

import numpy as np

from planner.lattice import Lattice
from planner.voxels.from_map import (
    inflated_obstacles,
    inflation_parts,
    unknown_grid,
    unknown_space,
)
from planner.world.world import World

__all__ = ["assemble", "reference_cells"]


def assemble(obst, lat: Lattice, bounds: np.ndarray, radius: float, policy: str, planar: bool,
             **world_options) -> World:
    """The world of a loaded map with its options resolved (3D lattice and bounds; a 2D
    map already lifted onto the plane z = 0 of a prism lattice, ``planar`` True).

    Parameters
    ----------
    obst : Obstacles
    lat : Lattice
    bounds : ndarray, shape (2, 3)
        World box (m).
    radius : float
        Robot radius (m).
    policy : {"blocked", "free"}
        Unknown-space policy.
    planar : bool
        A lifted 2D map.
    **world_options
        Passed to :class:`World` (``source``, ``obstacles``, ``dim``, ...).

    Returns
    -------
    World
    """
    world = World(lat, np.zeros((0, 3), np.int64), bounds, radius=float(radius),
                  unknown_policy=policy, **world_options)
    for part in inflation_parts(obst, lat, radius):
        if len(part) == 3:
            world.block_marked(*part, 0xFF)
        else:
            world.block_cells(part[0])
        del part
    if not obst.has_free_space:
        return world
    blocked = policy == "blocked"
    got = unknown_grid(obst, lat, bounds, radius, planar, blocked) if world.storage == "dense" \
        else None
    if got is not None:
        grid, glo, dims = got
        world.block_marked(grid, glo, dims, 1, unknown=True)
        if blocked:
            world.block_marked(grid, glo, dims, 3)
        return world
    unknown, near = unknown_space(obst, lat, bounds, radius, planar, blocked,
                                  np.zeros((0, 3), np.int64))
    world.add_unknown(unknown)
    if near is not None:
        world.block_cells(near)
    return world


def reference_cells(obst, lat: Lattice, bounds: np.ndarray, radius: float, policy: str,
                    planar: bool) -> tuple[np.ndarray, np.ndarray | None]:
    """The blocked cells (M, 3) and the cells meeting unknown space (U, 3) or None, as lists
    (duplicates possible; some out of bounds): the list path :func:`assemble` must agree
    with cell for cell in bounds."""
    cells = inflated_obstacles(obst, lat, radius).indices
    unknown = None
    if obst.has_free_space:
        unknown, near = unknown_space(obst, lat, bounds, radius, planar, policy == "blocked",
                                      cells)
        if near is not None:
            cells = np.concatenate([cells, near])
    return cells, unknown
