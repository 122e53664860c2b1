"""Occupied voxel lists on any lattice: storage and files (:mod:`planner.voxels._list`),
robot-radius inflation and exact cell sets of points and boxes
(:mod:`planner.voxels.inflate`), compiled kernels (:mod:`planner.voxels._kernels`)."""

from planner.voxels._list import FORMAT, VERSION, OccupiedVoxelList
from planner.voxels.inflate import (
    box_keys,
    exact_box_inflation,
    exact_inflation,
    inflation_stencil,
)

__all__ = ["OccupiedVoxelList", "exact_inflation", "exact_box_inflation", "inflation_stencil",
           "box_keys", "FORMAT", "VERSION"]
