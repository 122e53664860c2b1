"""Argument checks shared by every stage, one home each (the map readers' point checks are in
:mod:`planner.io.validate`)."""

from __future__ import annotations

import math
from numbers import Real

from planner.errors import PlanError

__all__ = ["check_radius"]


def check_radius(radius) -> float:
    """``radius`` (m) as a float; PlanError unless it is a finite number >= 0 (a bool or a
    string is not a radius)."""
    if isinstance(radius, bool) or not isinstance(radius, Real):
        raise PlanError(f"radius must be a non-negative number of metres, got {radius!r}")
    r = float(radius)
    if not math.isfinite(r) or r < 0:
        raise PlanError(f"radius must be a non-negative number of metres, got {radius!r}")
    return r
