"""The sight walk of every lattice (numba): from Voronoi cell to Voronoi cell through the facet
the segment leaves by, ties on edges and vertices resolved from the cell's face table.

Between two cell centres the segment touches the closed Voronoi cells of a chain of cells
it passes through, and besides them only cells whose boundary it meets: at an edge or a
vertex it passes through, or along a facet it runs in. :func:`face_walk` keeps the exit
time of the current cell through each facet facing forward (``t_r``, updated by a table
``inc`` when it steps; integer keys that name their facet, :mod:`planner.occupancy.
facestep`), and steps through the first facet when that facet is the only one
at the exit point and the segment runs in no facet: the common case, a few additions per
cell. Otherwise the exit point lies on a face (edge or vertex) of the cell named by the set
of facets through it; the face table (:class:`FaceTable`, from the cell's geometry) lists
the cells around that face, each with its facets through it. They all touch the segment
there; the ones it goes on in are those none of whose facets there faces forward, and among
them the one whose interior it enters (or, running along a facet, one of the two cells
sharing it) is the next chain cell. The same cells as :func:`planner.occupancy.walk.
segment_walk` (tests check both on random and tie-heavy segments); a tie the table does not
know (the float tolerances failing on a degenerate segment) reports ``ok`` False and the
caller walks the generic way.

Every walk is taken from both ends at no extra cost: the reflection through the segment's
midpoint maps the lattice's Voronoi cells and the segment onto themselves, so each fast
step from p looks up the cell it steps into and that cell's mirror image, the cell the same
step from q would reach (:func:`planner.occupancy.facemirror.run_mirror`), until the two are
about to meet; a tie met on the way looks up its cells' mirror images too, and the walk
goes on from both ends when the segment enters the next cell's interior. Then the walk
from p goes on as above and ends where it reaches the last mirror image (the segment is in
that cell's interior from there on, and the crossings beyond it are single facets, the
mirror images of the walk's own). Half the steps per cell. (One exit-time slot per pair
of opposite facets: a Voronoi cell's facets come in pairs, one of which faces forward.)
"""

from __future__ import annotations

import numpy as np
from numba.cpython.unsafe.numbers import leading_zeros

from planner._numba import njit_cached
from planner.occupancy.facemirror import mirror_steps
from planner.occupancy.facestep import (
    BLOCKED,
    END,
    KEY_BITS,
    LOW,
    MET,
    S_BIT,
    S_CUR,
    S_FW,
    S_IDQ,
    S_KEY,
    S_KINC,
    S_NP,
    S_ON,
    S_SG,
    S_STEP,
    S_SY,
    S_T,
    SLOTS,
    STEPPED,
    TIE,
    TIE_P,
    face_scratch,
    first_exit,
    first_key,
    key,
    recorded,
    steps,
)
from planner.occupancy.facetable import (
    F_A,
    F_H,
    F_REL,
    F_W,
    I_FMASK,
    I_R,
    I_REACH,
    I_SLOT,
    I_SM,
    I_STARMASK,
    I_STARN,
    I_STAROFF,
    FaceTable,
    face_table,
)
from planner.occupancy.grid import cell_free

__all__ = ["FaceTable", "face_scratch", "face_table", "face_walk", "recorded"]

SEG_TOL = 1e-9  # relative slack on each Voronoi half-space of every walk: contact counts
_PAR = 1e-12  # |cos| below which a facet is parallel to the segment
_ON = 1e-8  # slack (relative to |v|^2 / 2) below which a facet passes through the exit point
_GAP = 1e-6  # fast step only when the next exit is this much later (relative, as _ON)
_NEVER = 1e300  # exit time of an empty slot
# The fast steps' keys round each step's change of an exit time (facestep); a tie is
# decided on exit times only while their accumulated rounding stays below this share of
# the tie slack (_ON): past it (long lines with a facet nearly parallel to the segment,
# whose exit-time bound coarsens the scale) the generic walk decides.
_KEY_SAFE = 0.1 * _ON


