"""The face walk's fast steps (numba): the inner loops of
:func:`planner.occupancy.facewalk.face_walk` and the layout of its scratch, in a module of
their own (the walk's set-up and its tie handling stay there).

A fast step goes from a Voronoi cell through the one facet at the segment's exit point:
the exit times of the facets facing forward are kept in eight scalars, the next exit is
their minimum, and a step adds the crossed facet's row of the change table to them, the
way a cubic DDA adds tDelta to tMax.

The eight exit times are integer keys while the steps run: the time in fixed point (a
power-of-two scale per line, ``sc``, from a bound on every exit time of the line) with the
slot's number in its three low bits, and the change table's entries multiples of 8. The
minimum key is then the next exit and names its slot, with no compare of each time against
it: one integer minimum, a mask and a load per step (the float version compared all eight
against the minimum and counted the matches, twice the step's time). The rounding of the
table to the scale's unit (at most 16 units a step and slot) is what the walk's tie
decisions must tolerate: :func:`planner.occupancy.facewalk.face_walk` bounds it.

A cell of at most four facet pairs (the hexagonal prism) steps on four keys
(:func:`run_one4`: the same loop with half the minimum tree and half the additions, some
12% of a hex line's time), one of at most six (FCC) on six (:func:`run_one6`: ``python
benchmarks/lattice_sight.py`` put FCC's walk at 1.52-1.61 x cubic per cell, at 1.69 on
eight keys); :func:`steps` picks the variant. The steps from both ends at once are in
:mod:`planner.occupancy.facemirror`.
"""

from __future__ import annotations

import numpy as np

from planner._numba import njit_cached

__all__ = ["BLOCKED", "END", "KEY_BITS", "LOW", "MET", "SLOTS", "STEPPED", "TIE", "TIE_P",
           "face_scratch", "first_exit", "first_key", "key", "recorded", "run_one", "run_one4",
           "run_one6", "steps"]

SLOTS = 8  # exit-time slots: forward facets of a 3D Voronoi cell (at most 7)
KEY_BITS = 57  # a line's exit times in fixed point stay below 2**KEY_BITS
KEY_CAP = 2.0 ** 60  # the key of an empty slot (parallel facets, padding): never the next
# Scratch (``sf`` float64, ``si`` int64, from face_scratch): 1 / |d . v| of slot k, the
# sign of slot k's facet (+1: its pair's first, 0: parallel), sign / |d . w_k|, the first
# exit time of slot k; the facet of slot k, the flat index step through slot k's facet,
# the key of slot k, the change of slot k's key on a step through slot i (8, 8), the bit
# of slot k's facet (0: parallel, padding), the tie slack of slot k's key (a key within
# it of the next exit's: that facet passes through the exit point), the number of slots
# the padding (the slots past them) was set for, the cells the segment runs along (SM,:
# flat indices), the number of cells to record and the record.
S_IDQ, S_SG, S_SY, S_T, S_F = 0, 8, 16, 24, 32
S_FW, S_STEP, S_KEY, S_KINC, S_BIT, S_ON, S_NP, S_CUR = 0, 8, 16, 24, 88, 96, 104, 105

# how run_one and run_mirror stop (TIE_P: run_mirror's tie on the walk from p alone)
END, BLOCKED, TIE, STEPPED, MET, TIE_P = 0, 1, 2, 3, 4, 5
LOW = np.int64(-8)  # clears a key's slot bits


