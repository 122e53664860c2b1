"""The face walk's fast steps (numba): the inner loops of
:func:`planner.occupancy.facewalk.face_walk` and the layout of its scratch, in a module of
their own (the walk's set-up and its tie handling stay there).

A fast step goes from a Voronoi cell through the one facet at the segment's exit point:
the exit times of the facets facing forward are kept in eight scalars (``sf[S_T:]``), the
next exit is their minimum, and a step adds the crossed facet's row of the change table
(``sf[S_INC:]``) to them, the way a cubic DDA adds tDelta to tMax.
"""

from __future__ import annotations

import numpy as np
from numba.cpython.unsafe.numbers import trailing_zeros

from planner._numba import njit_cached

__all__ = ["BLOCKED", "END", "MET", "SLOTS", "STEPPED", "TIE", "run_mirror", "run_one"]

SLOTS = 8  # exit-time slots: forward facets of a 3D Voronoi cell (at most 7)
# Scratch (``sf`` float64, ``si`` int64, from face_scratch): exit time of forward slot k,
# 1 / (d . v) of slot k, d . v_r of facet r, the change of slot k's time on a step through
# slot i (8, 8); the facet of slot k, the flat index step through slot k's facet, the
# cells the segment runs along (SM,: flat indices), the number of cells to record and
# the record.
# The sign of slot k's facet (+1: its pair's first, 0: parallel) and 1 / (d . w_k).
S_T, S_IDQ, S_DQ, S_INC, S_SG, S_SY, S_F = 0, 8, 16, 32, 96, 104, 112
S_FW, S_STEP, S_CUR = 0, 8, 16

END, BLOCKED, TIE, STEPPED, MET = 0, 1, 2, 3, 4  # how run_one and run_mirror stop


@njit_cached(_nrt=False)
def run_one(grid, sf, si, idx, lookups, gap, dense, stop):  # pragma: no cover - compiled
    """The walk's fast steps, from the exit times in ``sf``: while one facet alone is at the
    exit point, step through it and (``dense``) test the cell's bit at flat index ``idx``.
    Stops at the segment's end (``END``), a blocked cell (``BLOCKED``), a tie
    (``TIE``) or, not dense, after one step (``STEPPED``: the caller looks the cell up).
    Returns ``(code, idx, lookups, m)``, ``m`` the next exit time; the exit times back in
    ``sf``. A function of its own, with few arguments and little state, so that the eight
    exit times stay in registers (in the walk's body the compiler spilled the step's state
    around them)."""
    # Eight locals: at most half the facets face forward, and a 3D Voronoi cell has at
    # most 14. Branch-free minima: which facet comes next is not predictable (a
    # mispredicted branch per facet doubled the step's time).
    t0, t1, t2, t3 = sf[S_T], sf[S_T + 1], sf[S_T + 2], sf[S_T + 3]
    t4, t5, t6, t7 = sf[S_T + 4], sf[S_T + 5], sf[S_T + 6], sf[S_T + 7]
    code = END
    while True:
        m = min(min(min(t0, t1), min(t2, t3)), min(min(t4, t5), min(t6, t7)))
        if m >= 1.0:
            break
        # The slot at the minimum (m is one of the times, exactly) picks the step; the tie
        # test (a second time within the margin) is off that chain, so the step's loads
        # need not wait for it.
        eq = (np.int64(t0 == m) | (np.int64(t1 == m) << 1) | (np.int64(t2 == m) << 2)
              | (np.int64(t3 == m) << 3) | (np.int64(t4 == m) << 4)
              | (np.int64(t5 == m) << 5) | (np.int64(t6 == m) << 6)
              | (np.int64(t7 == m) << 7))
        lim = m + gap
        at = (np.int64(t0 <= lim) + np.int64(t1 <= lim) + np.int64(t2 <= lim)
              + np.int64(t3 <= lim) + np.int64(t4 <= lim) + np.int64(t5 <= lim)
              + np.int64(t6 <= lim) + np.int64(t7 <= lim))
        if at > 1:
            code = TIE
            break
        # One facet at the exit point: step through it (unsigned indices: no
        # negative-index fix-up on each load).
        st = trailing_zeros(eq)
        idx += si[np.uint64(S_STEP + st)]
        a = np.uint64(S_INC + SLOTS * st)
        t0 += sf[a]
        t1 += sf[a + np.uint64(1)]
        t2 += sf[a + np.uint64(2)]
        t3 += sf[a + np.uint64(3)]
        t4 += sf[a + np.uint64(4)]
        t5 += sf[a + np.uint64(5)]
        t6 += sf[a + np.uint64(6)]
        t7 += sf[a + np.uint64(7)]
        if idx == stop:  # the far end's walk looked it up and the rest
            code = MET
            break
        lookups += 1
        if not dense:
            code = STEPPED
            break
        if (grid[np.uint64(idx) >> np.uint64(3)] >> (idx & 7)) & 1 == 0:
            code = BLOCKED
            break
    sf[S_T], sf[S_T + 1], sf[S_T + 2], sf[S_T + 3] = t0, t1, t2, t3
    sf[S_T + 4], sf[S_T + 5], sf[S_T + 6], sf[S_T + 7] = t4, t5, t6, t7
    return code, idx, lookups, m


