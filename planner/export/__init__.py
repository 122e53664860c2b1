"""Writers for the rest of the robotics stack.

========================  ==================================  ===============================
what                      function                            read by
========================  ==================================  ===============================
path, TUM trajectory      :func:`write_tum`                   evo, SLAM tools
path, ROS 2 bag           :func:`write_path_bag`              ros2 bag, RViz, rosbags
world cells, PLY          :func:`write_ply_cells`             plyfile, Open3D, CloudCompare
map obstacles, OctoMap    :func:`write_octomap`               OctoMap, octovis, octomap_server
C-space mask, OctoMap     :func:`write_cspace_octomap`        the same (half a cell shifted)
benchmark, SQLite         :func:`write_arena_db`              Planner Arena, OMPL's scripts
========================  ==================================  ===============================
"""

from __future__ import annotations

from planner.export.arena import write_arena_db
from planner.export.cells import write_ply_cells, write_world_cells
from planner.export.octomap import write_cspace_octomap, write_octomap
from planner.export.rosbag import write_path_bag
from planner.export.trajectory import distinct_waypoints, path_poses, write_tum

__all__ = ["distinct_waypoints", "path_poses", "write_arena_db", "write_cspace_octomap",
           "write_octomap", "write_path_bag", "write_ply_cells", "write_tum", "write_world_cells"]
