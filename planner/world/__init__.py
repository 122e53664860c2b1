"""The planning world: a lattice, its blocked cells, a box, and its one validity checker.

:mod:`~planner.world.world` (:class:`World`, :class:`ValidityChecker`), its unknown-space
queries (:mod:`~planner.world.unknown`) and saved worlds (:mod:`~planner.world.file`).
"""

from planner.world.world import (
    DENSE_BUDGET,
    Occupancy,
    ValidityChecker,
    Walk,
    World,
    as_point,
)

__all__ = ["DENSE_BUDGET", "Occupancy", "ValidityChecker", "Walk", "World", "as_point"]