@njit_cached(_nrt=False)
def run_mirror(grid, sf, si, idx, mir, lookups, gap, lim):  # pragma: no cover - compiled
    """:func:`run_one` on a dense grid, each step looking up the cell stepped into (flat
    index ``idx``) and its mirror image through the segment's midpoint (``mir - idx``), the
    cell the same step from q reaches: the walk from q need not be taken. Steps while the
    next exit time ``m`` is below ``lim / 2`` (just under the midpoint) and is one facet's
    alone; the mirror image is looked up while the exit time after the step plus ``m``
    stays below ``lim`` (the walks from both ends have not met: every cell is new).
    Returns ``(code, idx, stop, lookups)``: ``MET``, ``TIE`` or ``BLOCKED``; ``stop``
    the last mirror image looked up (q at first): the walk from p goes on until it reaches
    it (the segment is in its interior from there on, its later crossings single facets,
    the mirror images of this walk's). The exit times back in ``sf``."""
    t0, t1, t2, t3 = sf[S_T], sf[S_T + 1], sf[S_T + 2], sf[S_T + 3]
    t4, t5, t6, t7 = sf[S_T + 4], sf[S_T + 5], sf[S_T + 6], sf[S_T + 7]
    m = min(min(min(t0, t1), min(t2, t3)), min(min(t4, t5), min(t6, t7)))
    stop = mir - idx
    code = MET
    while m + m < lim:
        lm = m + gap
        # bit k: slot k's exit is at the minimum (up to the tie margin)
        at = (np.int64(t0 <= lm) | (np.int64(t1 <= lm) << 1) | (np.int64(t2 <= lm) << 2)
              | (np.int64(t3 <= lm) << 3) | (np.int64(t4 <= lm) << 4)
              | (np.int64(t5 <= lm) << 5) | (np.int64(t6 <= lm) << 6)
              | (np.int64(t7 <= lm) << 7))
        if at & (at - 1) != 0:
            code = TIE
            break
        st = trailing_zeros(at)
        idx += si[np.uint64(S_STEP + st)]
        a = np.uint64(S_INC + SLOTS * st)
        t0 += sf[a]
        t1 += sf[a + np.uint64(1)]
        t2 += sf[a + np.uint64(2)]
        t3 += sf[a + np.uint64(3)]
        t4 += sf[a + np.uint64(4)]
        t5 += sf[a + np.uint64(5)]
        t6 += sf[a + np.uint64(6)]
        t7 += sf[a + np.uint64(7)]
        lookups += 1
        if (grid[np.uint64(idx) >> np.uint64(3)] >> (idx & 7)) & 1 == 0:
            code = BLOCKED
            break
        mn = min(min(min(t0, t1), min(t2, t3)), min(min(t4, t5), min(t6, t7)))
        if mn + m >= lim:
            break
        stop = mir - idx
        lookups += 1
        if (grid[np.uint64(stop) >> np.uint64(3)] >> (stop & 7)) & 1 == 0:
            code = BLOCKED
            break
        m = mn
    sf[S_T], sf[S_T + 1], sf[S_T + 2], sf[S_T + 3] = t0, t1, t2, t3
    sf[S_T + 4], sf[S_T + 5], sf[S_T + 6], sf[S_T + 7] = t4, t5, t6, t7
    return code, idx, stop, lookups
