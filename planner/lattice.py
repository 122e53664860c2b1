"""Lattice geometry: generators, exact quantization, Voronoi cells and adjacency.

A lattice is the set of points ``G @ w`` for integer index vectors ``w`` (shape ``(d,)``),
where the generator ``G`` (``d x d``, columns are basis vectors, metres) is non-singular.
Each lattice point owns its Voronoi cell: the points of space closer to it than to any
other lattice point. Quantizing a point means finding the cell that contains it.

Everything here is derived from the generator: Voronoi-relevant vectors (face
neighbours), touching cells (full neighbours), cell vertices, covering and packing radii
and the normalised second moment. Nothing is tabulated per lattice except the paper's
unit-determinant generators and the choice of a specialised closest-point kernel.
"""

from __future__ import annotations

import itertools
import math
from functools import lru_cache

import numpy as np
from scipy.optimize import linprog

from planner import _quantize_kernels as qk
from planner.errors import LatticeError

__all__ = ["Lattice", "NAMED_LATTICES", "PAPER_DELTAS", "named_generator"]

NAMED_LATTICES = ("cubic", "bcc", "fcc", "mcc", "hex")

# Relative tolerance for geometric ties (distances compared in units of the cell size).
_TOL = 1e-9
_CHUNK = 1 << 16  # points per chunk when a temporary per point is unavoidable


def named_generator(name: str) -> np.ndarray:
    """Unit-determinant generator of a named lattice (paper section II-A, eqs. 8-12).

    The paper prints 4-digit values; these are the exact forms they round:
    BCC ``a = 2**(1/3)``, FCC ``b = 2**(-1/3)``, hex side ``sqrt(2) h`` with
    ``h = 3**(-1/6)``, and MCC the upper Cholesky factor of its Gram matrix
    ``((1+s, -1, 1-s), (-1, 1+s, -1), (1-s, -1, 1+s)) / 2`` with ``s = sqrt(2)``.

    Returns
    -------
    ndarray, shape (3, 3)
        Columns are the basis vectors; ``|det| == 1``.
    """
    key = name.lower() if isinstance(name, str) else name
    if key == "cubic":
        return np.eye(3)
    if key == "bcc":
        a = 2.0 ** (1 / 3)
        return np.array([[a, 0, a / 2], [0, a, a / 2], [0, 0, a / 2]])
    if key == "fcc":
        b = 2.0 ** (-1 / 3)
        return np.array([[2 * b, b, 0], [0, -b, b], [0, 0, -b]])
    if key == "mcc":
        s = math.sqrt(2.0)
        gram = 0.5 * np.array([[1 + s, -1, 1 - s], [-1, 1 + s, -1], [1 - s, -1, 1 + s]])
        return np.linalg.cholesky(gram).T
    if key == "hex":
        h = 3.0 ** (-1 / 6)
        a = math.sqrt(2.0) * h
        return np.array([[a, -a / 2, 0], [0, a * math.sqrt(3) / 2, 0], [0, 0, h]])
    names = ", ".join(NAMED_LATTICES)
    raise LatticeError(f"unknown lattice name {name!r}; expected one of {names}")


# The paper's off-by-one sets, eqs. (3)-(7), as index offsets in the paper's generators.
# Kept to test and report whether they suffice (they do not all: see Lattice.rounding_offsets).
def _pm(cols: list[tuple[int, int, int]]) -> np.ndarray:
    a = np.array(cols, dtype=np.int64)
    return np.concatenate([a, -a])


PAPER_DELTAS: dict[str, np.ndarray] = {
    "cubic": np.array(
        [p for p in itertools.product((-1, 0, 1), repeat=3) if any(p)], dtype=np.int64
    ),
    "fcc": _pm([(1, -2, -1), (0, -1, -1), (1, -1, -1), (0, 0, -1), (0, -1, 0), (1, -1, 0)]),
    "bcc": _pm(
        [(1, 1, -2), (0, 0, -1), (1, 0, -1), (0, 1, -1), (1, 1, -1), (0, -1, 0), (-1, 0, 0)]
    ),
    "mcc": _pm(
        [(-1, -1, -1), (0, -1, -1), (-1, 0, -1), (0, 0, -1), (-1, -1, 0), (0, -1, 0), (-1, 0, 0)]
    ),
    "hex": _pm(
        [(0, -1, -1), (-1, 0, -1), (0, 0, -1), (1, 0, -1), (0, 1, -1), (1, 1, -1), (-1, -1, 0),
         (0, -1, 0)]
    ),
}


