"""The :class:`Lattice`: a generator, exact quantization, Voronoi cells and adjacency.

A lattice is the set of points ``G @ w`` for integer index vectors ``w`` (shape ``(d,)``),
where the generator ``G`` (``d x d``, columns are basis vectors, metres) is non-singular.
Each lattice point owns its Voronoi cell: the points of space closer to it than to any
other lattice point. Quantizing a point means finding the cell that contains it.

Everything here is derived from the generator: Voronoi-relevant vectors (face
neighbours), touching cells (full neighbours), the cell as a polytope
(:class:`VoronoiCell`), covering and packing radii and the normalised second moment.
Nothing is tabulated per lattice except the paper's unit-determinant generators
(:mod:`planner.lattice.paper`) and the choice of a specialised closest-point kernel
(:mod:`planner.lattice.quantize`). The geometry lives in :mod:`planner.lattice._geometry`.
"""

from __future__ import annotations

import importlib
import math
from typing import TYPE_CHECKING

import numpy as np

from planner.errors import LatticeError
from planner.lattice._geometry import (
    TOL,
    VoronoiCell,
    geometry,
    reduce_basis,
    rounding_offsets,
    sorted_offsets,
)
from planner.lattice.paper import NAMED_LATTICES, PAPER_DELTAS, named_generator

if TYPE_CHECKING:
    from planner.lattice.quantize import Quantizer

__all__ = ["Lattice", "NAMED_LATTICES", "PAPER_DELTAS", "Quantizer", "VoronoiCell",
           "named_generator"]


_QK: list = []


def _qk():
    """The quantizer kernels, imported on first use: importing numba is slow, and
    ``import planner`` should not pay for it."""
    if not _QK:
        _QK.append(importlib.import_module("planner.lattice.quantize"))
    return _QK[0]


def __getattr__(name: str):
    if name == "Quantizer":  # public, from the numba kernel module: loaded when asked for
        return _qk().Quantizer
    raise AttributeError(f"module 'planner.lattice' has no attribute {name!r}")


_I8 = np.dtype(np.int64)  # to_world's usual index dtype
_CHUNK = 1 << 20  # points per chunk of the input checks (no full-size temporaries)
# Largest |index| a quantized point may have: float64 holds integers exactly up to 2**53.
_INDEX_LIMIT = 2.0**52
# Cell sizes (m, cube root of the cell volume) whose geometry derives reliably: the linear
# programs of the derivation have absolute tolerances, so far smaller or larger cells lose it.
_SIDE_RANGE = (1e-6, 1e6)
_SHELL_LIMIT = 5_000_000  # lattice vectors neighbors("face+k") may enumerate (24 bytes each)


