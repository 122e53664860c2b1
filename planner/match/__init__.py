"""Scan matching on multi-resolution lattice occupied voxel lists, and pose proximity.

* :class:`MultiResVoxelList` (:mod:`planner.match.multires`): one occupied voxel list per
  resolution of any lattice;
* :func:`match` (:mod:`planner.match.matcher`): coarse-to-fine rigid 6-DOF matching that
  counts source points falling in occupied reference cells, then a point-to-plane
  refinement on the matched cells (:mod:`planner.match.refine`);
* :class:`PoseIndex` (:mod:`planner.match.pose_index`): "is this pose within r of any
  stored pose" from a fixed set of cells per query, with amortised O(1) adds;
* :mod:`planner.match.simulate`: LiDAR scans cast against an OctoMap's leaf boxes at known
  poses; :mod:`planner.match.anchor`: the registration anchors, small_gicp's GICP and
  point-to-plane ICP (the ``match`` extra).
"""

from planner.match.matcher import MatchResult, match, pose_error, pose_matrix
from planner.match.multires import MultiResVoxelList
from planner.match.pose_index import PoseIndex

__all__ = ["MatchResult", "MultiResVoxelList", "PoseIndex", "match", "pose_error",
           "pose_matrix"]