def face_scratch(sm: int, record: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """Scratch ``(sf, si)`` for :func:`planner.occupancy.facewalk.face_walk`: ``sm`` cells
    around a face, ``record`` cells to record in ``si`` (tests; :func:`recorded` reads
    them). A scratch serves one walk at a time, of any lattice."""
    si = np.zeros(S_CUR + max(sm, 1) + 1 + 3 * record, np.int64)
    si[S_CUR + max(sm, 1)] = record
    return np.zeros(S_F), si


@njit_cached
def recorded(si, sm, n):  # pragma: no cover - compiled
    """The first ``n`` cells :func:`planner.occupancy.facewalk.face_walk` looked up, (n, 3),
    from a recording scratch."""
    o = S_CUR + max(sm, 1) + 1
    return si[o:o + 3 * n].reshape(-1, 3)


@njit_cached(_nrt=False)
def first_key(si, n):  # pragma: no cover - compiled
    """The earliest exit of the first ``n`` slots as a key, its slot bits cleared. All
    eight slots' minimum: the padding's keys are empty (KEY_CAP), and a fixed tree of
    minima has no loop to leave (a loop of ``n`` took a mispredicted exit per tie)."""
    m = min(min(min(si[S_KEY], si[S_KEY + 1]), min(si[S_KEY + 2], si[S_KEY + 3])),
            min(min(si[S_KEY + 4], si[S_KEY + 5]), min(si[S_KEY + 6], si[S_KEY + 7])))
    return m & LOW


@njit_cached(_nrt=False)
def first_exit(si, n, isc):  # pragma: no cover - compiled
    """The earliest exit time of the first ``n`` slots, from their keys."""
    return np.float64(first_key(si, n)) * isc


@njit_cached(_nrt=False)
def key(t, sc, k):  # pragma: no cover - compiled
    """Slot ``k``'s key of exit time ``t`` at scale ``sc`` (an empty slot's: KEY_CAP)."""
    return (np.int64(min(t * sc, KEY_CAP)) & LOW) | k


@njit_cached(_nrt=False)
def run_one(grid, si, idx, lookups, gi, one, dense, stop):  # pragma: no cover - compiled
    """The walk's fast steps, from the keys in ``si`` (``gi``: the tie margin, ``one``:
    the segment's end, as keys): while one facet alone is at the exit point, step through
    it and (``dense``) test the cell's bit at flat index ``idx``. Stops at the segment's
    end (``END``), a blocked cell (``BLOCKED``), a tie (``TIE``) or, not dense, after one
    step (``STEPPED``: the caller looks the cell up). Returns ``(code, idx, lookups, m)``,
    ``m`` the next exit's key; the keys back in ``si``. A function of its own, with few
    arguments and little state, so that the eight keys stay in registers (in the walk's
    body the compiler spilled the step's state around them)."""
    # Eight locals: at most half the facets face forward, and a 3D Voronoi cell has at
    # most 14. Branch-free minima: which facet comes next is not predictable (a
    # mispredicted branch per facet doubled the step's time).
    t0, t1, t2, t3 = si[S_KEY], si[S_KEY + 1], si[S_KEY + 2], si[S_KEY + 3]
    t4, t5, t6, t7 = si[S_KEY + 4], si[S_KEY + 5], si[S_KEY + 6], si[S_KEY + 7]
    code = END
    while True:
        m = min(min(min(t0, t1), min(t2, t3)), min(min(t4, t5), min(t6, t7)))
        if m >= one:
            break
        # A tie: a second key within the margin ((t - lim - 1) >> 63 is -1 for each key
        # at most lim); off the step's chain, which needs the minimum's slot bits only.
        lim = m + gi
        at = (((t0 - lim - 1) >> 63) + ((t1 - lim - 1) >> 63) + ((t2 - lim - 1) >> 63)
              + ((t3 - lim - 1) >> 63) + ((t4 - lim - 1) >> 63) + ((t5 - lim - 1) >> 63)
              + ((t6 - lim - 1) >> 63) + ((t7 - lim - 1) >> 63))
        if at < -1:
            code = TIE
            break
        # One facet at the exit point: step through it (unsigned indices: no
        # negative-index fix-up on each load).
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
    si[S_KEY], si[S_KEY + 1], si[S_KEY + 2], si[S_KEY + 3] = t0, t1, t2, t3
    si[S_KEY + 4], si[S_KEY + 5], si[S_KEY + 6], si[S_KEY + 7] = t4, t5, t6, t7
    return code, idx, lookups, m


@njit_cached(_nrt=False)
def run_one4(grid, si, idx, lookups, gi, one, dense, stop):  # pragma: no cover - compiled
    """:func:`run_one` for a cell of at most four facet pairs (hex prisms): four keys."""
    t0, t1, t2, t3 = si[S_KEY], si[S_KEY + 1], si[S_KEY + 2], si[S_KEY + 3]
    code = END
    while True:
        m = min(min(t0, t1), min(t2, t3))
        if m >= one:
            break
        # A tie: a second key within the margin ((t - lim - 1) >> 63 is -1 for each key
        # at most lim); off the step's chain, which needs the minimum's slot bits only.
        lim = m + gi
        at = (((t0 - lim - 1) >> 63) + ((t1 - lim - 1) >> 63) + ((t2 - lim - 1) >> 63)
              + ((t3 - lim - 1) >> 63))
        if at < -1:
            code = TIE
            break
        # One facet at the exit point: step through it (unsigned indices: no
        # negative-index fix-up on each load).
        st = np.uint64(m & 7)
        idx += si[np.uint64(S_STEP) + st]
        a = np.uint64(S_KINC) + np.uint64(SLOTS) * st
        t0 += si[a]
        t1 += si[a + np.uint64(1)]
        t2 += si[a + np.uint64(2)]
        t3 += si[a + np.uint64(3)]
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
    si[S_KEY], si[S_KEY + 1], si[S_KEY + 2], si[S_KEY + 3] = t0, t1, t2, t3
    return code, idx, lookups, m


@njit_cached(_nrt=False)
def run_one6(grid, si, idx, lookups, gi, one, dense, stop):  # pragma: no cover - compiled
    """:func:`run_one` for a cell of at most six facet pairs (FCC's rhombic dodecahedron):
    six keys."""
    t0, t1, t2, t3 = si[S_KEY], si[S_KEY + 1], si[S_KEY + 2], si[S_KEY + 3]
    t4, t5 = si[S_KEY + 4], si[S_KEY + 5]
    code = END
    while True:
        m = min(min(min(t0, t1), min(t2, t3)), min(t4, t5))
        if m >= one:
            break
        lim = m + gi
        at = (((t0 - lim - 1) >> 63) + ((t1 - lim - 1) >> 63) + ((t2 - lim - 1) >> 63)
              + ((t3 - lim - 1) >> 63) + ((t4 - lim - 1) >> 63) + ((t5 - lim - 1) >> 63))
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
    si[S_KEY], si[S_KEY + 1], si[S_KEY + 2], si[S_KEY + 3] = t0, t1, t2, t3
    si[S_KEY + 4], si[S_KEY + 5] = t4, t5
    return code, idx, lookups, m


# The picker is inlined (numba's IR inlining) where the walk calls it, as is
# planner.occupancy.facemirror.mirror_steps: as calls of their own, each a call level that
# passes both arrays again, the two cost the walk some 20 ns a line, an eighth of a short
# line's time (`python benchmarks/lattice_sight.py`, the sight table: bcc 1.62 -> 1.45 x
# the cubic walk per cell).
@njit_cached(_nrt=False, inline="always")
def steps(grid, si, idx, lookups, gi, one, dense, stop, npair):  # pragma: no cover
    """:func:`run_one` on the fewest keys that hold a cell's ``npair`` facet pairs."""
    if npair <= 4:
        return run_one4(grid, si, idx, lookups, gi, one, dense, stop)
    if npair <= 6:
        return run_one6(grid, si, idx, lookups, gi, one, dense, stop)
    return run_one(grid, si, idx, lookups, gi, one, dense, stop)