def _lll(basis: np.ndarray, delta: float = 0.99) -> tuple[np.ndarray, np.ndarray]:
    """LLL-reduce a column basis. Returns ``(B, T)`` with ``B = basis @ T``, T unimodular."""
    b = basis.astype(float).copy()
    d = b.shape[1]
    t = np.eye(d, dtype=np.int64)

    def gram_schmidt(m: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        star = np.zeros_like(m)
        mu = np.zeros((d, d))
        for i in range(d):
            star[:, i] = m[:, i]
            for j in range(i):
                mu[i, j] = m[:, i] @ star[:, j] / (star[:, j] @ star[:, j])
                star[:, i] -= mu[i, j] * star[:, j]
        return star, mu

    k = 1
    while k < d:
        for j in range(k - 1, -1, -1):
            _, mu = gram_schmidt(b)
            q = round(mu[k, j])
            if q:
                b[:, k] -= q * b[:, j]
                t[:, k] -= q * t[:, j]
        star, mu = gram_schmidt(b)
        lovasz = (delta - mu[k, k - 1] ** 2) * (star[:, k - 1] @ star[:, k - 1])
        if star[:, k] @ star[:, k] >= lovasz:
            k += 1
        else:
            b[:, [k - 1, k]] = b[:, [k, k - 1]]
            t[:, [k - 1, k]] = t[:, [k, k - 1]]
            k = max(k - 1, 1)
    return b, t


def _box_for_radius(basis: np.ndarray, radius: float) -> np.ndarray:
    """Per-axis coefficient bound K with every lattice vector of norm <= radius in [-K, K]^d."""
    rows = np.linalg.norm(np.linalg.inv(basis), axis=1)
    return np.ceil(radius * rows + 1e-9).astype(np.int64)


def _grid(bound: np.ndarray) -> np.ndarray:
    """All integer vectors in the box prod([-bound_i, bound_i]); shape (n, d)."""
    axes = [np.arange(-k, k + 1) for k in bound]
    return np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, len(bound))


@lru_cache(maxsize=64)
def _geometry(gen_bytes: bytes, d: int) -> dict:
    """Geometry of the lattice with this generator (cached; everything derived, nothing tabled)."""
    g = np.frombuffer(gen_bytes, dtype=float).reshape(d, d)
    b, t = _lll(g)
    # Covering radius bound: Babai rounding in the reduced basis errs by at most half the
    # longest diagonal of its parallelepiped, so coset minima lie within twice that.
    signs = np.array(list(itertools.product((-1.0, 1.0), repeat=d)))
    half_diag = 0.5 * np.linalg.norm(signs @ b.T, axis=1).max()
    z = _grid(_box_for_radius(b, 2 * half_diag))
    v = z @ b.T
    n2 = np.einsum("ij,ij->i", v, v)
    scale2 = float(np.abs(np.linalg.det(g))) ** (2 / d)
    face, full = [], []
    # Voronoi's theorem: v is relevant (shares a facet) iff +-v are the only shortest vectors
    # of the coset v + 2L. The cells of 0 and v touch at all iff v/2 lies in the closed
    # Voronoi cell, i.e. v is *a* shortest vector of its coset (ties allowed).
    parity = np.mod(z, 2)
    for c in itertools.product((0, 1), repeat=d):
        if not any(c):
            continue
        in_coset = np.all(parity == np.array(c), axis=1)
        m = n2[in_coset].min()
        shortest = z[in_coset][n2[in_coset] <= m + _TOL * scale2]
        full.append(shortest)
        if len(shortest) == 2:
            face.append(shortest)
    face_z = np.concatenate(face)
    full_z = np.concatenate(full)
    face_w = face_z @ t.T  # reduced coefficients -> indices in the user's generator
    full_w = full_z @ t.T
    rel = face_z @ b.T  # (k, d) relevant vectors, world units

    verts = _voronoi_vertices(rel)
    cover = float(np.linalg.norm(verts, axis=1).max())
    pack = float(np.linalg.norm(rel, axis=1).min() / 2)
    moment = _second_moment(rel, verts)
    offsets = _rounding_offsets(b, rel, cover)
    # Per sign pattern of the rounding residual (bit i set: f_i > 0), padded with the
    # zero offset so that every row has the same length for the compiled kernel.
    per = [_rounding_offsets(b, rel, cover, tuple(1 if (o >> i) & 1 else -1 for i in range(d)))
           for o in range(2**d)]
    width = max(len(p) for p in per)
    by_orthant = np.zeros((2**d, width, d), dtype=np.int64)
    counts = np.array([len(p) for p in per], dtype=np.int64)
    for o, p in enumerate(per):
        by_orthant[o, : len(p)] = p
    return {
        "reduced": b,
        "reduction": t,
        "face": _sorted_offsets(face_w, g),
        "full": _sorted_offsets(full_w, g),
        "relevant": rel,
        "vertices": verts,
        "covering": cover,
        "packing": pack,
        "second_moment": moment,
        "round_offsets": offsets,
        "orthant_offsets": by_orthant,
        "orthant_counts": counts,
    }


