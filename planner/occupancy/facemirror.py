"""The face walk's fast steps from both ends at once (numba): each step from p also looks
up the cell's mirror image through the segment's midpoint, the cell the same step from q
reaches (:func:`planner.occupancy.facewalk.face_walk` explains why it may), on the keys and
the scratch of :mod:`planner.occupancy.facestep`, whose single-ended loops these mirror:
eight keys (:func:`run_mirror`), six (:func:`run_mirror6`: FCC) and four
(:func:`run_mirror4`: hex prisms), :func:`mirror_steps` picking the variant. Each goes on
from p alone to the last mirror image it looked up, so that most lines end in one call.
"""

from __future__ import annotations

import numpy as np

from planner._numba import njit_cached
from planner.occupancy.facestep import (
    BLOCKED,
    END,
    MET,
    S_KEY,
    S_KINC,
    S_STEP,
    SLOTS,
    TIE,
    TIE_P,
)

__all__ = ["mirror_steps", "run_mirror", "run_mirror4", "run_mirror6"]


@njit_cached(_nrt=False)
def run_mirror(grid, si, idx, mir, lookups, gi, li, one):  # pragma: no cover - compiled
    """:func:`~planner.occupancy.facestep.run_one` on a dense grid, each step looking up
    the cell stepped into (flat index ``idx``) and its mirror image through the segment's
    midpoint (``mir - idx``), the cell the same step from q reaches: the walk from q need
    not be taken. Steps while the next exit's key ``m`` is below ``li / 2`` (just under
    the midpoint) and is one facet's alone; the mirror image is looked up while the exit
    after the step plus ``m`` stays below ``li`` (the walks from both ends have not met:
    every cell is new). Then, as ``run_one`` with ``one`` (the segment's end as a key),
    the walk from p goes on alone until it reaches ``stop``, the last mirror image looked
    up (q at first): the cells between the two walks, most often one step or none. In
    this call, not a second one: a call of its own cost a short line some 10 ns (`python
    benchmarks/lattice_sight.py`, the sight table: 2-6% per cell on every lattice).
    Returns ``(code, idx, stop, lookups)``: ``MET`` (or ``END``), the walk has reached
    ``stop`` and is done; ``TIE``, a tie on the mirrored steps; ``TIE_P``, a tie on the
    walk from p alone; ``BLOCKED``. The keys back in ``si``."""
    t0, t1, t2, t3 = si[S_KEY], si[S_KEY + 1], si[S_KEY + 2], si[S_KEY + 3]
    t4, t5, t6, t7 = si[S_KEY + 4], si[S_KEY + 5], si[S_KEY + 6], si[S_KEY + 7]
    m = min(min(min(t0, t1), min(t2, t3)), min(min(t4, t5), min(t6, t7)))
    stop = mir - idx
    code = MET
    while m + m < li:
        lm = m + gi
        at = (((t0 - lm - 1) >> 63) + ((t1 - lm - 1) >> 63) + ((t2 - lm - 1) >> 63)
              + ((t3 - lm - 1) >> 63) + ((t4 - lm - 1) >> 63) + ((t5 - lm - 1) >> 63)
              + ((t6 - lm - 1) >> 63) + ((t7 - lm - 1) >> 63))
        if at < -1:
            code = TIE
            break
        st = np.uint64(m & 7)
        idx += si[np.uint64(S_STEP) + st]
        a = np.uint64(S_KINC) + np.uint64(SLOTS) * st
        t0 += si[a]
        t1 += si[a + np.uint64(1)]
        t2 += si[a + np.uint64(2)]
        t3 += si[a + np.uint64(3)]
        t4 += si[a + np.uint64(4)]
        t5 += si[a + np.uint64(5)]
        t6 += si[a + np.uint64(6)]
        t7 += si[a + np.uint64(7)]
        lookups += 1
        if (grid[np.uint64(idx) >> np.uint64(3)] >> (idx & 7)) & 1 == 0:
            code = BLOCKED
            break
        mn = min(min(min(t0, t1), min(t2, t3)), min(min(t4, t5), min(t6, t7)))
        if mn + m >= li:
            break
        stop = mir - idx
        lookups += 1
        if (grid[np.uint64(stop) >> np.uint64(3)] >> (stop & 7)) & 1 == 0:
            code = BLOCKED
            break
        m = mn
    if code == MET:
        # From p alone to the last mirror image (the cells between them), as run_one:
        # most lines end here, in this call.
        while idx != stop:
            m = min(min(min(t0, t1), min(t2, t3)), min(min(t4, t5), min(t6, t7)))
            if m >= one:
                code = END
                break
            lm = m + gi
            at = (((t0 - lm - 1) >> 63) + ((t1 - lm - 1) >> 63) + ((t2 - lm - 1) >> 63) +
                  ((t3 - lm - 1) >> 63) + ((t4 - lm - 1) >> 63) + ((t5 - lm - 1) >> 63) +
                  ((t6 - lm - 1) >> 63) + ((t7 - lm - 1) >> 63))
            if at < -1:
                code = TIE_P
                break
            st = np.uint64(m & 7)
            idx += si[np.uint64(S_STEP) + st]
            a = np.uint64(S_KINC) + np.uint64(SLOTS) * st
            t0 += si[a]
            t1 += si[a + np.uint64(1)]
            t2 += si[a + np.uint64(2)]
            t3 += si[a + np.uint64(3)]
            t4 += si[a + np.uint64(4)]
            t5 += si[a + np.uint64(5)]
            t6 += si[a + np.uint64(6)]
            t7 += si[a + np.uint64(7)]
            if idx == stop:
                break
            lookups += 1
            if (grid[np.uint64(idx) >> np.uint64(3)] >> (idx & 7)) & 1 == 0:
                code = BLOCKED
                break
    si[S_KEY], si[S_KEY + 1], si[S_KEY + 2], si[S_KEY + 3] = t0, t1, t2, t3
    si[S_KEY + 4], si[S_KEY + 5], si[S_KEY + 6], si[S_KEY + 7] = t4, t5, t6, t7
    return code, idx, stop, lookups


