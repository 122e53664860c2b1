"""The planning world: a lattice, its blocked cells and a bounding box, and its one validity
checker.

Occupancy storage (chosen per world, see :attr:`World.storage`):

* ``"dense"`` (default when it fits ``dense_budget`` bytes, 256 MB, i.e. boxes up to
  ~2e9 cells): one bit per cell over the index bounding box of the in-bounds cells
  (:mod:`planner.occupancy.bits`), 1 = free. This is the world's own record of its cells
  (no list of blocked cells is kept); a lookup is one bounds test and one bit load, and it
  answers "in bounds" and "not blocked" at once. A 389 x 313 x 511 Warframe map takes
  7.8 MB. Cells meeting unknown space are a second bit set over the same box.
* ``"hash"`` (fallback for huge boxes): the in-bounds blocked cells as given, (M, 3) int64,
  an open-addressing set of their packed keys (power-of-two size, load <= 0.5, splitmix64
  mixing) plus an in-bounds test of the cell centre. Memory proportional to the number of
  blocked cells.

:attr:`World.blocked`, :attr:`World.unknown` and :meth:`World.blocked_centres` are views
made on each call from the compact sets (24 bytes a cell, and a pass over the box's bits):
for exports and figures, not for inner loops. :attr:`World.n_blocked` counts without a list.

Both live in a typed :class:`Occupancy` struct of plain numpy arrays read by the numba
kernels (:mod:`planner.occupancy.grid`). :attr:`World.checker` (a :class:`ValidityChecker`)
owns it with the segment-walk data: lattice search, shortcutting and the OMPL baseline all
check states and motions through it. It is built lazily and dropped when pickling (OMPL
ships the checker itself to its worker process).
"""

from __future__ import annotations

import math

import numpy as np

from planner.checks import check_radius
from planner.errors import MapError, PlanError
from planner.io.obstacles import UNKNOWN_POLICIES
from planner.lattice import Lattice
from planner.lattice.planar import planar_prism
from planner.occupancy import bits as ob
from planner.occupancy.bits import BoxBits
from planner.occupancy.grid import Occupancy
from planner.occupancy.keys import build_key_set, pack
from planner.occupancy.walk import Walk, as_cells, c_array, segment_walk, walk_of
from planner.voxels import OccupiedVoxelList
from planner.world.cells import CellSets
from planner.world.checker import ValidityChecker
from planner.world.frame import LocalFrame
from planner.world.points import as_point, fmt, xyz
from planner.world.unknown import SortedKeys, UnknownSpace

__all__ = ["World", "DENSE_BUDGET", "Occupancy", "ValidityChecker", "Walk", "as_point"]

DENSE_BUDGET = 256 * 2**20  # bytes of free bits: above this the hash set is used
_BOUNDS_TOL = 1e-9



