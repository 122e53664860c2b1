"""The occupancy layer every stage shares: packed cell keys, blocked-cell lookups and the
exact segment walk (numba kernels and their typed structs).

:mod:`~planner.occupancy.keys` (packing indices into int64 keys, key sets),
:mod:`~planner.occupancy.grid` (:class:`Occupancy` and its lookups),
:mod:`~planner.occupancy.walk` (:class:`Walk` and the exact segment walk),
:mod:`~planner.occupancy.facewalk` (sight lines between cell centres on every lattice).
"""

from planner.occupancy.grid import Occupancy
from planner.occupancy.keys import BITS, check_range, index_limit, pack, unique_keys, unpack
from planner.occupancy.walk import Walk, as_cells, segment_walk, walk_of

__all__ = ["BITS", "Occupancy", "Walk", "as_cells", "check_range", "index_limit", "pack",
           "segment_walk", "unique_keys", "unpack", "walk_of"]