def _sorted_offsets(w: np.ndarray, g: np.ndarray) -> np.ndarray:
    """Sort index offsets by world length, then lexicographically (deterministic order)."""
    lengths = np.round(np.linalg.norm(w @ g.T, axis=1), 9)
    order = np.lexsort(tuple(w.T[::-1]) + (lengths,))
    return np.ascontiguousarray(w[order], dtype=np.int64)


def _voronoi_vertices(rel: np.ndarray) -> np.ndarray:
    """Vertices of the Voronoi cell {x : x.v <= |v|^2/2 for every relevant v}; (n, d)."""
    d = rel.shape[1]
    rhs = 0.5 * np.einsum("ij,ij->i", rel, rel)
    tol = _TOL * float(rhs.max())
    found = []
    for idx in itertools.combinations(range(len(rel)), d):
        a = rel[list(idx)]
        if abs(np.linalg.det(a)) < 1e-12 * float(np.abs(a).max()) ** d:
            continue
        x = np.linalg.solve(a, rhs[list(idx)])
        if np.all(rel @ x <= rhs + tol * 10):
            found.append(x)
    pts = np.array(found)
    scale = math.sqrt(float(rhs.max()))
    _, keep = np.unique(np.round(pts / scale, 7), axis=0, return_index=True)
    return pts[np.sort(keep)]


def _second_moment(rel: np.ndarray, verts: np.ndarray) -> float:
    """Exact normalised second moment of the Voronoi cell: (1/d) E|x|^2 / V^(2/d)."""
    d = rel.shape[1]
    rhs = 0.5 * np.einsum("ij,ij->i", rel, rel)
    tol = 1e-7 * float(rhs.max())
    vol = 0.0
    inertia = 0.0
    for v, r in zip(rel, rhs, strict=True):
        on = verts[np.abs(verts @ v - r) < tol]
        if d == 2:
            # An edge of a polygon: triangle (0, a, b).
            a, b = on[0], on[1]
            area = abs(a[0] * b[1] - a[1] * b[0]) / 2
            vol += area
            inertia += area / 12 * (a @ a + b @ b + (a + b) @ (a + b))
            continue
        # A polygonal face: order vertices by angle about its centroid, fan into tetrahedra.
        c = on.mean(axis=0)
        n = v / np.linalg.norm(v)
        e1 = on[0] - c
        e1 /= np.linalg.norm(e1)
        e2 = np.cross(n, e1)
        ang = np.arctan2((on - c) @ e2, (on - c) @ e1)
        ring = on[np.argsort(ang)]
        for i in range(1, len(ring) - 1):
            a, b, cc = ring[0], ring[i], ring[i + 1]
            tv = abs(np.linalg.det(np.stack([a, b, cc]))) / 6
            s = a + b + cc
            vol += tv
            inertia += tv / 20 * (a @ a + b @ b + cc @ cc + s @ s)
    return inertia / vol / d / vol ** (2 / d)


