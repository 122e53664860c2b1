"""Moved to :mod:`planner.analysis.measure`; this name keeps old imports working."""

from planner.analysis.measure import *  # noqa: F403
from planner.analysis.measure import __all__  # noqa: F401