class World(CellSets, UnknownSpace, LocalFrame):
    """Lattice + blocked cells + bounds, built complete.

    Parameters
    ----------
    lattice : Lattice
        A 3D lattice.
    blocked_indices : array_like of int, shape (M, 3)
        Blocked cells (already inflated for the robot radius). Duplicates are fine; cells
        out of bounds are never free anyway (a dense world does not keep them).
    bounds : array_like, shape (2, 3)
        World box ``[min, max]`` in metres. A cell is in bounds iff its centre lies in the
        closed box (with ``1e-9`` relative tolerance).
    source : str, optional
        Where the obstacles came from (a path or ``"<array>"``), for reports.
    radius : float
        Robot radius (m) the blocked cells were inflated for (0: not inflated).
    obstacles : planner.io.Obstacles, optional
        The obstacles the cells were built from (for clearance measurements).
    build_seconds : float, optional
        Time it took to build the world from its source (s).
    dense_budget : int
        Largest dense occupancy bit set in bytes (8 cells a byte); beyond it the hash set
        is used.
    unknown_cells : array_like of int, shape (U, 3), optional
        Cells whose closed Voronoi cell meets unknown space (see :meth:`is_unknown`).
    unknown_policy : str
        ``"blocked"`` (the unknown cells and every cell within ``radius`` of them are among
        ``blocked_indices``) or ``"free"`` (paths may cross unknown cells; results count
        them).
    dim : int
        2 for a 2D map planned in the plane z = 0 (see :func:`planner.build_world`).
    offset : array_like, shape (3,) or (2,), optional
        The local frame's origin in the map's (m; :mod:`planner.world.frame`, set for maps
        far from their origin). Bounds, cells, obstacles and :attr:`checker` are local;
        :meth:`endpoint` takes map points and :func:`planner.plan` returns them.

    Attributes
    ----------
    cell_checks : int
        Running count of occupancy lookups made through this world (including by searches).

    Examples
    --------
    >>> from planner.lattice import Lattice
    >>> w = World(Lattice.named("cubic", 1.0), [[2, 2, 2]], [[0, 0, 0], [4, 4, 4]])
    >>> w.checker.is_valid((2.1, 1.9, 2.2)), w.checker.is_valid((0.5, 3.0, 1.0))
    (False, True)
    >>> w.checker.check_motion((0, 0, 0), (4, 4, 4)), w.checker.check_motion((0, 0, 0), (4, 0, 0))
    (False, True)
    """

    def __init__(
        self,
        lattice: Lattice,
        blocked_indices: np.ndarray,
        bounds: np.ndarray,
        *,
        source: str | None = None,
        radius: float = 0.0,
        obstacles=None,
        build_seconds: float | None = None,
        dense_budget: int = DENSE_BUDGET,
        unknown_cells: np.ndarray | None = None,
        unknown_policy: str = "free",
        dim: int = 3,
        offset=None,
    ):
        if not isinstance(lattice, Lattice):
            raise MapError(f"lattice must be a Lattice, got {type(lattice).__name__}")
        b = np.asarray(blocked_indices)
        if lattice.dim == 2:  # a 2D world: the plane z = 0 of the lattice's prism
            lattice, dim = planar_prism(lattice), 2
            b = b.reshape(-1, 2) if b.size == 0 else b
            if b.ndim == 2 and b.shape[1] == 2:
                b = np.concatenate([b, np.zeros((len(b), 1), dtype=b.dtype)], axis=1)
            bounds = np.asarray(bounds, dtype=float)
            if bounds.shape == (2, 2):
                bounds = np.concatenate([bounds, np.zeros((2, 1))], axis=1)
        if lattice.dim != 3:
            raise MapError(f"World supports 2D and 3D lattices, got dimension {lattice.dim}")
        if b.size == 0:
            b = np.zeros((0, 3), dtype=np.int64)
        if b.ndim != 2 or b.shape[1] != 3 or not np.issubdtype(b.dtype, np.integer):
            raise MapError(f"blocked indices must be an (M, 3) integer array, got {b.shape}")
        bb = np.asarray(bounds, dtype=float)
        if bb.shape != (2, 3) or not np.isfinite(bb).all() or np.any(bb[1] < bb[0]):
            raise MapError(f"bounds must be [[xmin, ymin, zmin], [xmax, ymax, zmax]], got "
                           f"{bb.tolist() if bb.ndim else bb}")
        reach = float(lattice._reach)
        if np.abs(bb).max() > reach:  # else every cell test beyond it would say "blocked"
            raise MapError(f"bounds reach {np.abs(bb).max():.3g} m, beyond the +-{reach:.3g} m "
                           f"where lattice indices stay exact (+-2**52); give smaller bounds")
        r = check_radius(radius)
        self._lattice = lattice
        self._bounds = bb
        self.source = source
        self.radius = r
        self.obstacles = obstacles
        self.build_seconds = build_seconds
        self.dense_budget = int(dense_budget)
        self.cell_checks = 0
        self._checker: ValidityChecker | None = None
        if unknown_policy not in UNKNOWN_POLICIES:
            raise MapError(f"unknown_policy must be one of {', '.join(UNKNOWN_POLICIES)}, got "
                           f"{unknown_policy!r}")
        u = np.zeros((0, 3), dtype=np.int64) if unknown_cells is None else np.asarray(
            unknown_cells)
        if u.size == 0:
            u = np.zeros((0, 3), dtype=np.int64)
        if u.ndim != 2 or u.shape[1] != 3 or not np.issubdtype(u.dtype, np.integer):
            raise MapError(f"unknown cells must be an (U, 3) integer array, got {u.shape}")
        b = np.ascontiguousarray(b, dtype=np.int64)
        u = np.ascontiguousarray(u, dtype=np.int64)
        lo, dims = self._box()
        self._free: BoxBits | None = None
        self._blocked: np.ndarray | None = None
        if ob.n_bytes(dims) <= self.dense_budget:
            self._free = self.in_bounds_bits(lo, dims)
            self._unknown = BoxBits.empty(lo, dims)
        else:
            self._blocked = np.zeros((0, 3), np.int64)
            self._unknown = SortedKeys(np.zeros(0, np.int64))
        self.block_cells(b)
        self.add_unknown(u)
        self.unknown_policy = unknown_policy
        self.dim = int(dim)  # 2: a 2D map planned in the plane z = 0 of a prism lattice
        self.source_sha256 = ""
        self.set_offset(offset)

    # -- pickling: plain arrays only; lookup structures rebuilt on first use -----------
    def __getstate__(self) -> dict:
        state = self.__dict__.copy()
        state["_checker"] = None
        return state

    def __setstate__(self, state: dict) -> None:
        self.__dict__.update(state)

    # -- properties ------------------------------------------------------------------
    @property
    def lattice(self) -> Lattice:
        return self._lattice

    @property
    def bounds(self) -> np.ndarray:
        """(2, 3) world box [min, max] (m)."""
        return self._bounds.copy()

    @property
    def cell_size(self) -> float:
        """Twice the packing radius: the distance between face-neighbour centres (m)."""
        return 2.0 * self._lattice.packing_radius

    def blocked_centres(self) -> np.ndarray:
        """(M, 3) centres of the :attr:`blocked` cells (m)."""
        return self._lattice.to_world(self.blocked)

    def blocked_voxels(self):
        """The :attr:`blocked` cells as an :class:`planner.voxels.OccupiedVoxelList`."""
        return OccupiedVoxelList(self._lattice, self.blocked)

    def _tol_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        lo, hi = self._bounds
        tol = _BOUNDS_TOL * max(float(np.abs(self._bounds).max()), self.cell_size)
        return lo - tol, hi + tol

    @property
    def checker(self) -> ValidityChecker:
        """The world's :class:`ValidityChecker` (built on first use)."""
        if self._checker is None:
            self._checker = ValidityChecker(self._build(), walk_of(self._lattice), self._lattice)
        return self._checker

    @property
    def occupancy(self) -> Occupancy:
        """The numba :class:`Occupancy` struct (module docstring); built lazily."""
        return self.checker.occupancy

    def _build(self) -> Occupancy:
        g = c_array(self._lattice.generator, float)
        blo, bhi = (c_array(x, float) for x in self._tol_bounds())
        if self._free is not None:
            f = self._free
            return Occupancy(mode=0, grid=f.bits, lo=f.lo, dims=f.dims,
                             table=np.full(1, -1, np.int64), tmask=0, gmat=g, blo=blo, bhi=bhi)
        keys = np.unique(pack(self._blocked))
        size = 16
        while size < 2 * len(keys):
            size *= 2
        table = build_key_set(keys, size)
        return Occupancy(mode=1, grid=np.zeros(1, np.uint8), lo=np.zeros(3, np.int64),
                         dims=np.zeros(3, np.int64), table=table, tmask=size - 1, gmat=g,
                         blo=blo, bhi=bhi)

    # -- queries ----------------------------------------------------------------------
    def in_bounds(self, indices: np.ndarray) -> np.ndarray:
        """(N,) bool: cell centre inside the bounds box (no lookup counted)."""
        w = as_cells(indices)
        c = self._lattice.to_world(w)
        blo, bhi = self._tol_bounds()
        return np.all((c >= blo) & (c <= bhi), axis=1)

    def is_free(self, indices: np.ndarray) -> np.ndarray:
        """(N,) bool: cell in bounds and not blocked. Adds N to :attr:`cell_checks`.

        Parameters
        ----------
        indices : array_like of int, shape (N, 3) or (3,)
        """
        w = as_cells(indices)
        out = self.checker.cells_free(w)
        self.cell_checks += len(w)
        return out

    def points_free(self, points: np.ndarray) -> np.ndarray:
        """(N,) bool: the cell containing each point (m, (N, 3), local frame) is free."""
        return self.is_free(self._lattice.quantize(points))

    def _walk(self, a, b, check: bool):
        a = np.asarray(a, dtype=float).reshape(3)
        b = np.asarray(b, dtype=float).reshape(3)
        if not (np.isfinite(a).all() and np.isfinite(b).all()):
            raise PlanError("segment end points must be finite")
        s = self._lattice.quantize(a[None])[0]
        chk = self.checker
        return segment_walk(chk.occupancy, chk.walk, a, b, s, check)

    def segment_cells(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """Cells whose closed Voronoi cell the segment a-b (points, m) touches.

        Returns
        -------
        ndarray, shape (K, 3), int64
            In walk order (breadth-first from the cell containing ``a``).
        """
        cells, _, _ = self._walk(a, b, False)
        return cells

    def segment_free(self, a: np.ndarray, b: np.ndarray) -> bool:
        """True iff every cell the segment a-b touches (see :meth:`segment_cells`) is free.
        Stops at the first blocked cell; adds the lookups made to :attr:`cell_checks`."""
        if self._lattice.dim == 3:  # one compiled call: the generic walk's rule and lookups
            x, y = xyz(a), xyz(b)
            if x is not None and y is not None and math.isfinite(sum(x) + sum(y)):
                free, n = self.checker.segment(*x, *y)
                self.cell_checks += n
                return free
        _, free, n = self._walk(a, b, True)
        self.cell_checks += int(n)
        return bool(free)

    def endpoint(self, p, what: str = "point") -> tuple[np.ndarray, np.ndarray]:
        """Check a start or goal point (m, map frame): returns the point (3,) in the local
        frame and its cell (3,) int64. A 2D world takes (x, y) or (x, y, 0).

        Raises PlanError saying which end is wrong and why: malformed, outside the bounds,
        inside an obstacle after inflation (with the nearest free cell centre), or blocked
        by unknown space.
        """
        given = as_point(p, what, self.dim)
        a = self.to_local(given)
        lo, hi = self._bounds
        x, bl, bh = a.tolist(), lo.tolist(), hi.tolist()  # floats: a plan checks two ends
        for i in range(3):
            if x[i] < bl[i] - _BOUNDS_TOL or x[i] > bh[i] + _BOUNDS_TOL:
                raise PlanError(f"{what} {fmt(given)} is outside the map bounds "
                                f"{fmt(self.to_map(lo))} .. {fmt(self.to_map(hi))}")
        hit = self.checker.locate(x[0], x[1], x[2])  # quantize and look up: one call
        if hit is None:  # no named rounding kernel
            cell = self._lattice.quantize(a[None])[0]
            self.cell_checks += 1
            i, j, k = cell.tolist()
            free = self.checker.cell_free(i, j, k)
        else:
            cell, free = hit
            self.cell_checks += 1
        if not free:  # the message only when needed
            self._not_free(cell, f"{what} {fmt(given)}")
        return a, cell

    def end_coords(self, start, goal) -> tuple[float, ...] | None:
        """``(x0, x1, x2, y0, y1, y2)``: a start and a goal point as Python floats (m) when
        both are (3,) float64 arrays or tuples or lists of three reals that pass
        :meth:`endpoint`'s bounds test (a plan's usual case), else None (other input, NaN,
        infinities, a point outside, a world in a local frame)."""
        if self.local_frame:
            return None
        s, g = xyz(start), xyz(goal)
        if s is None or g is None:
            return None
        x0, x1, x2 = s
        y0, y1, y2 = g
        (l0, l1, l2), (h0, h1, h2) = self._bounds.tolist()
        t = _BOUNDS_TOL  # endpoint's test, inverted: NaN and infinities fail it
        if (l0 - t <= x0 <= h0 + t and l1 - t <= x1 <= h1 + t and l2 - t <= x2 <= h2 + t
                and l0 - t <= y0 <= h0 + t and l1 - t <= y1 <= h1 + t and l2 - t <= y2 <= h2 + t):
            return x0, x1, x2, y0, y1, y2
        return None

    def endpoints(self, start, goal) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """:meth:`endpoint` of a start and a goal point (m): ``(start, its cell, goal, its
        cell)``, the same values, lookups and errors (the start's first). When both are
        (3,) float64 arrays (a plan's usual case) both cells are looked up in one compiled
        call; the cells are then the rows of one (2, 3) int64 array."""
        pts = self.end_coords(start, goal)
        if pts is not None:
            hit = self.checker.locate_two(*pts)
            if hit is not None and hit[1] == 3:  # both free
                self.cell_checks += 2
                cells = hit[0]
                return np.array(pts[:3]), cells[0], np.array(pts[3:]), cells[1]
        s, s_cell = self.endpoint(start, "start")  # anything else, and the errors
        g, g_cell = self.endpoint(goal, "goal")
        return s, s_cell, g, g_cell

    def endpoint_cell(self, cell, what: str = "cell") -> np.ndarray:
        """:meth:`endpoint` for a lattice cell ((3,) int): returns it as (3,) int64, or
        raises the same PlanError (naming the cell and its centre)."""
        c = as_cells(cell)
        if len(c) != 1:
            raise PlanError(f"{what} must be one cell (i, j, k), got shape {c.shape}")
        c = c[0]
        if not self.is_free(c[None])[0]:  # the message only when needed: searches are short
            centre = self.to_map(self._lattice.to_world(c[None])[0])
            self._not_free(c, f"{what} cell {c.tolist()} (centre {fmt(centre)})")
        return c

    def _not_free(self, cell: np.ndarray, label: str) -> None:
        """The one endpoint message: which end, where, why, and the nearest free cell."""
        if not self.in_bounds(cell[None])[0]:
            where = "outside the map bounds"
        elif self._near_unknown(cell):
            where = ("blocked by unknown space (not observed free within the robot radius; "
                     "--unknown free plans through it)")
        else:
            where = "inside an obstacle (after inflation for the robot radius)"
        near = self.nearest_free(cell)
        hint = "; no free cell nearby" if near is None else (
            f"; nearest free cell centre: {fmt(self.to_map(self._lattice.to_world(near[None])))}")
        raise PlanError(f"{label} is {where}{hint}")

    def nearest_free(self, cell: np.ndarray, max_radius: float | None = None) -> np.ndarray | None:
        """Nearest free cell to ``cell`` by centre distance, searching outward in growing
        shells up to ``max_radius`` metres (default 64 cell sizes). None if there is none.
        Lookups are not counted (this is for error messages)."""
        c = as_cells(cell)[0]
        g = self._lattice.generator
        limit = max_radius if max_radius is not None else 64 * self.cell_size
        r = 2 * self.cell_size
        rows = np.linalg.norm(np.linalg.inv(g), axis=1)
        before = self.cell_checks
        try:
            while True:
                k = np.ceil(min(r, limit) * rows).astype(np.int64)
                axes = [np.arange(-x, x + 1) for x in k]
                offs = np.stack(np.meshgrid(*axes, indexing="ij"), -1).reshape(-1, 3)
                d = np.linalg.norm(offs @ g.T, axis=1)
                keep = d <= min(r, limit)
                offs, d = offs[keep], d[keep]
                order = np.argsort(d, kind="stable")
                cand = c + offs[order]
                free = self.is_free(cand)
                if free.any():
                    return cand[int(np.argmax(free))]
                if r >= limit or len(cand) > 4_000_000:
                    return None
                r *= 2
        finally:
            self.cell_checks = before

    def __repr__(self) -> str:
        return (f"World({self._lattice!r}, {self.n_blocked} blocked cells, "
                f"bounds={self._bounds.tolist()})")
