"""lattice planner: path planning on non-cubic 3D lattices over occupied voxel lists."""

from planner.errors import LatticeError, MapError, PlanError, PlannerError
from planner.lattice import NAMED_LATTICES, Lattice

__all__ = [
    "NAMED_LATTICES",
    "Lattice",
    "LatticeError",
    "MapError",
    "PlanError",
    "PlannerError",
]
__version__ = "0.1.0"
