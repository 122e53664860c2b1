"""The occupancy layer every stage shares: packed cell keys, blocked-cell lookups and the
exact segment walk (numba kernels and their typed structs).

:mod:`~planner.occupancy.keys` (packing indices into int64 keys), :mod:`~planner.occupancy.grid`
(:class:`Occupancy` lookups, :class:`Walk` and the exact segment walk).
"""

from planner.occupancy.grid import Occupancy, Walk
from planner.occupancy.keys import BITS, check_range, index_limit, pack, unpack

__all__ = ["BITS", "Occupancy", "Walk", "check_range", "index_limit", "pack", "unpack"]
