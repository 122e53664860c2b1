"""Reading obstacle maps and point clouds; writing point clouds.

One module per format (:mod:`~planner.io.ply`, :mod:`~planner.io.pcd`, :mod:`~planner.io.text`,
:mod:`~planner.io.octomap`, :mod:`~planner.io.movingai`, :mod:`~planner.io.rosmap`,
:mod:`~planner.io.bag`, :mod:`~planner.io.lidar`, :mod:`~planner.io.scans`), the map model
(:mod:`~planner.io.obstacles`), the one boundary validator (:mod:`~planner.io.validate`), map
sidecars (:mod:`~planner.io.sidecar`) and the reader chosen by extension or format name
(:mod:`~planner.io.load`, where the formats table is).
"""

from planner.io._files import DECOMPRESSED_BUDGET
from planner.io.load import (
    load_obstacles,
    load_points,
    load_posed_scans,
    obstacles_from_points,
    save_points,
)
from planner.io.movingai import load_scenarios
from planner.io.obstacles import Obstacles, Scenarios
from planner.io.scans import merge_scans, with_origin
from planner.io.sidecar import load_sidecar
from planner.io.validate import robust_extent

__all__ = [
    "DECOMPRESSED_BUDGET",
    "Obstacles",
    "Scenarios",
    "load_obstacles",
    "load_points",
    "load_posed_scans",
    "load_scenarios",
    "load_sidecar",
    "merge_scans",
    "obstacles_from_points",
    "robust_extent",
    "save_points",
    "with_origin",
]
