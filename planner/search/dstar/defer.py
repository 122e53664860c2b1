"""D* Lite's deferred changes: blocked cells far from the search wait until a search nears them.

A blocked cell x changes the edges of the nodes whose stencil holds it, all within ``ext``
of x in the gauge (the largest gauge length of a union-stencil offset). Such a node n has
min(g, rhs)(n) >= gauge(n, goal) (the gauge, the heuristic's metric, is a lower bound of
every path cost) and first key min(g, rhs)(n) + gauge(start, n) + km, hence a key of at
least

    LB(x) = gauge(x, goal) + gauge(start, x) - 2 ext + km

with the start and ``km`` of the moment; it stays a lower bound as the robot moves, as the
queued keys do (``km`` grows by the gauge of each move). A repair collects the changed cells
whose bound is within reach of the start's key and leaves the others here (a scan reveals
obstacles all around the robot, most of them far off the corridor of shortest paths):
:func:`planner.search.dstar.kernel.compute_path` returns ``RUN_DEFER`` before it would pop
a key at or above the smallest bound (or stop with the start's key above it), so no node
those cells touch is read while they wait, and the planner collects the cells that are due
and resumes. Only blocked cells wait: a freed cell is repaired after every waiting one,
in order.
"""

from __future__ import annotations

import math

import numpy as np

from planner._entry import entry_point
from planner._numba import njit_cached
from planner.search._grow import grown
from planner.search.heuristic import gauge, gauge_np

__all__ = ["Deferred"]

_MARGIN = 1e-6  # m: float noise of the bounds (keys are rounded to 1e-9 move lengths)
# How far past the start's key a repair collects, in longest moves: the key rises with the
# cost the changes add, and each cell collected late costs another compiled call
_SLACK_MOVES = 8.0


class Deferred:
    """Blocked cells waiting to be repaired, with their key bounds.

    Parameters
    ----------
    ms : MoveSet
        The planner's move set (``hmat``, ``union``, ``cost``).
    goal : ndarray (3,) int64
        The goal cell.
    """

    def __init__(self, ms, goal: np.ndarray):
        self._hmat = ms.hmat
        self._goal = goal
        ext = float(gauge_np(ms.hmat, ms.union).max()) if len(ms.union) else 0.0
        self._ext2 = 2.0 * ext + _MARGIN
        self.slack = _SLACK_MOVES * float(ms.cost.max())  # m
        self._n = 0  # waiting cells: rows [0, n) of the buffers (grown by doubling)
        self._cells = np.empty((1024, 3), np.int64)
        self._bound = np.empty(1024)
        self._least = math.inf
        self._due = np.empty((1024, 3), np.int64)  # split's output
        self._split = None  # _split's entry point

    def __len__(self) -> int:
        return self._n

    @property
    def least(self) -> float:
        """The smallest bound (inf when none waits)."""
        return self._least

    def split(self, cells: np.ndarray, start: np.ndarray, km: float,
              reach: float) -> np.ndarray:
        """Of blocked ``cells`` ((K, 3) int64, C-contiguous), return those whose bound is
        at most ``reach`` and keep the others waiting."""
        k, n = len(cells), self._n
        if len(self._due) < k:
            self._due = np.empty((max(k, 2 * len(self._due)), 3), np.int64)
        if len(self._bound) < n + k:
            cap = max(n + k, 2 * len(self._bound))
            self._cells = grown(self._cells, cap, n)
            self._bound = grown(self._bound, cap, n)
        args = (self._hmat, self._goal, start, km - self._ext2, reach, cells, self._due,
                self._cells[n:], self._bound[n:])
        if self._split is None:
            self._split = entry_point(_split, args)
        nd = self._split(*args)
        if nd == k:
            return cells
        self._n = n + k - nd
        self._least = min(self._least, float(self._bound[n:self._n].min()))
        return self._due[:nd].copy()

    def take(self, reach: float) -> np.ndarray:
        """The waiting cells whose bound is at most ``reach``, removed from the wait."""
        n = self._n
        due = self._bound[:n] <= reach
        out = self._cells[:n][due]
        rest = ~due
        m = int(rest.sum())
        self._cells[:m] = self._cells[:n][rest]
        self._bound[:m] = self._bound[:n][rest]
        self._n = m
        self._least = float(self._bound[:m].min()) if m else math.inf
        return out

    def take_all(self) -> np.ndarray:
        """Every waiting cell, in the order it arrived."""
        out = self._cells[:self._n].copy()
        self._n, self._least = 0, math.inf
        return out


@njit_cached(_nrt=False)
def _split(hmat, goal, start, base, reach, cells, due, far, lb):  # pragma: no cover
    """Cells whose bound (``base`` + gauge to the goal + gauge to the start) is at most
    ``reach`` to ``due``, the others to ``far`` with their bounds in ``lb``; returns the
    number due."""
    nd = 0
    nf = 0
    for i in range(cells.shape[0]):
        c0, c1, c2 = cells[i, 0], cells[i, 1], cells[i, 2]
        b = (base + gauge(hmat, c0 - goal[0], c1 - goal[1], c2 - goal[2])
             + gauge(hmat, c0 - start[0], c1 - start[1], c2 - start[2]))
        if b <= reach:
            due[nd, 0], due[nd, 1], due[nd, 2] = c0, c1, c2
            nd += 1
        else:
            far[nf, 0], far[nf, 1], far[nf, 2] = c0, c1, c2
            lb[nf] = b
            nf += 1
    return nd