def _rounding_offsets(
    basis: np.ndarray, rel: np.ndarray, cover: float, orthant: tuple[int, ...] | None = None
) -> np.ndarray:
    """Exact candidate set for quantization by rounding in ``basis`` then a local search.

    With ``z0 = round(B^-1 x)`` the residual ``x - B z0`` lies in the parallelepiped
    ``P = B [-1/2, 1/2]^d``, so the nearest lattice point is ``B (z0 + delta)`` for some
    ``delta`` whose Voronoi cell meets the interior of ``P``. Each candidate is decided by a
    small linear programme (largest ball-slack of a common point), so the set is minimal:
    every returned offset is the unique answer for some open set of points.
    With ``orthant`` (a sign per axis) only residuals ``f = B^-1 x - z0`` with those
    signs are considered: the residual's sign pattern then selects a smaller set.

    Returns
    -------
    ndarray, shape (k, d), int64
        Offsets in ``basis`` coefficients, the zero offset first.
    """
    d = basis.shape[0]
    binv = np.linalg.inv(basis)
    signs = np.array(list(itertools.product((-1.0, 1.0), repeat=d)))
    half_diag = 0.5 * np.linalg.norm(signs @ basis.T, axis=1).max()
    cand = _grid(_box_for_radius(basis, half_diag + cover))
    rn = np.linalg.norm(rel, axis=1)
    rows = np.linalg.norm(binv, axis=1)
    rhs_v = 0.5 * rn**2
    keep = []
    for delta in cand:
        c = basis @ delta
        if np.linalg.norm(c) > half_diag + cover + 1e-9:
            continue
        # Variables (x, t): maximise t s.t. x + t-ball inside both V + c and P.
        a_ub = np.vstack(
            [
                np.hstack([rel, rn[:, None]]),
                np.hstack([binv, rows[:, None]]),
                np.hstack([-binv, rows[:, None]]),
            ]
        )
        hi = np.full(d, 0.5)
        lo = np.full(d, 0.5)
        if orthant is not None:  # 0 <= sign_i * f_i: clamp the other half of the box
            o = np.asarray(orthant)
            hi = np.where(o > 0, 0.5, 0.0)
            lo = np.where(o > 0, 0.0, 0.5)
        b_ub = np.concatenate([rhs_v + rel @ c, hi, lo])
        res = linprog(
            np.r_[np.zeros(d), -1.0],
            A_ub=a_ub,
            b_ub=b_ub,
            bounds=[(None, None)] * d + [(None, 1.0)],
            method="highs",
        )
        if res.status == 0 and -res.fun > 1e-9 * cover:
            keep.append(delta)
    out = np.array(keep, dtype=np.int64)
    zero = np.all(out == 0, axis=1)
    return np.concatenate([out[zero], out[~zero]])


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
        scale = float(np.abs(g).max())
        if scale == 0 or abs(det) <= 1e-12 * scale ** g.shape[0]:
            raise LatticeError(f"generator is singular (det = {det:.3g})")
        self._g = g
        self._g.setflags(write=False)
        self._ginv = np.linalg.inv(g)
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
        return cls(g * v ** (1 / 3), name=key, _kind=key)

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
        return float(abs(np.linalg.det(self._g)))

    @property
    def _geo(self) -> dict:
        return _geometry(np.ascontiguousarray(self._g).tobytes(), self.dim)

    @property
    def covering_radius(self) -> float:
        """Largest distance from a cell centre to any point of its cell (metres)."""
        return self._geo["covering"]

    @property
    def packing_radius(self) -> float:
        """Half the shortest distance between lattice points (metres)."""
        return self._geo["packing"]

    @property
    def voronoi_vertices(self) -> np.ndarray:
        """(n, d) vertices of the Voronoi cell of the origin (metres)."""
        return self._geo["vertices"].copy()

    @property
    def relevant_vectors(self) -> np.ndarray:
        """(k, d) Voronoi-relevant vectors in world units: the cell is
        ``{x : x . v <= |v|^2 / 2}`` over these ``v``."""
        return self._geo["relevant"].copy()

    @property
    def normalized_second_moment(self) -> float:
        """Exact dimensionless second moment ``(1/d) E|x - Q(x)|^2 / V^(2/d)`` of the cell."""
        return self._geo["second_moment"]

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
        base, _, extra = str(kind).partition("+")
        if base not in ("face", "full"):
            raise LatticeError(
                f"unknown neighbour kind {kind!r}; expected face, full, face+k or full+k"
            )
        offs = self._geo[base]
        if not extra:
            return offs.copy()
        try:
            shells = int(extra)
        except ValueError:
            raise LatticeError(f"bad shell count in neighbour kind {kind!r}") from None
        if shells < 0:
            raise LatticeError(f"bad shell count in neighbour kind {kind!r}")
        return self._with_shells(offs, shells)

    def _with_shells(self, offs: np.ndarray, shells: int) -> np.ndarray:
        lengths = np.linalg.norm(offs @ self._g.T, axis=1)
        tol = _TOL * self.packing_radius
        r = lengths.max()
        # Enough vectors to see `shells` further distinct distances: grow until found.
        radius = r + (shells + 1) * 2 * self.packing_radius
        b = self._geo["reduced"]
        z = _grid(_box_for_radius(b, radius))
        w = z @ self._geo["reduction"].T
        n = np.linalg.norm(w @ self._g.T, axis=1)
        sel = (n > r + tol) & (n <= radius)
        dists = np.unique(np.round(n[sel] / tol) * tol)
        if shells and len(dists):
            cut = dists[min(shells, len(dists)) - 1]
            add = w[sel & (n <= cut + tol)]
            offs = np.concatenate([offs, add])
        return _sorted_offsets(offs, self._g)

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
            return _rounding_offsets(self._g, self._geo["relevant"], self.covering_radius)
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
        """
        x = self._check_points(points)
        out = np.empty(x.shape, dtype=np.int64)
        if not len(x):
            return out
        # Checked per chunk so that a NaN check never holds a full (N, d) bool temporary.
        for s in range(0, len(x), _CHUNK * 16):
            blk = x[s : s + _CHUNK * 16]
            if not np.isfinite(blk).all():
                bad = s + int(np.flatnonzero(~np.isfinite(blk).all(axis=1))[0])
                raise LatticeError(f"points contain NaN or infinite coordinates (row {bad})")
        self._quantize_into(x, out)
        return out

    def _quantize_into(self, x: np.ndarray, out: np.ndarray) -> None:
        kind = self._kind
        g, ginv = self._g, self._ginv
        if kind == "cubic":
            qk.quantize_cubic(x, 1.0 / g[0, 0], out)
        elif kind == "fcc":
            qk.quantize_fcc(x, -g[2, 2], ginv, out)  # FCC = b * D3, b = -G[2,2]
        elif kind == "bcc":
            qk.quantize_bcc(x, g[0, 0], ginv, out)  # BCC = a * (Z3 u Z3 + 1/2)
        elif kind == "hex":
            qk.quantize_hex(x, g[0, 0], g[2, 2], ginv, out)  # A2 (side a) x Z (height h)
        else:
            self.quantize_generic(x, out=out)

    def quantize_generic(self, points: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
        """Generic exact quantizer: round in the reduced basis, then test the minimal
        candidate set from :meth:`rounding_offsets`. Works for any generator; the named
        lattices use specialised kernels (Conway and Sloane) verified against this one."""
        x = self._check_points(points)
        geo = self._geo
        b = geo["reduced"]
        cand_z = geo["orthant_offsets"]
        cand = cand_z.astype(float) @ b.T
        if out is None:
            out = np.empty(x.shape, dtype=np.int64)
        kernel = qk.quantize_generic3 if self.dim == 3 else qk.quantize_generic
        kernel(
            x,
            np.ascontiguousarray(b),
            np.ascontiguousarray(np.linalg.inv(b)),
            np.ascontiguousarray(cand),
            np.ascontiguousarray(cand_z),
            geo["orthant_counts"],
            np.ascontiguousarray(geo["reduction"]),
            out,
        )
        return out

    def to_world(self, indices: np.ndarray) -> np.ndarray:
        """Cell centres ``G @ w`` in metres.

        Parameters
        ----------
        indices : array_like of int, shape (N, d)

        Returns
        -------
        ndarray, shape (N, d), float64
        """
        w = np.asarray(indices)
        if w.ndim == 1 and w.shape[0] == self.dim:
            w = w[None, :]
        if w.ndim != 2 or w.shape[1] != self.dim:
            raise LatticeError(f"indices must have shape (N, {self.dim}), got {w.shape}")
        if not np.issubdtype(w.dtype, np.integer):
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
