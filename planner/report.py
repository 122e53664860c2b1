"""Moved to :mod:`planner.analysis.compare`; this name keeps old imports working."""

from planner.analysis.compare import *  # noqa: F403
from planner.analysis.compare import __all__  # noqa: F401
