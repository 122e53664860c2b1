"""Deprecated alias of :mod:`planner.ompl` (the OMPL baseline), kept until every import
moves there."""

from planner.ompl import ANYTIME, PLANNERS, OmplResult, canonical_planner, plan_ompl, run_seeds

__all__ = ["ANYTIME", "PLANNERS", "OmplResult", "canonical_planner", "plan_ompl", "run_seeds"]
