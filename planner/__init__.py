"""lattice planner: path planning on non-cubic 3D lattices over occupied voxel lists.

The pipeline, one module per step: points (:mod:`planner.io`) -> lattice indices
(:class:`Lattice`) -> occupied voxel list (:class:`OccupiedVoxelList`) -> planning world
(:class:`World`) -> search (:mod:`planner.search`, :mod:`planner.ompl`) -> path
(:class:`PlanResult`) -> metrics (:mod:`planner.bench`, :mod:`planner.analysis`).
"""

from planner.errors import LatticeError, MapError, PlanError, PlannerError
from planner.lattice import NAMED_LATTICES, Lattice

__all__ = [
    "NAMED_LATTICES",
    "Lattice",
    "LatticeError",
    "MapError",
    "OccupiedVoxelList",
    "PlanError",
    "PlanResult",
    "PlannerError",
    "World",
    "build_world",
    "plan",
]
__version__ = "0.1.0"

# Lazy so that `import planner` stays cheap (the search and voxel modules load numba kernels).
_LAZY = {
    "OccupiedVoxelList": "planner.voxels",
    "World": "planner.world",
    "PlanResult": "planner.planning",
    "build_world": "planner.world.build",
    "plan": "planner.planning",
}


_SUBMODULES = ("analysis", "api", "bench", "explore", "io", "lattice", "maps", "occupancy", "ompl",
               "path", "planning", "search", "voxels", "world")


def __getattr__(name: str):
    import importlib

    if name in _LAZY:
        return getattr(importlib.import_module(_LAZY[name]), name)
    if name in _SUBMODULES:  # `planner.io.load_points(...)` without importing planner.io
        return importlib.import_module(f"planner.{name}")
    raise AttributeError(f"module 'planner' has no attribute {name!r}")
