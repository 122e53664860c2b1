"""Exploration: a robot plans through a map it does not know, senses, and replans.

:func:`explore` and :class:`ExploreResult` (:mod:`~planner.explore.run`), the simulated range
sensor (:mod:`~planner.explore.sensor`) and the run's figures (:mod:`~planner.explore.figures`).
"""

from planner.explore.run import ExploreResult, explore
from planner.explore.sensor import Sensor, cast_rays, ray_directions

__all__ = ["ExploreResult", "Sensor", "cast_rays", "explore", "ray_directions"]
