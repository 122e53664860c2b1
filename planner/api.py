"""Former home of :func:`planner.plan` and :func:`planner.build_world`, kept as re-exports for
one release: import them from :mod:`planner` (or :mod:`planner.planning`,
:mod:`planner.world.build`)."""

from planner.planning import PlanResult, plan, unknown_on_path
from planner.world.build import (
    as_obstacles,
    build_world,
    default_cell_volume,
    inflated_obstacles,
    map_box,
)

__all__ = ["PlanResult", "as_obstacles", "build_world", "default_cell_volume",
           "inflated_obstacles", "map_box", "plan", "unknown_on_path"]