@njit_cached(_nrt=False)
def run_mirror4(grid, si, idx, mir, lookups, gi, li, one):  # pragma: no cover - compiled
    """:func:`run_mirror` for a cell of at most four facet pairs (hex prisms): four keys."""
    t0, t1, t2, t3 = si[S_KEY], si[S_KEY + 1], si[S_KEY + 2], si[S_KEY + 3]
    m = min(min(t0, t1), min(t2, t3))
    stop = mir - idx
    code = MET
    while m + m < li:
        lm = m + gi
        at = (((t0 - lm - 1) >> 63) + ((t1 - lm - 1) >> 63) + ((t2 - lm - 1) >> 63)
              + ((t3 - lm - 1) >> 63))
        if at < -1:
            code = TIE
            break
        st = np.uint64(m & 7)
        idx += si[np.uint64(S_STEP) + st]
        a = np.uint64(S_KINC) + np.uint64(SLOTS) * st
        t0 += si[a]
        t1 += si[a + np.uint64(1)]
        t2 += si[a + np.uint64(2)]
        t3 += si[a + np.uint64(3)]
        lookups += 1
        if (grid[np.uint64(idx) >> np.uint64(3)] >> (idx & 7)) & 1 == 0:
            code = BLOCKED
            break
        mn = min(min(t0, t1), min(t2, t3))
        if mn + m >= li:
            break
        stop = mir - idx
        lookups += 1
        if (grid[np.uint64(stop) >> np.uint64(3)] >> (stop & 7)) & 1 == 0:
            code = BLOCKED
            break
        m = mn
    if code == MET:
        # From p alone to the last mirror image (the cells between them), as run_one:
        # most lines end here, in this call.
        while idx != stop:
            m = min(min(t0, t1), min(t2, t3))
            if m >= one:
                code = END
                break
            lm = m + gi
            at = (((t0 - lm - 1) >> 63) + ((t1 - lm - 1) >> 63) + ((t2 - lm - 1) >> 63) +
                  ((t3 - lm - 1) >> 63))
            if at < -1:
                code = TIE_P
                break
            st = np.uint64(m & 7)
            idx += si[np.uint64(S_STEP) + st]
            a = np.uint64(S_KINC) + np.uint64(SLOTS) * st
            t0 += si[a]
            t1 += si[a + np.uint64(1)]
            t2 += si[a + np.uint64(2)]
            t3 += si[a + np.uint64(3)]
            if idx == stop:
                break
            lookups += 1
            if (grid[np.uint64(idx) >> np.uint64(3)] >> (idx & 7)) & 1 == 0:
                code = BLOCKED
                break
    si[S_KEY], si[S_KEY + 1], si[S_KEY + 2], si[S_KEY + 3] = t0, t1, t2, t3
    return code, idx, stop, lookups


