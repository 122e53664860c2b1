"""A lattice path's ends joined to its start and goal points, in one compiled call.

:func:`join_path` is :func:`planner.planning.joined` on a world's structs: the two joining
segment checks (the exact walk of :func:`planner.occupancy.walk.motion_free`: the search's
own validity rule, the same cells looked up in the same order), the hops they make
redundant dropped, and points equal to 1 um to the one before them merged, in place in the
caller's array, with the path's length. Its arguments are one :class:`Joiner` (a world's
structs and the walk's scratch, made once per world: a compiled call unboxes each array of
a ``NamedTuple`` argument, about 20 here, for more than a short walk costs) and the path: a
plan pays one call for what took two segment checks and a merge in Python
(``benchmarks/fixed_cost.py``).
"""

from __future__ import annotations

import math

import numpy as np
from numba import types
from numba.experimental import structref

from planner._numba import njit_cached
from planner.lattice import quantize as qk
from planner.occupancy.walk import walk_on, walk_scratch

__all__ = ["Joiner", "join_path", "new_joiner"]


@structref.register
class _JoinerType(types.StructRef):
    def preprocess_fields(self, fields):
        return tuple((n, types.unliteral(t)) for n, t in fields)


class Joiner(structref.StructRefProxy):
    """A world's occupancy, walk and quantizer structs and the segment walk's scratch, as
    one object (made by :func:`new_joiner`; its scratch is reused by every call)."""


structref.define_proxy(Joiner, _JoinerType, ["occ", "walk", "quant", "buf", "out", "vis",
                                             "vgen", "queue", "gen"])


@njit_cached
def new_joiner(occ, walk, quant):  # pragma: no cover - compiled
    """:class:`Joiner` of these structs (shared, not copied), with scratch for walks about
    four cells long (grown by :func:`join_path` when a walk needs more)."""
    vis, vgen, queue = walk_scratch(4.0 * np.sqrt(2.0 * walk.rhs.max()),
                                    np.sqrt(2.0 * walk.rhs.min()), walk.full.shape[0])
    return Joiner(occ, walk, quant, np.zeros((2, 3)), np.zeros((1, 3), np.int64), vis, vgen,
                  queue, np.int64(0))


@njit_cached
def _segment_free(j, path, i, k):  # pragma: no cover - compiled
    """:func:`planner.occupancy.walk.motion_free` of the segment path[i] -> path[k] on the
    scratch of ``j``: ``(every touched cell free, lookups made)``. The walk's result does
    not depend on its scratch (the visited set is exact whatever its size), so a walk that
    outgrows it is walked again on larger scratch, as ``segment_walk`` does."""
    buf, out, quant = j.buf, j.out, j.quant
    for c in range(3):
        buf[0, c] = path[i, c]
        buf[1, c] = path[k, c]
    qk.quantize_generic3(buf[:1], quant.basis, quant.basis_inv, quant.cand, quant.cand_z,
                         quant.counts, quant.reduction, out)
    length = -1.0  # the segment's length, needed only for more scratch
    while True:
        j.gen += 1
        _, free, n, ok = walk_on(j.occ, j.walk, buf[0], buf[1], out[0], True, j.vis, j.vgen,
                                 j.gen, j.queue)
        if ok:
            return free, n
        if length < 0.0:
            d0, d1, d2 = buf[1, 0] - buf[0, 0], buf[1, 1] - buf[0, 1], buf[1, 2] - buf[0, 2]
            length = math.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
        length = 2.0 * length + 1.0
        vis, vgen, queue = walk_scratch(length, np.sqrt(2.0 * j.walk.rhs.min()),
                                        j.walk.full.shape[0])
        if vis.shape[0] > j.vis.shape[0]:
            j.vis, j.vgen, j.gen = vis, vgen, np.int64(0)
        if queue.shape[0] > j.queue.shape[0]:
            j.queue = queue


@njit_cached
def join_path(j, path, s0, s1, s2, g0, g1, g2):  # pragma: no cover - compiled
    """Write the start (s0, s1, s2) and goal (g0, g1, g2) (m) to the first and last rows of
    ``path`` ((K + 2, 3) float64, C-contiguous, the K cell centres between) and join its
    ends as :func:`planner.planning.joined` does, in place, on the structs of ``j``.

    Returns
    -------
    m : int
        Rows of the joined path: ``path[:m]`` (the rows after it are left over).
    lookups : int
        Occupancy lookups the joining checks made.
    length : float
        Length of ``path[:m]`` (m), summed as :func:`planner.path.rows_length` sums it.
    """
    n = path.shape[0]
    path[0, 0], path[0, 1], path[0, 2] = s0, s1, s2
    path[n - 1, 0], path[n - 1, 1], path[n - 1, 2] = g0, g1, g2
    look = 0
    skip1 = skip2 = -1  # rows the joins make redundant
    if n >= 3:
        first, k = _segment_free(j, path, 0, 2)  # start -> the second cell's centre
        look += k
        if n > 3:
            prev = 0 if n == 4 and first else n - 3  # the point before the goal's centre
            last, k = _segment_free(j, path, prev, n - 1)
            look += k
            if last:
                skip2 = n - 2
        if first:
            skip1 = 1
    m = 0
    for i in range(n):
        if i != skip1 and i != skip2:
            if m != i:
                path[m, 0], path[m, 1], path[m, 2] = path[i, 0], path[i, 1], path[i, 2]
            m += 1
    m = _distinct(path, m)
    length = 0.0
    for i in range(1, m):
        d0 = path[i, 0] - path[i - 1, 0]
        d1 = path[i, 1] - path[i - 1, 1]
        d2 = path[i, 2] - path[i - 1, 2]
        length += math.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
    return m, look, length


@njit_cached
def _distinct(path, m):  # pragma: no cover - compiled
    """:func:`planner.planning.distinct` of ``path[:m]``, in place: the new row count. Two
    points are equal when each coordinate's ``rint(v * 1e6)`` is (Python's ``round`` and
    ``np.round`` round half to even alike)."""
    if m < 2:
        return m
    keep = np.ones(m, np.bool_)
    same = False
    for i in range(m - 1):
        if (np.rint(path[i + 1, 0] * 1e6) == np.rint(path[i, 0] * 1e6)
                and np.rint(path[i + 1, 1] * 1e6) == np.rint(path[i, 1] * 1e6)
                and np.rint(path[i + 1, 2] * 1e6) == np.rint(path[i, 2] * 1e6)):
            keep[i + 1] = False
            same = True
    if not same:
        return m
    if not keep[m - 1]:  # the goal replaces the point before it
        keep[m - 1] = True
        keep[m - 2] = m == 2
    r = 0
    for i in range(m):
        if keep[i]:
            if r != i:
                path[r, 0], path[r, 1], path[r, 2] = path[i, 0], path[i, 1], path[i, 2]
            r += 1
    return r
