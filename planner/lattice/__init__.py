"""Lattice geometry: generators, exact quantization, Voronoi cells and adjacency.

:class:`Lattice` (:mod:`~planner.lattice.lattice`), its geometry
(:mod:`~planner.lattice._geometry`, the cell as a polytope in
:mod:`~planner.lattice._polytope`), the closest-point kernels (:mod:`~planner.lattice.quantize`,
loaded on first use), the paper's generators (:mod:`~planner.lattice.paper`) and 2D lattices as
prisms (:mod:`~planner.lattice.planar`).
"""

import importlib

from planner.lattice._geometry import VoronoiCell
from planner.lattice.lattice import Lattice
from planner.lattice.paper import NAMED_LATTICES, PAPER_DELTAS, named_generator

__all__ = ["Lattice", "NAMED_LATTICES", "PAPER_DELTAS", "Quantizer", "VoronoiCell",
           "named_generator"]


def __getattr__(name: str):
    # Quantizer lives beside the numba kernels: loaded when asked for, so that
    # `import planner` does not import numba
    if name == "Quantizer":
        return importlib.import_module("planner.lattice.quantize").Quantizer
    raise AttributeError(f"module 'planner.lattice' has no attribute {name!r}")