class Lattice:
    """A lattice in 2 or 3 dimensions, given by its generator matrix.

    Parameters
    ----------
    generator : array_like, shape (d, d)
        Non-singular generator; columns are the basis vectors, in metres. ``d`` is 2 or 3.
    name : str, optional
        Label used in tables and saved maps.

    Examples
    --------
    >>> fcc = Lattice.named("fcc", cell_volume=0.125)
    >>> fcc.neighbors("face").shape
    (12, 3)
    """

    def __init__(self, generator: np.ndarray, name: str | None = None, *, _kind: str = "generic"):
        try:
            g = np.array(generator, dtype=float)
        except (TypeError, ValueError) as exc:
            raise LatticeError(f"generator is not a numeric matrix: {exc}") from None
        if g.ndim != 2 or g.shape[0] != g.shape[1]:
            raise LatticeError(f"generator must be a square matrix, got shape {g.shape}")
        if g.shape[0] not in (2, 3):
            raise LatticeError(f"only 2D and 3D lattices are supported, got dimension {g.shape[0]}")
        if not np.all(np.isfinite(g)):
            raise LatticeError("generator contains NaN or infinite entries")
        det = float(np.linalg.det(g))
        # |det| over the product of column lengths is 1 for orthogonal columns and 0 for
        # singular ones; unlike |det| / max|G|^d it does not flag a unimodular generator
        # with one long column (LLL reduces that to a good basis).
        hadamard = float(np.prod(np.linalg.norm(g, axis=0)))
        if hadamard == 0 or abs(det) <= 1e-12 * hadamard:
            raise LatticeError(f"generator is singular or numerically singular (det = {det:.3g}"
                               f", column lengths {np.linalg.norm(g, axis=0).round(6).tolist()})")
        side = abs(det) ** (1 / g.shape[0])
        if not _SIDE_RANGE[0] <= side <= _SIDE_RANGE[1]:
            raise LatticeError(f"cell volume {abs(det):.3g} m^{g.shape[0]} is outside the "
                               f"supported range: cells {_SIDE_RANGE[0]:g} m to "
                               f"{_SIDE_RANGE[1]:g} m across")
        g.setflags(write=False)
        self._g = g
        self._volume = abs(det)
        # Refuses lattices too ill-conditioned to derive, before any large enumeration.
        b, _ = reduce_basis(g.tobytes(), g.shape[0])
        self._ginv = np.linalg.inv(g)
        # Coordinates beyond _reach give indices past 2**52 (|w_j| <= gain * (|x| + R), R the
        # covering radius, which is at most the reduced basis' half diagonal).
        gain = max(float(np.abs(self._ginv).sum(axis=1).max()),
                   float(np.abs(np.linalg.inv(b)).sum(axis=1).max()))
        self._reach = _INDEX_LIMIT / gain - float(np.linalg.norm(b, axis=0).sum())
        self._quantizer: Quantizer | None = None
        self.name = name
        self._kind = _kind

    # -- construction -------------------------------------------------------------------
    @classmethod
    def named(cls, name: str, cell_volume: float = 1.0) -> Lattice:
        """One of the paper's lattices scaled so that ``|det G| == cell_volume`` (m^3).

        ``name`` is ``cubic``, ``bcc``, ``fcc``, ``mcc`` or ``hex`` (hexagonal prismatic:
        hexagons in the x-y plane, prism axis along z).
        """
        g = named_generator(name)
        try:
            v = float(cell_volume)
        except (TypeError, ValueError):
            raise LatticeError(f"cell_volume must be a number, got {cell_volume!r}") from None
        if not math.isfinite(v) or v <= 0:
            raise LatticeError(f"cell_volume must be positive and finite, got {cell_volume!r}")
        key = name.lower()
        return cls(g * v ** (1 / len(g)), name=key, _kind=key)

    # -- basic properties ---------------------------------------------------------------
    @property
    def generator(self) -> np.ndarray:
        """(d, d) generator, columns are basis vectors (metres). Read-only."""
        return self._g

    @property
    def dim(self) -> int:
        """Dimension d (2 or 3)."""
        return self._g.shape[0]

    @property
    def cell_volume(self) -> float:
        """Volume (area in 2D) of one Voronoi cell, ``|det G|``."""
        return self._volume

    @property
    def _geo(self) -> dict:
        return geometry(self._g.tobytes(), self.dim)

    @property
    def voronoi(self) -> VoronoiCell:
        """The Voronoi cell of the origin as a polytope (facets, vertices, edges, radii).

        Examples
        --------
        >>> cell = Lattice.named("fcc").voronoi  # the rhombic dodecahedron
        >>> len(cell.normals), len(cell.vertices), len(cell.edges[0])
        (12, 14, 24)
        """
        return self._geo["cell"]

    @property
    def covering_radius(self) -> float:
        """Largest distance from a cell centre to any point of its cell (metres)."""
        return self.voronoi.covering_radius

    @property
    def packing_radius(self) -> float:
        """Half the shortest distance between lattice points (metres)."""
        return self.voronoi.packing_radius

    @property
    def voronoi_vertices(self) -> np.ndarray:
        """(n, d) vertices of the Voronoi cell of the origin (metres)."""
        return self.voronoi.vertices.copy()

    @property
    def relevant_vectors(self) -> np.ndarray:
        """(k, d) Voronoi-relevant vectors in world units: the cell is
        ``{x : x . v <= |v|^2 / 2}`` over these ``v``."""
        return self.voronoi.relevant.copy()

    @property
    def normalized_second_moment(self) -> float:
        """Exact dimensionless second moment ``(1/d) E|x - Q(x)|^2 / V^(2/d)`` of the cell."""
        return self.voronoi.second_moment

    def quantizer(self) -> Quantizer:
        """Tables of the exact generic quantizer (what :meth:`quantize_generic` runs), as a
        picklable struct for compiled code elsewhere (e.g. another process)."""
        if self._quantizer is None:
            self._quantizer = _qk().make_quantizer(self._geo)
        return self._quantizer

    def neighbors(self, kind: str = "face") -> np.ndarray:
        """Index offsets of adjacent cells.

        Parameters
        ----------
        kind : str
            ``"face"``: cells sharing a (d-1)-face (Voronoi-relevant vectors, the paper's
            Delta adjacency). ``"full"``: cells whose closed Voronoi cells touch at all.
            ``"face+k"`` / ``"full+k"``: additionally the next ``k`` shells of lattice
            vectors (by distance) beyond the farthest vector of the base set.

        Returns
        -------
        ndarray, shape (k, d), int64
            Sorted by world distance.
        """
        base, plus, extra = str(kind).partition("+")
        if base not in ("face", "full"):
            raise LatticeError(
                f"unknown neighbour kind {kind!r}; expected face, full, face+k or full+k"
            )
        offs = self._geo[base]
        if not plus:
            return offs.copy()
        # digits only: "face+" is no shorthand for face+0, nor is "face+ 1" or "face++1"
        if not (extra.isascii() and extra.isdigit()):
            raise LatticeError(f"bad shell count in neighbour kind {kind!r}: expected "
                               f"{base}+k with k a whole number >= 0")
        shells = int(extra)
        return self._with_shells(offs, shells)

    def _with_shells(self, offs: np.ndarray, shells: int) -> np.ndarray:
        lengths = np.linalg.norm(offs @ self._g.T, axis=1)
        tol = TOL * self.packing_radius
        r = lengths.max()
        # Enough vectors to see `shells` further distinct distances: grow until found.
        radius = r + (shells + 1) * 2 * self.packing_radius
        need = self.voronoi.count_within(radius)
        if need > _SHELL_LIMIT:
            raise LatticeError(f"{shells} extra neighbour shells would enumerate ~{need:.3g} "
                               f"lattice vectors (limit {_SHELL_LIMIT:,}); ask for fewer")
        w = self.voronoi.offsets_within(radius, budget=float("inf"))
        n = np.linalg.norm(w @ self._g.T, axis=1)
        sel = n > r + tol
        dists = np.unique(np.round(n[sel] / tol) * tol)
        if shells and len(dists):
            cut = dists[min(shells, len(dists)) - 1]
            add = w[sel & (n <= cut + tol)]
            offs = np.concatenate([offs, add])
        return sorted_offsets(offs, self._g)

    def rounding_offsets(self, basis: str = "reduced") -> np.ndarray:
        """Minimal off-by-one set for quantizing by rounding then local search (eq. 2).

        Parameters
        ----------
        basis : {"reduced", "given"}
            ``"reduced"``: rounding in the LLL-reduced basis (what :meth:`quantize` uses).
            ``"given"``: rounding in the user's generator, as the paper does.

        Returns
        -------
        ndarray, shape (k, d), int64
            Index offsets (in the user's generator) relative to ``round(G^-1 x)`` (for
            ``"given"``) that are the nearest lattice point for some open set of points.
            The zero offset comes first.
        """
        if basis == "reduced":
            return self._geo["round_offsets"] @ self._geo["reduction"].T
        if basis == "given":
            return rounding_offsets(self._g, self.voronoi.relevant, self.covering_radius)
        raise LatticeError(f"basis must be 'reduced' or 'given', got {basis!r}")

    # -- point <-> index ----------------------------------------------------------------
    def _check_points(self, points: np.ndarray, what: str = "points") -> np.ndarray:
        try:
            x = np.asarray(points, dtype=float)
        except (TypeError, ValueError):
            raise LatticeError(f"{what} must be a numeric (N, {self.dim}) array") from None
        if x.ndim == 1 and x.shape[0] == self.dim:
            x = x[None, :]
        if x.ndim != 2 or x.shape[1] != self.dim:
            raise LatticeError(f"{what} must have shape (N, {self.dim}), got {x.shape}")
        return np.ascontiguousarray(x)

    def quantize(self, points: np.ndarray) -> np.ndarray:
        """Indices of the nearest lattice point (the Voronoi cell containing each point).

        Exact: identical to a brute-force nearest lattice point search (up to ties on cell
        boundaries, which have measure zero).

        Parameters
        ----------
        points : array_like, shape (N, d)
            Coordinates in metres.

        Returns
        -------
        ndarray, shape (N, d), int64
            Lattice indices ``w`` with ``G @ w`` the nearest lattice point.

        Raises
        ------
        LatticeError
            Bad shape, NaN or infinite coordinates, or points so far from the origin that
            their indices would pass 2**52 (no longer exact in float64).
        """
        x = self._check_points(points)
        out = np.empty(x.shape, dtype=np.int64)
        if not len(x):
            return out
        self._check_range(x)
        qk = _qk()
        if not qk.run_named(self._kind, self._g, self._ginv, x, out):
            qk.run_generic(self.quantizer(), x, out)
        return out

    def point_rounding(self) -> tuple | None:
        """How :meth:`quantize` rounds a point with a named lattice's own kernel, as the
        arguments of :func:`planner.occupancy.grid.point_cell`: ``(kind, a, b, ginv,
        reach)`` (``reach``: the largest coordinate (m) it takes, see :meth:`quantize`'s
        range check), or None when :meth:`quantize` runs the generic quantizer."""
        named = _qk().named_scalars(self._kind, self._g) if self.dim == 3 else None
        if named is None:
            return None
        kind, a, b = named
        return kind, float(a), float(b), self._ginv, self._reach

    def _check_range(self, x: np.ndarray) -> None:
        """LatticeError for NaN/inf or for points whose indices would not fit exactly.

        min/max per chunk: NaN propagates through both, and no (N, d) temporary is made."""
        reach = self._reach
        if len(x) == 1 and x.shape[1] == 3:  # a start or goal: Python floats, no reductions
            a, b, c = x[0].tolist()
            if -reach <= a <= reach and -reach <= b <= reach and -reach <= c <= reach:
                return  # NaN fails every comparison, an infinity the bound
        for s in range(0, len(x), _CHUNK):
            blk = x[s: s + _CHUNK]
            lo, hi = float(blk.min()), float(blk.max())
            if not (math.isfinite(lo) and math.isfinite(hi)):
                bad = s + int(np.flatnonzero(~np.isfinite(blk).all(axis=1))[0])
                raise LatticeError(f"points contain NaN or infinite coordinates (row {bad})")
            if max(-lo, hi) > reach:
                bad = s + int(np.flatnonzero(np.abs(blk).max(axis=1) > reach)[0])
                raise LatticeError(
                    f"point {bad} has a coordinate of {np.abs(blk[bad - s]).max():.3g} m, beyond "
                    f"the +-{reach:.3g} m where lattice indices stay exact (+-2**52)")

    def quantize_generic(self, points: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
        """Generic exact quantizer: round in the reduced basis, then test the minimal
        candidate set from :meth:`rounding_offsets`. Works for any generator; the named
        lattices use specialised kernels (Conway and Sloane) verified against this one."""
        x = self._check_points(points)
        if out is None:
            out = np.empty(x.shape, dtype=np.int64)
        if len(x):
            self._check_range(x)
            _qk().run_generic(self.quantizer(), x, out)
        return out

    def to_world(self, indices: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
        """Cell centres ``G @ w`` in metres.

        Parameters
        ----------
        indices : array_like of int, shape (N, d)
        out : ndarray, shape (N, d), float64, optional
            Written with the centres (the same values) and returned, instead of a new array.

        Returns
        -------
        ndarray, shape (N, d), float64
        """
        w = indices
        if type(w) is np.ndarray and w.dtype == _I8 and w.ndim == 2 and w.shape[1] == self.dim:
            # the usual case (a path's cells), checked at once (the dtype by equality: an
            # array a compiled kernel returns has a dtype object of its own). np.dot: the
            # product ``w @ G.T`` has the same floats (both go to BLAS for 2-D float64) at
            # less dispatch cost; it refuses (ValueError) an ``out`` that is not a
            # C-contiguous float64 array of the product's shape, which matmul takes
            if out is None:
                return np.dot(w, self._g.T)
            try:
                return np.dot(w, self._g.T, out=out)
            except ValueError:
                return np.matmul(w, self._g.T, out=out)
        if out is not None:
            out[...] = self.to_world(indices)
            return out
        w = np.asarray(indices)
        if w.ndim == 1 and w.shape[0] == self.dim:
            w = w[None, :]
        if w.ndim != 2 or w.shape[1] != self.dim:
            raise LatticeError(f"indices must have shape (N, {self.dim}), got {w.shape}")
        if w.dtype != np.int64 and not np.issubdtype(w.dtype, np.integer):
            raise LatticeError(f"indices must be integers, got dtype {w.dtype}")
        return w @ self._g.T

    # -- misc ---------------------------------------------------------------------------
    def scaled(self, cell_volume: float) -> Lattice:
        """The same lattice shape scaled to another cell volume."""
        v = float(cell_volume)
        if not math.isfinite(v) or v <= 0:
            raise LatticeError(f"cell_volume must be positive and finite, got {cell_volume!r}")
        f = (v / self.cell_volume) ** (1 / self.dim)
        return Lattice(self._g * f, name=self.name, _kind=self._kind)

    def __eq__(self, other: object) -> bool:
        return isinstance(other, Lattice) and np.array_equal(self._g, other._g)

    def __hash__(self) -> int:
        return hash(self._g.tobytes())

    def __repr__(self) -> str:
        label = self.name or "custom"
        return f"Lattice({label!r}, dim={self.dim}, cell_volume={self.cell_volume:.6g})"
