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

__all__ = ["BLOCKED", "END", "MET", "SLOTS", "STEPPED", "TIE", "run_both", "run_one"]

SLOTS = 8  # exit-time slots: forward facets of a 3D Voronoi cell (at most 7)
# Scratch (``sf`` float64, ``si`` int64, from face_scratch): exit time of forward slot k,
# 1 / (d . v) of slot k, d . v_r of facet r, the change of slot k's time on a step through
# slot i (8, 8); the facet of slot k, the flat index step through slot k's facet, the
# cells the segment runs along (SM, 3), the number of cells to record and the record.
# The walk from the far end (:func:`run_both`): its exit times at S_TB, their change per
# step at S_INCB (1 / (-d . v) at S_IDQB), its facets at S_FWB and flat index steps at S_STEPB.
S_T, S_IDQ, S_DQ, S_INC, S_TB, S_IDQB, S_INCB, S_F = 0, 8, 16, 32, 96, 104, 112, 176
S_FW, S_STEP, S_FWB, S_STEPB, S_CUR = 0, 8, 16, 24, 32

END, BLOCKED, TIE, STEPPED, MET = 0, 1, 2, 3, 4  # how run_one and run_both stop


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
def run_both(grid, sf, si, idx, idb, lookups, gap, lim):  # pragma: no cover - compiled
    """Fast steps from both ends of the segment in turn, on a dense grid: from p through
    the exit times at ``S_T`` (flat index ``idx``) and from q through those at ``S_TB``
    (walking q -> p, flat index ``idb``), while the near end's next exit time plus the far
    end's stays below ``lim`` (just under 1: the two chains have not met, so every cell
    stepped into is new) and each step is through one facet alone. Two independent
    chains of exit times: each step waits for the previous one's minimum and table loads,
    and the other end's step fills that wait. Returns ``(code, idx, idb, lookups)``
    (``MET``, ``TIE`` or ``BLOCKED``), the near end's exit times back in ``sf``. Every
    cell the far end stepped through, q included, was looked up; the near end's walk goes
    on until it reaches cell ``idb`` (looked up): the segment is in that cell's interior
    from there on, its crossings single facets."""
    t0, t1, t2, t3 = sf[S_T], sf[S_T + 1], sf[S_T + 2], sf[S_T + 3]
    t4, t5, t6, t7 = sf[S_T + 4], sf[S_T + 5], sf[S_T + 6], sf[S_T + 7]
    u0, u1, u2, u3 = sf[S_TB], sf[S_TB + 1], sf[S_TB + 2], sf[S_TB + 3]
    u4, u5, u6, u7 = sf[S_TB + 4], sf[S_TB + 5], sf[S_TB + 6], sf[S_TB + 7]
    m = min(min(min(t0, t1), min(t2, t3)), min(min(t4, t5), min(t6, t7)))
    mb = min(min(min(u0, u1), min(u2, u3)), min(min(u4, u5), min(u6, u7)))
    code = MET
    while m + mb < lim:
        lm = m + gap
        if (np.int64(t0 <= lm) + np.int64(t1 <= lm) + np.int64(t2 <= lm)
                + np.int64(t3 <= lm) + np.int64(t4 <= lm) + np.int64(t5 <= lm)
                + np.int64(t6 <= lm) + np.int64(t7 <= lm)) > 1:
            code = TIE
            break
        st = trailing_zeros(np.int64(t0 == m) | (np.int64(t1 == m) << 1)
                            | (np.int64(t2 == m) << 2) | (np.int64(t3 == m) << 3)
                            | (np.int64(t4 == m) << 4) | (np.int64(t5 == m) << 5)
                            | (np.int64(t6 == m) << 6) | (np.int64(t7 == m) << 7))
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
        m = min(min(min(t0, t1), min(t2, t3)), min(min(t4, t5), min(t6, t7)))
        if m + mb >= lim:
            break
        lm = mb + gap
        if (np.int64(u0 <= lm) + np.int64(u1 <= lm) + np.int64(u2 <= lm)
                + np.int64(u3 <= lm) + np.int64(u4 <= lm) + np.int64(u5 <= lm)
                + np.int64(u6 <= lm) + np.int64(u7 <= lm)) > 1:
            code = TIE
            break
        st = trailing_zeros(np.int64(u0 == mb) | (np.int64(u1 == mb) << 1)
                            | (np.int64(u2 == mb) << 2) | (np.int64(u3 == mb) << 3)
                            | (np.int64(u4 == mb) << 4) | (np.int64(u5 == mb) << 5)
                            | (np.int64(u6 == mb) << 6) | (np.int64(u7 == mb) << 7))
        idb += si[np.uint64(S_STEPB + st)]
        a = np.uint64(S_INCB + SLOTS * st)
        u0 += sf[a]
        u1 += sf[a + np.uint64(1)]
        u2 += sf[a + np.uint64(2)]
        u3 += sf[a + np.uint64(3)]
        u4 += sf[a + np.uint64(4)]
        u5 += sf[a + np.uint64(5)]
        u6 += sf[a + np.uint64(6)]
        u7 += sf[a + np.uint64(7)]
        lookups += 1
        if (grid[np.uint64(idb) >> np.uint64(3)] >> (idb & 7)) & 1 == 0:
            code = BLOCKED
            break
        mb = min(min(min(u0, u1), min(u2, u3)), min(min(u4, u5), min(u6, u7)))
    sf[S_T], sf[S_T + 1], sf[S_T + 2], sf[S_T + 3] = t0, t1, t2, t3
    sf[S_T + 4], sf[S_T + 5], sf[S_T + 6], sf[S_T + 7] = t4, t5, t6, t7
    return code, idx, idb, lookups