# numpy's error model: a float division by zero (a parallel slot's, selected away) is not
# checked (no branch in the set-up's loop). Inlined where it is called (numba's IR inlining;
# its callers take its error model): a call passes some 90 words of arguments (the arrays
# of the occupancy, table and scratch), about 20 ns a line, a sixth of a short line's walk.
@njit_cached(_nrt=False, error_model="numpy", inline="always")
def face_walk(occ, fd, fi, sf, si, p0, p1, p2, q0, q1, q2):  # pragma: no cover - compiled
    """Line of sight between the centres of cells p and q: every cell whose closed Voronoi
    cell the segment touches is looked up, in order along it, until a blocked one.
    ``fd``, ``fi``: the lattice's :class:`FaceTable`; ``sf``, ``si``: :func:`face_scratch`.
    Returns ``(free, lookups, ok)``; ``ok`` False: a tie the face table does not know,
    nothing decided (walk the generic way)."""
    mode, grid, lo, dims, table, tmask, gg, blo, bhi = occ
    nrel = fi[I_R]
    sm = fi[I_SM]
    o_cells = fi[I_STAROFF]
    o_masks = fi[I_STARMASK]
    o_rec = S_CUR + max(sm, 1)
    nrec = si[o_rec]
    o_rec += 1
    e0, e1, e2 = q0 - p0, q1 - p1, q2 - p2
    x0 = gg[0, 0] * e0 + gg[0, 1] * e1 + gg[0, 2] * e2
    x1 = gg[1, 0] * e0 + gg[1, 1] * e1 + gg[1, 2] * e2
    x2 = gg[2, 0] * e0 + gg[2, 1] * e1 + gg[2, 2] * e2
    dn2 = x0 * x0 + x1 * x1 + x2 * x2
    # The walk tracks one flat index in a box holding every touched cell: the dense grid's
    # box when it holds them (then a lookup is a bit test), else the segment's own box
    # (cells from the index by division). One integer instead of three keeps the step's
    # state in registers. Recording (tests) takes the second way.
    b0 = min(p0, q0) - fi[I_REACH]
    b1 = min(p1, q1) - fi[I_REACH + 1]
    b2 = min(p2, q2) - fi[I_REACH + 2]
    d1 = max(p1, q1) + fi[I_REACH + 1] + 1 - b1
    d2 = max(p2, q2) + fi[I_REACH + 2] + 1 - b2
    dense = (mode == 0 and nrec == 0 and b0 >= lo[0] and b1 >= lo[1] and b2 >= lo[2]
             and max(p0, q0) + fi[I_REACH] < lo[0] + dims[0] and b1 + d1 <= lo[1] + dims[1]
             and b2 + d2 <= lo[2] + dims[2])
    if dense:
        b0, b1, b2, d1, d2 = lo[0], lo[1], lo[2], dims[1], dims[2]
    s1 = d2
    s0 = d1 * d2
    # One slot per pair of opposite facets (v, -v): the one facing forward, unless the
    # segment is parallel to both (exit time never). No branch on the direction (which
    # of a pair faces forward is unpredictable), and the table of a step's changes is
    # a product of whole rows: inc[j, k] = v_j . v_k / (d . v_k) = s_j (w_j . w_k) s_k / |y_k|
    # for v_j = s_j w_j (w_j the pair's first facet, y_k = d . w_k, s = sign y).
    npair = nrel // 2
    o_gp = F_REL + 3 * nrel
    nfw = npair
    fwm = np.int64(0)
    parm = np.int64(0)
    gap = 0.0
    tmax = 0.0  # a bound on every exit time of the line (facetable: F_A)
    t0min = _NEVER
    par2 = 2.0 * _PAR * _PAR * dn2
    if si[S_NP] != npair:  # a fresh scratch (or another lattice's): the padding slots,
        for j in range(npair, SLOTS):  # set once: never the next exit, never moved
            sf[S_T + j] = _NEVER
            sf[S_IDQ + j] = sf[S_SG + j] = sf[S_SY + j] = 0.0
            si[S_FW + j] = si[S_STEP + j] = si[S_BIT + j] = si[S_ON + j] = 0
            si[S_KEY + j] = key(_NEVER, 1.0, j)
            for k in range(SLOTS):
                si[S_KINC + SLOTS * j + k] = si[S_KINC + SLOTS * k + j] = 0
        si[S_NP] = npair
    # Every pair's slot alike, and no branch: the selects by which of a pair faces forward
    # (unpredictable) are arithmetic, as the compiler made branches of conditional
    # expressions.
    for j in range(npair):
        y = x0 * fd[F_W + j] + x1 * fd[F_W + SLOTS + j] + x2 * fd[F_W + 2 * SLOTS + j]
        h = fd[F_H + j]
        ay = abs(y)
        pos = np.int64(y > 0.0)
        live = np.int64(y * y > par2 * h)  # not parallel
        fp = -pos  # all ones if the pair's first faces forward
        fl = -live
        iy = np.float64(live) / max(ay, 1e-300)  # parallel: 0
        t = h * iy + np.float64(1 - live) * _NEVER  # exact (no tolerance): ties to rounding
        sg = np.float64(live * (pos + pos - 1))
        br = fi[I_SLOT + 2 * SLOTS + j]
        bs = fi[I_SLOT + 3 * SLOTS + j]
        fb = ((br & fp) | (bs & ~fp)) & fl  # the forward facet's bit
        fwm |= fb
        si[S_BIT + j] = fb
        parm |= (br | bs) & ~fl
        st = (fi[I_SLOT + 4 * SLOTS + j] * s0 + fi[I_SLOT + 5 * SLOTS + j] * s1
              + fi[I_SLOT + 6 * SLOTS + j])
        si[S_STEP + j] = st * (pos + pos - 1)
        si[S_FW + j] = (fi[I_SLOT + j] & fp) | (fi[I_SLOT + SLOTS + j] & ~fp)
        gap = max(gap, _GAP * h * iy)
        t0min = min(t0min, t)
        tmax = max(tmax, fd[F_A + j] * iy)
        sf[S_T + j] = t
        sf[S_IDQ + j] = iy
        sf[S_SG + j] = sg
        sf[S_SY + j] = sg * iy
    # The keys' scale: a power of two with every exit time of the line below
    # 2**KEY_BITS units, and the lookups after which a tie is past their precision (each
    # step moves a key by its rounded change: < 16 units, a lookup at most a step).
    if tmax >= 2.0 ** 40:  # a facet all but parallel to a long line: keys too coarse
        return True, 0, False
    ex = 64 - leading_zeros(np.int64(1.0 + tmax))  # 1 + tmax < 2**ex
    sc = np.float64(np.int64(1) << (KEY_BITS - ex))
    isc = 1.0 / sc
    nsafe = _KEY_SAFE * t0min * np.float64(np.int64(1) << (KEY_BITS - 6 - ex))
    for j in range(npair):
        si[S_KEY + j] = key(sf[S_T + j], sc, j)
        # the tie slack (_ON, relative to |v|^2 / 2) of this facet's exit time, in key units
        si[S_ON + j] = np.int64(_ON * fd[F_H + j] * sf[S_IDQ + j] * sc)
    # The change table in keys (multiples of 8: the slot bits stay), rows of the pairs
    # only: the padding's and parallel slots' products are zeros, so their keys stay
    # empty. Whole rows from locals: independent products, the columns of the pairs only
    # (at most seven: the eighth is padding; the padding's columns stay zeros, set once).
    y0, y1, y2, y3 = sf[S_SY] * sc, sf[S_SY + 1] * sc, sf[S_SY + 2] * sc, sf[S_SY + 3] * sc
    y4, y5, y6 = sf[S_SY + 4] * sc, sf[S_SY + 5] * sc, sf[S_SY + 6] * sc
    low = np.int64(-8)
    for j in range(npair):
        sg = sf[S_SG + j]
        a = np.uint64(S_KINC + SLOTS * j)
        b = np.uint64(o_gp + SLOTS * j)
        si[a] = np.int64(sg * fd[b] * y0) & low
        si[a + np.uint64(1)] = np.int64(sg * fd[b + np.uint64(1)] * y1) & low
        si[a + np.uint64(2)] = np.int64(sg * fd[b + np.uint64(2)] * y2) & low
        si[a + np.uint64(3)] = np.int64(sg * fd[b + np.uint64(3)] * y3) & low
        if npair > 4:
            si[a + np.uint64(4)] = np.int64(sg * fd[b + np.uint64(4)] * y4) & low
            si[a + np.uint64(5)] = np.int64(sg * fd[b + np.uint64(5)] * y5) & low
            if npair > 6:
                si[a + np.uint64(6)] = np.int64(sg * fd[b + np.uint64(6)] * y6) & low
    idx = ((p0 - b0) * d1 + (p1 - b1)) * d2 + (p2 - b2)
    if nrec > 0:
        si[o_rec] = p0
        si[o_rec + 1] = p1
        si[o_rec + 2] = p2
    lookups = 1
    # On a dense grid (the box holding every touched cell inside it) a bit test.
    free = ((grid[np.uint64(idx) >> np.uint64(3)] >> (idx & 7)) & 1 != 0 if dense
            else cell_free(mode, grid, lo, dims, table, tmask, gg, blo, bhi, p0, p1, p2))
    if not free:
        return False, lookups, True
    if fwm == 0:  # p == q
        return True, lookups, True
    # The reflection through the segment's midpoint, c -> p + q - c, maps the lattice, its
    # Voronoi cells and the segment onto themselves: the cells the walk steps into from p
    # mirror those a walk from q would step into. So each fast step from p looks up its
    # cell and that cell's mirror image (flat index ``mir - idx``), while the two have not
    # met; then the walk from p goes on to the last mirrored cell (``stop``).
    stop = ((q0 - b0) * d1 + (q1 - b1)) * d2 + (q2 - b2)
    mir = idx + stop
    if nrec > 1:
        si[o_rec + 3] = q0
        si[o_rec + 4] = q1
        si[o_rec + 5] = q2
    lookups += 1
    free = ((grid[np.uint64(stop) >> np.uint64(3)] >> (stop & 7)) & 1 != 0 if dense
            else cell_free(mode, grid, lo, dims, table, tmask, gg, blo, bhi, q0, q1, q2))
    if not free:
        return False, lookups, True
    lim = 1.0 - 4.0 * gap
    gi = np.int64(gap * sc)  # the tie margin, the midpoint's margin and the end as keys
    li = np.int64(lim * sc)
    one = np.int64(sc)
    # stepping from both ends (``stop``: the last mirror image), unless the first exit is
    # already past the midpoint (p and q touch: one step)
    mirroring = t0min + t0min < lim
    ncur = 0  # cells the segment runs along besides the chain cell (flat: si[S_CUR:][:ncur])
    pm = np.int64(0)  # the chain cell's facets the segment runs in
    u0 = u1 = u2 = 0  # off a dense grid: the chain cell's offset from p, at a tie
    while True:
        if mirroring:
            if dense:
                code, idx, stop, lookups = mirror_steps(grid, si, idx, mir, lookups, gi, li,
                                                        one, npair)
                if code == BLOCKED:
                    return False, lookups, True
                if code == MET or code == END:  # the walk from p reached the last image
                    break
                if code == TIE_P:  # a tie on the walk from p alone: no images from here
                    mirroring = False
            else:
                code = MET
                m = first_exit(si, nfw, isc)
                while m + m < lim:
                    code, idx, lookups, _ = steps(grid, si, idx, lookups, gi, one, False, stop,
                                                  npair)
                    if code != STEPPED:  # a tie
                        break
                    code = MET
                    mn = first_exit(si, nfw, isc)
                    for half in range(2):  # the cell stepped into, then its mirror image
                        if half == 1:
                            if mn + m >= lim:
                                break  # its mirror would meet the walk from p: not yet
                            lookups += 1
                            stop = mir - idx
                        c = idx if half == 0 else stop
                        c2 = c % d2 + b2
                        c1 = (c // d2) % d1 + b1
                        c0 = c // s0 + b0
                        if lookups <= nrec:
                            si[o_rec + 3 * lookups - 3] = c0
                            si[o_rec + 3 * lookups - 2] = c1
                            si[o_rec + 3 * lookups - 1] = c2
                        if not cell_free(mode, grid, lo, dims, table, tmask, gg, blo, bhi,
                                         c0, c1, c2):
                            return False, lookups, True
                    if stop != mir - idx:
                        break
                    m = mn
            if code != TIE and code != TIE_P:  # met: from here on from p only
                mirroring = False
                if idx == stop:
                    break
                continue
            mk = first_key(si, nfw)
            m = np.float64(mk) * isc
        elif pm == 0:
            code, idx, lookups, mk = steps(grid, si, idx, lookups, gi, one, dense, stop, npair)
            mk &= LOW
            m = np.float64(mk) * isc
            if code == END or code == MET:
                break
            if code == BLOCKED:
                return False, lookups, True
            if code == STEPPED:  # the cell stepped into, looked up here (not dense)
                c2 = idx % d2 + b2
                c1 = (idx // d2) % d1 + b1
                c0 = idx // s0 + b0
                if lookups <= nrec:
                    si[o_rec + 3 * lookups - 3] = c0
                    si[o_rec + 3 * lookups - 2] = c1
                    si[o_rec + 3 * lookups - 1] = c2
                if not cell_free(mode, grid, lo, dims, table, tmask, gg, blo, bhi, c0, c1, c2):
                    return False, lookups, True
                continue
        else:
            mk = first_key(si, nfw)
            m = np.float64(mk) * isc
            if m >= 1.0:
                break
        # An edge or a vertex, or a facet the segment runs in: the face table. Its cells
        # by flat index (the chain cell's plus their offset's): on a dense grid a lookup
        # is a bit test and no cell's indices are needed (no division); else from the
        # chain cell's offset from p.
        if lookups > nsafe:
            return True, lookups, False
        if not dense:
            u2 = idx % d2 + b2 - p2
            u1 = (idx // d2) % d1 + b1 - p1
            u0 = idx // s0 + b0 - p0
        # The facets through the exit point: each forward one whose key is within its slack
        # of the exit's (no branch per facet: which are is not predictable; all eight slots,
        # the padding's bits 0: a loop of nfw slots cost a mispredicted exit per tie).
        am = pm
        for k in range(SLOTS):
            u = np.uint64(k)
            am |= si[np.uint64(S_BIT) + u] & (((si[np.uint64(S_KEY) + u] & LOW) - mk
                                                - si[np.uint64(S_ON) + u] - 1) >> 63)
        f = fi[fi[I_FMASK] + am]
        if f < 0:
            return True, lookups, False
        nxt = -1  # the next chain cell: the one entered, else one the segment runs along
        inner = False
        ns = fi[fi[I_STARN] + f]
        # The star's first cell is the chain cell (facetable), which the segment leaves
        # here (the exit's facet is forward): never the next one.
        for j in range(1, ns):
            a = o_cells + 3 * (sm * f + j)
            f0, f1, f2 = fi[a], fi[a + 1], fi[a + 2]
            c = idx + f0 * s0 + f1 * s1 + f2
            seen = c == stop  # the far end's cell: looked up by its walk
            for i in range(ncur):
                if si[S_CUR + i] == c:
                    seen = True
                    break
            if not seen:
                lookups += 1
                if dense:
                    if (grid[np.uint64(c) >> np.uint64(3)] >> (c & 7)) & 1 == 0:
                        return False, lookups, True
                else:
                    c0, c1, c2 = p0 + u0 + f0, p1 + u1 + f1, p2 + u2 + f2
                    if lookups <= nrec:
                        si[o_rec + 3 * lookups - 3] = c0
                        si[o_rec + 3 * lookups - 2] = c1
                        si[o_rec + 3 * lookups - 1] = c2
                    if not cell_free(mode, grid, lo, dims, table, tmask, gg, blo, bhi,
                                     c0, c1, c2):
                        return False, lookups, True
            bm = fi[o_masks + sm * f + j]
            if bm & fwm:
                continue  # the segment leaves it here
            if bm & parm == 0:
                nxt = j  # enters its interior: no other cell goes on
                inner = True
            elif not inner:
                nxt = j
        if nxt < 0:
            return True, lookups, False
        # The cells it runs along from here (their lookups done): the dedup list.
        ncur = 0
        if not inner:
            for j in range(1, ns):
                bm = fi[o_masks + sm * f + j]
                if bm & fwm == 0 and bm & parm != 0:
                    a = o_cells + 3 * (sm * f + j)
                    si[S_CUR + ncur] = idx + fi[a] * s0 + fi[a + 1] * s1 + fi[a + 2]
                    ncur += 1
        pm = fi[o_masks + sm * f + nxt] & parm
        a = o_cells + 3 * (sm * f + nxt)
        g0, g1, g2 = fi[a], fi[a + 1], fi[a + 2]
        old = idx
        idx += g0 * s0 + g1 * s1 + g2
        if idx == stop:
            break
        # The exit times from the next chain cell: moved by the offset (c_u . v), as the
        # fast steps move them (a change rounded the same way).
        # (A parallel or padding slot's 1 / |d . v| is 0: its key stays. All eight slots.)
        for k in range(SLOTS):
            u = np.uint64(k)
            w = np.uint64(F_REL + 3 * si[np.uint64(S_FW) + u])
            si[np.uint64(S_KEY) + u] += np.int64(
                (fd[w] * g0 + fd[w + np.uint64(1)] * g1 + fd[w + np.uint64(2)] * g2)
                * sf[np.uint64(S_IDQ) + u] * sc) & LOW
        if mirroring:
            # The tie's mirror image: its cells' images, when the next chain cell's exit
            # keeps the two walks apart (the segment in its interior: no facet run along).
            mn = first_exit(si, nfw, isc)
            if not inner or mn + m >= lim:
                mirroring = False
                continue
            for j in range(1, ns):
                a = o_cells + 3 * (sm * f + j)
                f0, f1, f2 = fi[a], fi[a + 1], fi[a + 2]
                lookups += 1
                if dense:
                    c = mir - old - f0 * s0 - f1 * s1 - f2
                    if (grid[np.uint64(c) >> np.uint64(3)] >> (c & 7)) & 1 == 0:
                        return False, lookups, True
                else:
                    c0, c1, c2 = q0 - u0 - f0, q1 - u1 - f1, q2 - u2 - f2
                    if lookups <= nrec:
                        si[o_rec + 3 * lookups - 3] = c0
                        si[o_rec + 3 * lookups - 2] = c1
                        si[o_rec + 3 * lookups - 1] = c2
                    if not cell_free(mode, grid, lo, dims, table, tmask, gg, blo, bhi,
                                     c0, c1, c2):
                        return False, lookups, True
            stop = mir - idx
    return True, lookups, True
