"""The one validity checker of a world: point and motion tests that search, shortcutting and
OMPL all use (numba kernels over the world's :class:`~planner.occupancy.grid.Occupancy`)."""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np

from planner._entry import entry_point
from planner.lattice import Lattice
from planner.lattice.quantize import Quantizer
from planner.occupancy import grid as wk
from planner.occupancy.grid import Occupancy
from planner.occupancy.walk import Walk, motion_free
from planner.world.join import join_path, new_joiner

__all__ = ["ValidityChecker"]


class ValidityChecker:
    """State and motion validity on one world: the single checker every planner uses.

    A state (point, m) is valid iff the lattice cell containing it is in bounds and free
    (one occupancy lookup). A motion a -> b is valid iff every cell whose *closed* Voronoi
    cell the segment touches is free (the exact segment walk; no resolution involved).
    Lattice searches use the same structs directly inside their kernels
    (:attr:`occupancy`, :attr:`walk`).

    Parameters
    ----------
    occupancy : Occupancy
    walk : Walk
    lattice : Lattice
        For the point quantizer tables (derived on the first :meth:`is_valid`).

    Attributes
    ----------
    checks : int
        Occupancy lookups made through :meth:`is_valid` / :meth:`check_motion`.
    states, motions : int
        Number of state and motion queries.
    """

    def __init__(self, occupancy: Occupancy, walk: Walk, lattice: Lattice):
        self.occupancy = occupancy
        self.walk = walk
        self._lattice = lattice
        self._quant: Quantizer | None = None
        self._buf = np.zeros((2, 3))
        self._out = np.zeros((1, 3), dtype=np.int64)
        self.checks = 0
        self.states = 0
        self.motions = 0
        self._free_one = None  # compiled entry point of grid.free_one (see cell_free)
        self._rounding = None  # Lattice.point_rounding(), or () when there is none (locate)
        self._point_cell = None  # compiled entry point of grid.point_cell (see locate)
        self._point_cells = None  # and of grid.point_cells (see locate_two)
        self._segment = None  # and of walk.motion_free (see segment)
        self._join = None  # (Joiner, compiled entry point of join.join_path): see join
        self._kernels: dict = {}  # kernel -> its compiled entry point (see compiled)

    @property
    def quantizer(self) -> Quantizer:
        """The compiled point quantizer's tables (derived once; shipped when pickled)."""
        if self._quant is None:
            self._quant = self._lattice.quantizer()
        return self._quant

    def __getstate__(self) -> dict:
        self.quantizer  # noqa: B018 - a worker would otherwise redo the lattice geometry
        d = self.__dict__.copy()
        # entry points do not pickle
        d["_free_one"] = d["_point_cell"] = d["_point_cells"] = d["_segment"] = d["_join"] = None
        d["_kernels"] = {}
        return d

    def compiled(self, kernel, args: Sequence) -> Callable:
        """The compiled function of numba kernel ``kernel`` for ``args``, looked up once per
        kernel (:func:`planner._entry.entry_point`): a call skips numba's typing of this
        world's structs, some microseconds. The caller passes arguments of the same types on
        every call (the entry point does not check them)."""
        f = self._kernels.get(kernel)
        if f is None:
            f = self._kernels[kernel] = entry_point(kernel, args)
        return f

    def is_valid(self, point) -> bool:
        """The cell containing ``point`` ((3,), m) is in bounds and free (one lookup)."""
        self.checks += 1
        self.states += 1
        return bool(wk.point_free(self.occupancy, self.quantizer, float(point[0]),
                                  float(point[1]), float(point[2]), self._buf, self._out))

    def check_motion(self, a, b) -> bool:
        """Exact segment walk a -> b ((3,) each, m): every touched cell free. Counts every
        cell looked at (the walk stops at the first blocked one)."""
        free, n = motion_free(self.occupancy, self.walk, self.quantizer, float(a[0]),
                                 float(a[1]), float(a[2]), float(b[0]), float(b[1]),
                                 float(b[2]), self._buf, self._out)
        self.checks += int(n)
        self.motions += 1
        return bool(free)

    def segment(self, a0: float, a1: float, a2: float, b0: float, b1: float,
                b2: float) -> tuple[bool, int]:
        """:meth:`check_motion`'s exact walk of the segment (a0, a1, a2) -> (b0, b1, b2) (m,
        finite Python floats) as ``(every touched cell free, lookups made)``, called without
        numba's typing of the structs (a plan joins its two ends with it). Not counted
        here (the world counts its own lookups)."""
        f = self._segment
        if f is None:
            f = self._segment = entry_point(motion_free, (
                self.occupancy, self.walk, self.quantizer, a0, a1, a2, b0, b1, b2, self._buf,
                self._out))
        free, n = f(self.occupancy, self.walk, self.quantizer, a0, a1, a2, b0, b1, b2,
                    self._buf, self._out)
        return bool(free), int(n)

    def join(self, path: np.ndarray, s0: float, s1: float, s2: float, g0: float, g1: float,
             g2: float) -> tuple[int, int, float]:
        """:func:`planner.world.join.join_path`: the start (s0, s1, s2) and goal (g0, g1, g2)
        (m, Python floats) written to the first and last rows of ``path`` ((K + 2, 3)
        float64, C-contiguous and writable, the K cell centres between) and its ends joined
        in place: ``(rows of the joined path, lookups made, its length in m)``. One
        compiled call, on scratch kept for the next (a plan joins its ends with it); the
        caller makes sure of ``path``'s type (the compiled call does not check it). Not
        counted here (the world counts its own lookups)."""
        jf = self._join
        if jf is None:
            j = new_joiner(self.occupancy, self.walk, self.quantizer)
            jf = self._join = (j, entry_point(join_path, (j, path, s0, s1, s2, g0, g1, g2)))
        return jf[1](jf[0], path, s0, s1, s2, g0, g1, g2)

    def cell_free(self, i: int, j: int, k: int) -> bool:
        """Cell (i, j, k) (Python ints) is in bounds and free: one lookup, called without
        numba's typing of the occupancy struct (a start or goal check on every plan). Not
        counted here (the world counts its own lookups)."""
        f = self._free_one
        if f is None:
            f = self._free_one = entry_point(wk.free_one, (self.occupancy, 0, 0, 0))
        return f(self.occupancy, i, j, k)

    def locate(self, x: float, y: float, z: float) -> tuple[np.ndarray, bool] | None:
        """The cell (3,) int64 that ``Lattice.quantize`` gives point (x, y, z) (m, Python
        floats) and whether it is in bounds and free, in one compiled call (a start or goal
        on every plan). None for a lattice without a named rounding kernel or a point past
        its exact range: then ``quantize`` decides (or raises). Not counted here."""
        r = self._rounding
        if r is None:
            r = self._rounding = self._lattice.point_rounding() or ()
        if not r:
            return None
        kind, a, b, ginv, reach = r
        if not (-reach <= x <= reach and -reach <= y <= reach and -reach <= z <= reach):
            return None
        cell = np.empty(3, np.int64)
        f = self._point_cell
        if f is None:
            f = self._point_cell = entry_point(wk.point_cell, (self.occupancy, kind, a, b, ginv,
                                                               x, y, z, cell))
        return cell, f(self.occupancy, kind, a, b, ginv, x, y, z, cell)

    def rounding(self) -> tuple | None:
        """:meth:`planner.lattice.Lattice.point_rounding` of the lattice, ``(kind, a, b,
        ginv, reach)``, made once; None for a lattice without a named rounding kernel."""
        r = self._rounding
        if r is None:
            r = self._rounding = self._lattice.point_rounding() or ()
        return r or None

    def locate_two(self, x0: float, x1: float, x2: float, y0: float, y1: float,
                   y2: float) -> tuple[np.ndarray, int] | None:
        """:meth:`locate` of two points (m, Python floats; a plan's start and goal) in one
        compiled call: their cells, rows of a (2, 3) int64 array, and whether each is in
        bounds and free as bit 0 (the first point) and bit 1. None when :meth:`locate`
        would say None for either. Not counted here."""
        r = self.rounding()
        if r is None:
            return None
        kind, a, b, ginv, reach = r
        if not (-reach <= x0 <= reach and -reach <= x1 <= reach and -reach <= x2 <= reach
                and -reach <= y0 <= reach and -reach <= y1 <= reach and -reach <= y2 <= reach):
            return None
        cells = np.empty((2, 3), np.int64)
        f = self._point_cells
        if f is None:
            f = self._point_cells = entry_point(wk.point_cells, (
                self.occupancy, kind, a, b, ginv, x0, x1, x2, y0, y1, y2, cells))
        return cells, f(self.occupancy, kind, a, b, ginv, x0, x1, x2, y0, y1, y2, cells)

    def cells_free(self, cells: np.ndarray) -> np.ndarray:
        """(N,) bool: each cell of ``cells`` ((N, 3) int64, C-contiguous) in bounds and free.
        Not counted here (the world counts its own lookups)."""
        out = np.empty(len(cells), dtype=np.bool_)
        wk.free_many(self.occupancy, cells, out)
        return out
