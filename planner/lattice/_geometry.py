"""Lattice geometry derived from a generator: LLL reduction, Voronoi-relevant vectors, the
Voronoi cell as a polytope (:class:`VoronoiCell`), touching cells, radii, second moment and
the exact candidate sets of the rounding quantizer.

Nothing is tabulated per lattice: everything follows from the generator ``G`` (``d x d``,
columns are basis vectors, metres). Enumerations run over boxes of integer coefficients in
the LLL-reduced basis; their size is checked against a budget first (ill-conditioned
generators would otherwise ask for billions of vectors).

The integer sets (relevant and touching vectors, rounding candidates) depend only on the
lattice's shape, not its scale: they are derived once per shape and cell volumes share
them (:func:`_shape_sets`). The polytope's vertices, edges and second moment are computed
in :mod:`planner.lattice._polytope`.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from planner.budget import memory_budget
from planner.errors import LatticeError
from planner.lattice._polytope import TOL, cell_edges, second_moment, voronoi_vertices

__all__ = ["VoronoiCell", "ENUM_LIMIT", "reduce_basis", "geometry"]

# Most lattice vectors the geometry may enumerate (cubic needs 125; an aspect ratio of ~500
# between reduced basis vectors reaches it). Beyond it, deriving the cell takes minutes.
ENUM_LIMIT = 20_000
DEFAULT_BUDGET = None  # bytes an offsets_within enumeration may use: planner.budget's


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
    steps = 0
    while k < d:
        steps += 1
        if steps > 10_000:  # a valid input converges in a few dozen steps
            raise LatticeError("generator is too ill-conditioned: basis reduction does not "
                               "converge")
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


def box_for_radius(basis: np.ndarray, radius: float) -> np.ndarray:
    """Per-axis coefficient bound K with every lattice vector of norm <= radius in [-K, K]^d."""
    rows = np.linalg.norm(np.linalg.inv(basis), axis=1)
    return np.ceil(radius * rows + 1e-9).astype(np.int64)


def box_count(basis: np.ndarray, radius: float) -> float:
    """Number of coefficient vectors :func:`grid` would enumerate for ``radius``."""
    k = box_for_radius(basis, radius).astype(float)
    return float(np.prod(2 * k + 1))


def grid(bound: np.ndarray) -> np.ndarray:
    """All integer vectors in the box prod([-bound_i, bound_i]); shape (n, d)."""
    axes = [np.arange(-k, k + 1) for k in bound]
    return np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, len(bound))


def _half_diagonal(b: np.ndarray) -> float:
    """Half the longest diagonal of the parallelepiped spanned by the columns of ``b``."""
    signs = np.array(list(itertools.product((-1.0, 1.0), repeat=b.shape[1])))
    return 0.5 * float(np.linalg.norm(signs @ b.T, axis=1).max())


@lru_cache(maxsize=256)
def reduce_basis(gen_bytes: bytes, d: int) -> tuple[np.ndarray, np.ndarray]:
    """LLL-reduced basis ``B`` and unimodular ``T`` (``B = G T``) of a valid generator.

    Raises LatticeError when the geometry of this lattice would enumerate more than
    :data:`ENUM_LIMIT` vectors (a badly ill-conditioned lattice, e.g. ``diag(1, 1, 1e-6)``).
    """
    g = np.frombuffer(gen_bytes, dtype=float).reshape(d, d)
    b, t = _lll(g)
    need = box_count(b, 2 * _half_diagonal(b))
    if need > ENUM_LIMIT:
        lengths = np.linalg.norm(b, axis=0)
        raise LatticeError(
            f"generator is too ill-conditioned: its reduced basis vectors are "
            f"{lengths.min():.3g} to {lengths.max():.3g} m long, so deriving its Voronoi cell "
            f"would enumerate ~{need:.3g} lattice vectors (limit {ENUM_LIMIT:,})")
    b.setflags(write=False)
    t.setflags(write=False)
    return b, t


def _frozen(a: np.ndarray, dtype=float) -> np.ndarray:
    out = np.ascontiguousarray(a, dtype=dtype)
    out.setflags(write=False)
    return out


@dataclass(frozen=True, eq=False)
class VoronoiCell:
    """The Voronoi cell ``V`` of the origin of a lattice, as a polytope (metres).

    ``V = {y : normals @ y <= offsets}``; its facets are the bisectors of the Voronoi-relevant
    vectors. All arrays are read-only.

    Attributes
    ----------
    generator : ndarray, shape (d, d)
        The lattice generator (columns are basis vectors).
    reduced, reduction : ndarray, shape (d, d)
        LLL-reduced basis ``B = G @ T`` and the unimodular ``T`` (int64).
    relevant : ndarray, shape (k, d)
        Voronoi-relevant vectors ``v``: ``V = {y : y . v <= |v|^2 / 2}``.
    normals : ndarray, shape (k, d)
        Unit facet normals ``v / |v|``.
    offsets : ndarray, shape (k,)
        Facet offsets ``|v| / 2``.
    vertices : ndarray, shape (n, d)
        Cell vertices.
    edges : tuple of two ndarrays, shape (m, d) each
        Edge end points ``(e0, e1)`` (in 2D the edges are the facets).
    packing_radius, covering_radius : float
        Radii of the inscribed and circumscribed balls centred at the origin.
    second_moment : float
        Normalised second moment ``(1/d) E|x|^2 / V^(2/d)`` of the cell.
    """

    generator: np.ndarray
    reduced: np.ndarray
    reduction: np.ndarray
    relevant: np.ndarray
    normals: np.ndarray
    offsets: np.ndarray
    vertices: np.ndarray
    edges: tuple[np.ndarray, np.ndarray]
    packing_radius: float
    covering_radius: float
    second_moment: float

    @property
    def dim(self) -> int:
        return self.generator.shape[0]

    def count_within(self, radius: float) -> float:
        """How many coefficient vectors :meth:`offsets_within` examines for ``radius``."""
        return box_count(self.reduced, radius)

    def offsets_within(self, radius: float, budget: float | None = DEFAULT_BUDGET
                       ) -> np.ndarray:
        """Index offsets ``w`` whose cell centre ``G w`` lies within ``radius`` (m) of 0.

        Enumerated over a box in the LLL-reduced basis (tight for skewed generators).

        Returns
        -------
        ndarray, shape (K, d), int64

        Raises
        ------
        LatticeError
            When the enumeration would take more than ``budget`` bytes (default: the
            memory budget of :mod:`planner.budget`).
        """
        if budget is None:
            budget = memory_budget()
        need = self.count_within(radius) * self.dim * 8 * 3
        if need > budget:
            raise LatticeError(f"offsets within {radius:.6g} m need ~{need / 2**30:.3g} GB, over "
                               f"the budget of {budget / 2**30:.3g} GB")
        z = grid(box_for_radius(self.reduced, radius))
        w = z @ self.reduction.T
        keep = np.linalg.norm(w @ self.generator.T, axis=1) <= radius
        return np.ascontiguousarray(w[keep], dtype=np.int64)

    def separating_axes(self, box_axes: np.ndarray | None = None) -> np.ndarray:
        """Unit axes (one per +- pair) deciding whether a box and a cell overlap.

        Box face normals, cell facet normals and (3D) cross products of the box axes with
        the cell's edge directions: two convex polytopes are disjoint iff their projections
        on one of these axes are (separating axis theorem). They are also the facet normals
        of the Minkowski sum box + V.

        Parameters
        ----------
        box_axes : ndarray, shape (d, d), optional
            Columns are the box's edge directions (a rotation); default the identity.

        Returns
        -------
        ndarray, shape (m, d)
        """
        d = self.dim
        rot = np.eye(d) if box_axes is None else np.asarray(box_axes, dtype=float)
        axes = [rot.T, self.normals]
        if d == 3:
            e0, e1 = self.edges
            edges = (e1 - e0) / np.linalg.norm(e1 - e0, axis=1)[:, None]
            cr = np.cross(rot.T[:, None, :], edges[None, :, :]).reshape(-1, 3)
            n = np.linalg.norm(cr, axis=1)
            axes.append(cr[n > 1e-9] / n[n > 1e-9, None])
        ax = np.concatenate(axes)
        # Canonical sign (first nonzero component positive), then drop duplicates.
        first = ax[np.arange(len(ax)), np.argmax(np.abs(ax) > 1e-9, axis=1)]
        ax = ax * np.sign(first)[:, None]
        _, keep = np.unique(np.round(ax, 9), axis=0, return_index=True)
        return np.ascontiguousarray(ax[np.sort(keep)])


def _shape_key(g: np.ndarray, d: int) -> bytes:
    """The shape of generator ``g`` (d, d): ``g`` scaled to unit determinant (cells about 1
    across) and rounded to 12 decimals, so that one shape at any cell volume gives one key
    (the scaled matrix differs from volume to volume in its last bits). The rounding moves
    the lattice by at most 5e-13 of a cell, far inside the 1e-9 tolerances of the tests."""
    u = g / abs(float(np.linalg.det(g))) ** (1 / d)
    return np.ascontiguousarray(np.round(u, 12)).tobytes()


@lru_cache(maxsize=64)
def _shape_sets(shape: bytes, d: int) -> dict:
    """The integer sets of a lattice shape (:func:`_shape_key`): the reduction ``T`` and, in
    reduced coefficients, the Voronoi-relevant (``face_z``) and touching (``full_z``)
    vectors and the rounding candidate sets (``round_offsets``, ``orthant_offsets``,
    ``orthant_counts``). Cached per process: the linear programmes cost most of a lattice.

    Exact for every scale ``s`` of the shape: the lattice ``s U`` has the vectors ``s U w``
    and the Voronoi cell ``s V``, so every test below scales as a whole: norms and coset
    minima by ``s**2``, the rounding parallelepiped, the cells and the ball slack of each
    linear programme by ``s``, and every tolerance is relative to the cell's size. Each
    test therefore decides the same integer vectors at every scale; only the metric
    quantities (vectors in metres, vertices, radii) scale, and :func:`geometry` computes
    those from the generator itself.
    """
    u = np.frombuffer(shape, dtype=float).reshape(d, d)
    b, t = reduce_basis(shape, d)
    # Covering radius bound: Babai rounding in the reduced basis errs by at most half the
    # longest diagonal of its parallelepiped, so coset minima lie within twice that.
    z = grid(box_for_radius(b, 2 * _half_diagonal(b)))
    v = z @ b.T
    n2 = np.einsum("ij,ij->i", v, v)
    scale2 = float(np.abs(np.linalg.det(u))) ** (2 / d)
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
        shortest = z[in_coset][n2[in_coset] <= m + TOL * scale2]
        full.append(shortest)
        if len(shortest) == 2:
            face.append(shortest)
    face_z = np.concatenate(face)
    rel = face_z @ b.T
    cover = float(np.linalg.norm(voronoi_vertices(rel), axis=1).max())
    offsets_all = rounding_offsets(b, rel, cover)
    # Per sign pattern of the rounding residual (bit i set: f_i > 0), padded with the
    # zero offset so that every row has the same length for the compiled kernel. Each
    # orthant's set is a subset of the whole box's, so only those candidates are tested.
    per = [rounding_offsets(b, rel, cover, tuple(1 if (o >> i) & 1 else -1 for i in range(d)),
                            candidates=offsets_all)
           for o in range(2**d)]
    width = max(len(p) for p in per)
    by_orthant = np.zeros((2**d, width, d), dtype=np.int64)
    for o, p in enumerate(per):
        by_orthant[o, : len(p)] = p
    out = {"reduction": t, "face_z": face_z, "full_z": np.concatenate(full),
           "round_offsets": offsets_all, "orthant_offsets": by_orthant,
           "orthant_counts": np.array([len(p) for p in per], dtype=np.int64)}
    for a in out.values():
        a.setflags(write=False)
    return out


@lru_cache(maxsize=64)
def geometry(gen_bytes: bytes, d: int) -> dict:
    """Geometry of the lattice with this generator (cached; everything derived, nothing tabled).

    The integer sets come from the lattice's shape (:func:`_shape_sets`, derived once per
    shape, whatever the cell volume); the cell in metres from the generator itself.

    Keys: ``reduced``, ``reduction``, ``face``, ``full``, ``cell`` (:class:`VoronoiCell`),
    ``round_offsets``, ``orthant_offsets``, ``orthant_counts``.
    """
    g = np.frombuffer(gen_bytes, dtype=float).reshape(d, d)
    sets = _shape_sets(_shape_key(g, d), d)
    t = sets["reduction"]
    b = g @ t  # the shape's reduced basis at this scale
    face_z = sets["face_z"]
    rel = face_z @ b.T  # (k, d) relevant vectors, world units
    scale2 = float(np.abs(np.linalg.det(g))) ** (2 / d)
    verts = voronoi_vertices(rel)
    cover = float(np.linalg.norm(verts, axis=1).max())
    norms = np.linalg.norm(rel, axis=1)
    normals, offsets = rel / norms[:, None], norms / 2
    e0, e1 = cell_edges(normals, offsets, verts, d, scale2 ** 0.5)
    cell = VoronoiCell(
        generator=_frozen(g), reduced=_frozen(b), reduction=_frozen(t, np.int64),
        relevant=_frozen(rel), normals=_frozen(normals), offsets=_frozen(offsets),
        vertices=_frozen(verts), edges=(_frozen(e0), _frozen(e1)),
        packing_radius=float(norms.min() / 2), covering_radius=cover,
        second_moment=second_moment(rel, verts))
    return {
        "reduced": cell.reduced,
        "reduction": t,
        "face": sorted_offsets(face_z @ t.T, g),  # reduced coefficients -> user indices
        "full": sorted_offsets(sets["full_z"] @ t.T, g),
        "cell": cell,
        "round_offsets": sets["round_offsets"],
        "orthant_offsets": sets["orthant_offsets"],
        "orthant_counts": sets["orthant_counts"],
    }


def sorted_offsets(w: np.ndarray, g: np.ndarray) -> np.ndarray:
    """Sort index offsets by world length, then lexicographically (deterministic order)."""
    lengths = np.round(np.linalg.norm(w @ g.T, axis=1), 9)
    order = np.lexsort(tuple(w.T[::-1]) + (lengths,))
    return np.ascontiguousarray(w[order], dtype=np.int64)


def rounding_offsets(
    basis: np.ndarray, rel: np.ndarray, cover: float, orthant: tuple[int, ...] | None = None,
    candidates: np.ndarray | None = None,
) -> np.ndarray:
    """Exact candidate set for quantization by rounding in ``basis`` then a local search.

    With ``z0 = round(B^-1 x)`` the residual ``x - B z0`` lies in the parallelepiped
    ``P = B [-1/2, 1/2]^d``, so the nearest lattice point is ``B (z0 + delta)`` for some
    ``delta`` whose Voronoi cell meets the interior of ``P``. Each candidate is decided by a
    small linear programme (largest ball-slack of a common point), so the set is minimal:
    every returned offset is the unique answer for some open set of points.
    With ``orthant`` (a sign per axis) only residuals ``f = B^-1 x - z0`` with those
    signs are considered: the residual's sign pattern then selects a smaller set.
    ``candidates`` restricts the search (default: every offset that could qualify).

    Returns
    -------
    ndarray, shape (k, d), int64
        Offsets in ``basis`` coefficients, the zero offset first.
    """
    from scipy.optimize import linprog  # heavy import: only when a lattice is derived

    d = basis.shape[0]
    binv = np.linalg.inv(basis)
    half_diag = _half_diagonal(basis)
    if candidates is None:
        candidates = grid(box_for_radius(basis, half_diag + cover))
    rn = np.linalg.norm(rel, axis=1)
    rows = np.linalg.norm(binv, axis=1)
    rhs_v = 0.5 * rn**2
    # Variables (x, t): maximise t s.t. x + t-ball inside both V + c and P.
    a_ub = np.vstack([np.hstack([rel, rn[:, None]]), np.hstack([binv, rows[:, None]]),
                      np.hstack([-binv, rows[:, None]])])
    hi = np.full(d, 0.5)
    lo = np.full(d, 0.5)
    if orthant is not None:  # 0 <= sign_i * f_i: clamp the other half of the box
        o = np.asarray(orthant)
        hi = np.where(o > 0, 0.5, 0.0)
        lo = np.where(o > 0, 0.0, 0.5)
    keep = []
    for delta in candidates:
        c = basis @ delta
        if np.linalg.norm(c) > half_diag + cover + 1e-9:
            continue
        res = linprog(np.r_[np.zeros(d), -1.0], A_ub=a_ub,
                      b_ub=np.concatenate([rhs_v + rel @ c, hi, lo]),
                      bounds=[(None, None)] * d + [(None, 1.0)], method="highs")
        if res.status == 0 and -res.fun > 1e-9 * cover:
            keep.append(delta)
    out = np.array(keep, dtype=np.int64)
    zero = np.all(out == 0, axis=1)
    return np.concatenate([out[zero], out[~zero]])
