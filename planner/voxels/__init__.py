"""Occupied voxel lists on any lattice.

* :mod:`planner.voxels.voxel_list`: :class:`OccupiedVoxelList` (sorted packed keys) and its files;
* :mod:`planner.voxels.inflate`: robot-radius inflation by a stencil, and the exact cell
  sets of obstacle points (:func:`exact_inflation`) and (rotated) boxes
  (:func:`exact_box_inflation`, :func:`box_keys`);
* :mod:`planner.voxels.kernels`, :mod:`planner.voxels._box_kernels`: compiled kernels;
* :mod:`planner.voxels._checks`: input checks and key helpers shared by the above;
* :mod:`planner.voxels.from_map`: a map's obstacles and free space as lattice cells (blocked
  for a robot radius, meeting unknown space), the parts :func:`planner.build_world` joins.

All cell geometry comes from :attr:`planner.Lattice.voronoi`.
"""

from planner.voxels.inflate import (
    box_keys,
    exact_box_inflation,
    exact_inflation,
    inflation_stencil,
)
from planner.voxels.voxel_list import FORMAT, VERSION, OccupiedVoxelList

__all__ = ["OccupiedVoxelList", "exact_inflation", "exact_box_inflation", "inflation_stencil",
           "box_keys", "FORMAT", "VERSION"]
