"""Line of sight for many segments in one call: the test every any-angle search and
:func:`~planner.search.shortcut` apply between two cells, exposed for batches."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from planner.errors import PlanError
from planner.occupancy.walk import as_cells
from planner.search._los import is_cubic, longest_segment, new_scratch, sight_batch
from planner.world.world import World


class Sight(NamedTuple):
    """Per segment: whether it is in sight, and the cells looked up to decide it.

    Attributes
    ----------
    free : ndarray, shape (N,), bool
        True iff every cell whose closed Voronoi cell the centre-to-centre segment touches
        is free (the searches' own rule; the same answer as
        :meth:`planner.world.World.segment_free` between the two centres).
    lookups : ndarray, shape (N,), int64
        Cells looked up for that segment (the walk stops at the first blocked one).
    """

    free: np.ndarray
    lookups: np.ndarray


def sight_many(world: World, starts, goals) -> Sight:
    """Line of sight between the centres of ``starts[i]`` and ``goals[i]`` for every i, by
    the walk the searches use (the cubic integer walk on the cubic lattice, the face walk
    on the others), compiled, in one call.

    Parameters
    ----------
    world : World
    starts, goals : array_like of int, shape (N, 3)
        Lattice indices of each segment's ends.

    Returns
    -------
    Sight
        ``free`` and ``lookups`` per segment, shape (N,) each. The total of ``lookups`` is
        added to ``world.cell_checks``.

    Raises
    ------
    PlanError
        When ``starts`` and ``goals`` are not integer arrays of the same shape (N, 3).
    """
    p, q = as_cells(starts), as_cells(goals)
    if p.shape != q.shape:
        raise PlanError(f"starts and goals must have the same shape, got {p.shape} and "
                        f"{q.shape}")
    free = np.zeros(len(p), dtype=np.bool_)
    lookups = np.zeros(len(p), dtype=np.int64)
    if len(p):
        chk = world.checker
        # Longest sight line of the batch (x2 headroom), for the generic walk's scratch
        # (compiled: numpy's temporaries cost about 1 ns per cell of a batch).
        # The cubic lattice's integer walk needs none.
        span = 0.0 if is_cubic(chk.walk.g) else 2.0 * longest_segment(chk.walk.g, p, q) + 1.0
        total = sight_batch(chk.occupancy, chk.walk, p, q, new_scratch(span, chk.walk),
                            free, lookups)
        world.cell_checks += int(total)
    return Sight(free, lookups)
