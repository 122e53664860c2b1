"""The planning world: a lattice, its blocked cells, a box, and its one validity checker.

:mod:`~planner.world.world` (:class:`World`, :class:`ValidityChecker`), its unknown-space
queries (:mod:`~planner.world.unknown`), saved worlds (:mod:`~planner.world.file`) and
:func:`build_world` with the one resolver of map defaults (:mod:`~planner.world.build`).
"""

from planner.world.build import MapDefaults, build_world, resolve_defaults
from planner.world.world import (
    DENSE_BUDGET,
    Occupancy,
    ValidityChecker,
    Walk,
    World,
    as_point,
)

__all__ = ["DENSE_BUDGET", "MapDefaults", "Occupancy", "ValidityChecker", "Walk", "World",
           "as_point", "build_world", "resolve_defaults"]