@njit_cached(_nrt=False)
def run_mirror6(grid, si, idx, mir, lookups, gi, li, one):  # pragma: no cover - compiled
    """:func:`run_mirror` for a cell of at most six facet pairs (FCC's rhombic dodecahedron):
    six keys."""
    t0, t1, t2, t3 = si[S_KEY], si[S_KEY + 1], si[S_KEY + 2], si[S_KEY + 3]
    t4, t5 = si[S_KEY + 4], si[S_KEY + 5]
    m = min(min(min(t0, t1), min(t2, t3)), min(t4, t5))
    stop = mir - idx
    code = MET
    while m + m < li:
        lm = m + gi
        at = (((t0 - lm - 1) >> 63) + ((t1 - lm - 1) >> 63) + ((t2 - lm - 1) >> 63)
              + ((t3 - lm - 1) >> 63) + ((t4 - lm - 1) >> 63) + ((t5 - lm - 1) >> 63))
        if at < -1:
            code = TIE
            break
        st = np.uint64(m & 7)
        idx += si[np.uint64(S_STEP) + st]
        a = np.uint64(S_KINC) + np.uint64(SLOTS) * st
        t0 += si[a]
        t1 += si[a + np.uint64(1)]
        t2 += si[a + np.uint64(2)]
        t3 += si[a + np.uint64(3)]
        t4 += si[a + np.uint64(4)]
        t5 += si[a + np.uint64(5)]
        lookups += 1
        if (grid[np.uint64(idx) >> np.uint64(3)] >> (idx & 7)) & 1 == 0:
            code = BLOCKED
            break
        mn = min(min(min(t0, t1), min(t2, t3)), min(t4, t5))
        if mn + m >= li:
            break
        stop = mir - idx
        lookups += 1
        if (grid[np.uint64(stop) >> np.uint64(3)] >> (stop & 7)) & 1 == 0:
            code = BLOCKED
            break
        m = mn
    if code == MET:
        # From p alone to the last mirror image (the cells between them), as run_one:
        # most lines end here, in this call.
        while idx != stop:
            m = min(min(min(t0, t1), min(t2, t3)), min(t4, t5))
            if m >= one:
                code = END
                break
            lm = m + gi
            at = (((t0 - lm - 1) >> 63) + ((t1 - lm - 1) >> 63) + ((t2 - lm - 1) >> 63) +
                  ((t3 - lm - 1) >> 63) + ((t4 - lm - 1) >> 63) + ((t5 - lm - 1) >> 63))
            if at < -1:
                code = TIE_P
                break
            st = np.uint64(m & 7)
            idx += si[np.uint64(S_STEP) + st]
            a = np.uint64(S_KINC) + np.uint64(SLOTS) * st
            t0 += si[a]
            t1 += si[a + np.uint64(1)]
            t2 += si[a + np.uint64(2)]
            t3 += si[a + np.uint64(3)]
            t4 += si[a + np.uint64(4)]
            t5 += si[a + np.uint64(5)]
            if idx == stop:
                break
            lookups += 1
            if (grid[np.uint64(idx) >> np.uint64(3)] >> (idx & 7)) & 1 == 0:
                code = BLOCKED
                break
    si[S_KEY], si[S_KEY + 1], si[S_KEY + 2], si[S_KEY + 3] = t0, t1, t2, t3
    si[S_KEY + 4], si[S_KEY + 5] = t4, t5
    return code, idx, stop, lookups


# Inlined where the walk calls it (facestep.steps says why).
@njit_cached(_nrt=False, inline="always")
def mirror_steps(grid, si, idx, mir, lookups, gi, li, one, npair):  # pragma: no cover
    """:func:`run_mirror` on the fewest keys that hold a cell's ``npair`` facet pairs."""
    if npair <= 4:
        return run_mirror4(grid, si, idx, mir, lookups, gi, li, one)
    if npair <= 6:
        return run_mirror6(grid, si, idx, mir, lookups, gi, li, one)
    return run_mirror(grid, si, idx, mir, lookups, gi, li, one)
