"""Measurements of lattice quality: the numbers behind the paper's Figs. 3-5 and Table I.

Plain functions, numpy in and out. Distances are in metres (the lattice's units); with
``cell_volume=1`` they are in units of the cube root of the cell volume. Random numbers
come from ``numpy.random.default_rng(seed)`` so every result is reproducible.

``planner lattices`` prints :func:`lattice_table`; ``planner stats`` runs
:mod:`planner.analysis.paper`.
"""

from __future__ import annotations

import math
import time
from collections.abc import Iterable, Sequence

import numpy as np
from scipy.optimize import minimize
from scipy.spatial.transform import Rotation

from planner.analysis.tables import format_table
from planner.budget import require
from planner.errors import PlannerError
from planner.lattice import NAMED_LATTICES, PAPER_DELTAS, Lattice
from planner.occupancy.keys import pack

__all__ = [
    "NAMED",
    "adjacency_offsets",
    "distance_distributions",
    "distribution_stats",
    "exact_extent",
    "format_table",
    "lattice_table",
    "neighbour_distances",
    "paper_delta_errors",
    "quantization_metrics",
    "quantize_eq2_numpy",
    "quantize_throughput",
    "random_rotations",
    "sample_in_cell",
    "sample_in_cells",
    "hex_prism",
    "optimal_hex_height",
    "rotation_summary",
    "table1",
    "uniform_points",
]

NAMED: tuple[str, ...] = tuple(NAMED_LATTICES)
_CHUNK = 1 << 16


# -- points ------------------------------------------------------------------------------
def uniform_points(lattice: Lattice, n: int, rng: np.random.Generator,
                   cells_per_side: int = 16) -> np.ndarray:
    """Points uniform in the parallelepiped ``G [0, k)^d`` (``k = cells_per_side``) at a
    random offset.

    The parallelepiped is a union of ``k^d`` lattice translates of one fundamental domain,
    so the points are exactly uniform modulo the lattice: Monte Carlo estimates of the
    quantization error are unbiased for every lattice. (An axis-aligned cube is not a union
    of cells; for a skewed generator such as MCC's its partial cells bias the estimate.)

    Returns
    -------
    ndarray, shape (n, d), float64, metres.
    """
    side = cells_per_side * lattice.cell_volume ** (1 / lattice.dim)
    origin = rng.uniform(-side, side, size=lattice.dim)
    return origin + (cells_per_side * rng.random((n, lattice.dim))) @ lattice.generator.T


def sample_in_cell(lattice: Lattice, n: int, rng: np.random.Generator) -> np.ndarray:
    """Points uniform in the Voronoi cell of the origin (relative to the cell centre).

    Uniform points in the fundamental parallelepiped ``G [0, 1)^d`` reduced modulo the
    lattice (``x - Q(x)``) are uniform in the Voronoi cell: both are fundamental domains,
    so this is the "uniform in a big box, grouped by cell" method with no rejection.

    Returns
    -------
    ndarray, shape (n, d), float64, metres.
    """
    u = rng.random((n, lattice.dim)) @ lattice.generator.T
    return u - lattice.to_world(lattice.quantize(u))


def adjacency_offsets(lattice: Lattice, kind: str) -> np.ndarray:
    """Index offsets of the adjacent cells under one definition of "adjacent".

    ``"face"``: cells sharing a 2-face; ``"full"``: cells touching at all (face, edge or
    vertex); ``"paper"``: the paper's Delta set, eqs. (3)-(7) (named lattices only, in the
    paper's generator, which ``Lattice.named`` uses).

    Returns
    -------
    ndarray, shape (k, d), int64.
    """
    if kind == "paper":
        if lattice.name not in PAPER_DELTAS:
            raise ValueError(f"no paper Delta set for lattice {lattice.name!r}")
        return PAPER_DELTAS[lattice.name].copy()
    return lattice.neighbors(kind)


def sample_in_cells(lattice: Lattice, offsets: np.ndarray, n: int,
                    rng: np.random.Generator) -> np.ndarray:
    """Points uniform in the union of the cells at index ``offsets`` (all cells have equal
    volume and are disjoint, so: pick a cell uniformly, then a point uniform in it).

    Returns
    -------
    ndarray, shape (n, d), float64, metres from the origin's lattice point.
    """
    centres = lattice.to_world(np.asarray(offsets, dtype=np.int64))
    pick = rng.integers(0, len(centres), size=n)
    return centres[pick] + sample_in_cell(lattice, n, rng)


def random_rotations(k: int, seed: int | np.random.Generator = 0) -> np.ndarray:
    """Uniformly distributed (Haar) random 3D rotations,
    :meth:`scipy.spatial.transform.Rotation.random` drawn from ``default_rng(seed)``.

    Returns
    -------
    ndarray, shape (k, 3, 3), float64: proper rotation matrices (``R @ R.T = I``,
    ``det R = +1``).
    """
    return Rotation.random(int(k), random_state=np.random.default_rng(seed)).as_matrix()


# -- quantization quality ----------------------------------------------------------------
def quantization_metrics(lattice: Lattice, points: np.ndarray) -> dict:
    """Quality of quantizing ``points`` (shape (N, d), metres) to ``lattice``.

    Returns
    -------
    dict with
        ``distortion``: E of the paper's eq. (13), mean ``|Q(x) - x|`` (metres);
        ``mse_per_dim``: mean ``|Q(x) - x|^2 / d`` (m^2);
        ``nsm``: ``mse_per_dim / V^(2/d)`` (dimensionless; the normalised second moment
        when the points are uniform);
        ``voxel_count``: number of distinct cells hit (the occupied voxel list length).
    """
    idx = lattice.quantize(points)
    err2 = np.empty(len(points))
    for s in range(0, len(points), _CHUNK):
        e = lattice.to_world(idx[s : s + _CHUNK]) - points[s : s + _CHUNK]
        err2[s : s + _CHUNK] = np.einsum("ij,ij->i", e, e)
    d = lattice.dim
    mse = float(err2.mean()) / d
    return {
        "distortion": float(np.sqrt(err2).mean()),
        "mse_per_dim": mse,
        "nsm": mse / lattice.cell_volume ** (2 / d),
        "voxel_count": int(len(np.unique(pack(idx)))),
    }


def quantize_throughput(lattice: Lattice, points: np.ndarray, repeat: int = 3) -> float:
    """Best-of-``repeat`` rate of ``lattice.quantize`` on ``points`` (points per second),
    after a small warm-up call (compiled kernels load once per process)."""
    lattice.quantize(points[:16])
    best = math.inf
    for _ in range(repeat):
        t = time.perf_counter()
        lattice.quantize(points)
        best = min(best, time.perf_counter() - t)
    return len(points) / best


def neighbour_distances(lattice: Lattice, kind: str = "full") -> np.ndarray:
    """Sorted distances (metres) from the origin to the lattice points at
    ``lattice.neighbors(kind)`` (``kind`` as in :meth:`Lattice.neighbors`, e.g. ``"full+2"``).

    Returns
    -------
    ndarray, shape (k,), float64, ascending.
    """
    return np.sort(np.linalg.norm(lattice.to_world(lattice.neighbors(kind)), axis=1))


def lattice_table(cell_volume: float = 1.0, names: Iterable[str] = NAMED,
                  n_points: int = 10**6, seed: int = 0) -> list[dict]:
    """One row of lattice properties per named lattice, all at ``cell_volume`` (m^3).

    Keys: ``lattice``, ``cell_volume``; ``n_face``/``n_full`` neighbour counts;
    ``face_min``/``face_mean``/``face_max`` and ``full_*``: distances to those neighbours
    (m); ``covering_radius``, ``packing_radius`` (m); ``nsm_exact`` (from the Voronoi cell)
    and ``nsm_mc`` (Monte Carlo on ``n_points`` uniform points); ``mean_error`` (eq. 13 on
    the same points, m); ``points_per_s`` (quantization throughput on those points).
    When ``"hex"`` is named, the hex prism at :func:`optimal_hex_height` follows it (row
    ``"hex h=<height>"``, the height in metres).
    """
    # per point: the point, its cell, its error vector and the metrics' temporaries
    require(float(n_points) * 3 * 8 * 6, f"{n_points} uniform points (--points)",
            error=PlannerError)
    lats = []
    for name in names:
        lats.append(Lattice.named(name, cell_volume))
        if name == "hex":
            lats.append(hex_prism(cell_volume, optimal_hex_height(cell_volume)))
    rows = []
    for lat in lats:
        rng = np.random.default_rng(seed)
        pts = uniform_points(lat, n_points, rng)
        m = quantization_metrics(lat, pts)
        row = {"lattice": lat.name, "cell_volume": float(cell_volume)}
        for kind in ("face", "full"):
            d = neighbour_distances(lat, kind)
            row[f"n_{kind}"] = len(d)
            row[f"{kind}_min"] = float(d.min())
            row[f"{kind}_mean"] = float(d.mean())
            row[f"{kind}_max"] = float(d.max())
        row.update(
            covering_radius=lat.covering_radius,
            packing_radius=lat.packing_radius,
            nsm_exact=lat.normalized_second_moment,
            nsm_mc=m["nsm"],
            mean_error=m["distortion"],
            points_per_s=quantize_throughput(lat, pts),
        )
        rows.append(row)
    return rows


# -- Fig. 4: distances within a cell and to points in adjacent cells ----------------------
def distance_distributions(lattice: Lattice, n: int, seed: int = 0,
                           kinds: Sequence[str] = ("face", "full", "paper")) -> dict:
    """Distances (metres) from the origin's lattice point to ``n`` points uniform in its own
    cell (key ``"cell"``) and to ``n`` points uniform in the union of its adjacent cells
    for each adjacency definition in ``kinds`` (see :func:`adjacency_offsets`).

    Returns
    -------
    dict: name -> ndarray, shape (n,), float64.
    """
    rng = np.random.default_rng(seed)
    out = {"cell": np.linalg.norm(sample_in_cell(lattice, n, rng), axis=1)}
    for kind in kinds:
        offs = adjacency_offsets(lattice, kind)
        out[kind] = np.linalg.norm(sample_in_cells(lattice, offs, n, rng), axis=1)
    return out


def exact_extent(lattice: Lattice, offsets: np.ndarray | None) -> tuple[float, float]:
    """Exact (min, max) distance from the origin to the closed union of the cells at index
    ``offsets``; ``None`` means the origin's own cell (min 0, max the covering radius).

    The max of a convex function over a polytope is at a vertex; the min over each cell is a
    small convex quadratic programme.
    """
    verts = lattice.voronoi_vertices
    if offsets is None:
        return 0.0, float(np.linalg.norm(verts, axis=1).max())
    rel = lattice.relevant_vectors
    rhs = 0.5 * np.einsum("ij,ij->i", rel, rel)
    centres = lattice.to_world(np.asarray(offsets, dtype=np.int64))
    far = max(float(np.linalg.norm(c + verts, axis=1).max()) for c in centres)
    near = math.inf
    for c in centres:
        # Cell of c: (x - c) . r <= |r|^2 / 2 for every relevant r. Start at the vertex
        # nearest the origin (feasible), minimise |x|^2.
        x0 = (c + verts)[np.argmin(np.linalg.norm(c + verts, axis=1))]
        res = minimize(
            lambda x: x @ x, x0, jac=lambda x: 2 * x, method="SLSQP",
            constraints=[{"type": "ineq", "fun": lambda x, c=c: rhs - rel @ (x - c),
                          "jac": lambda x: -rel}],
            options={"ftol": 1e-14, "maxiter": 200},
        )
        near = min(near, math.sqrt(max(float(res.fun), 0.0)), float(np.linalg.norm(x0)))
    return near, far


def distribution_stats(d: np.ndarray) -> dict:
    """Spread of a sample of distances ``d`` (shape (n,), metres): ``mean``, ``std``,
    ``p5``/``p95`` percentiles, ``range90 = p95 - p5``, sample ``min``/``max`` and
    ``range = max - min``."""
    p5, p95 = np.percentile(d, [5, 95])
    return {
        "mean": float(d.mean()), "std": float(d.std()),
        "p5": float(p5), "p95": float(p95), "range90": float(p95 - p5),
        "min": float(d.min()), "max": float(d.max()), "range": float(d.max() - d.min()),
    }


# -- eq. (2) in plain numpy, and the paper's Delta sets ----------------------------------
def quantize_eq2_numpy(points: np.ndarray, generator: np.ndarray, deltas: np.ndarray,
                       chunk: int = 1 << 14) -> np.ndarray:
    """The paper's eq. (2), straightforwardly vectorised: ``w = round(G^-1 x)``, then the
    candidate among ``w + Delta_i`` nearest to ``x``. ``deltas`` (shape (k, d), int) should
    contain the zero offset. Processes ``chunk`` points at a time (16,384 was the fastest
    chunk size tried; squared distances are summed per axis to keep temporaries small).

    Returns
    -------
    ndarray, shape (N, d), int64 lattice indices.
    """
    g = np.asarray(generator, dtype=float)
    ginv = np.linalg.inv(g)
    dl = np.asarray(deltas, dtype=np.int64)
    dw = dl @ g.T  # (k, d) world offsets
    out = np.empty(points.shape, dtype=np.int64)
    for s in range(0, len(points), chunk):
        x = points[s : s + chunk]
        w = np.rint(x @ ginv.T)
        r0 = w @ g.T - x  # (c, d) rounded point - x
        d2 = np.zeros((len(x), len(dl)))
        for j in range(g.shape[0]):
            t = r0[:, j : j + 1] + dw[None, :, j]  # (c, k) candidate - x along axis j
            d2 += t * t
        best = np.argmin(d2, axis=1)
        out[s : s + chunk] = w.astype(np.int64) + dl[best]
    return out


def paper_delta_errors(lattice: Lattice, n: int = 10**6, seed: int = 0,
                       deltas: np.ndarray | None = None) -> dict:
    """How often eq. (2) with the paper's Delta set (plus the zero offset) misses the
    nearest lattice point, on ``n`` uniform random points.

    Returns
    -------
    dict: ``n``, ``n_deltas`` (candidates incl. zero), ``wrong`` (count whose answer is
    strictly farther than the nearest point by > 1e-9 cell sizes), ``rate``,
    ``max_extra`` (largest extra distance, metres) and ``max_extra_rel`` (the same over the
    cube root of the cell volume).
    """
    if deltas is None:
        deltas = PAPER_DELTAS[lattice.name]
    dl = np.unique(np.vstack([np.zeros((1, lattice.dim), np.int64), deltas]), axis=0)
    pts = uniform_points(lattice, n, np.random.default_rng(seed))
    got = quantize_eq2_numpy(pts, lattice.generator, dl)
    ref = lattice.quantize(pts)
    extra = (np.linalg.norm(lattice.to_world(got) - pts, axis=1)
             - np.linalg.norm(lattice.to_world(ref) - pts, axis=1))
    scale = lattice.cell_volume ** (1 / lattice.dim)
    wrong = extra > 1e-9 * scale
    mx = float(extra.max(initial=0.0))
    return {"n": n, "n_deltas": len(dl), "wrong": int(wrong.sum()),
            "rate": float(wrong.mean()), "max_extra": mx, "max_extra_rel": mx / scale}


# -- Table I -----------------------------------------------------------------------------
def rotation_summary(rows: Sequence[dict], reference: str = "cubic") -> list[dict]:
    """Median over rotations, per (dataset, cell_volume, lattice), of ``voxel_count``,
    ``mse_per_dim`` and ``distortion``, each also as percent change relative to
    ``reference`` (``rel_*``, negative = better than the reference).

    ``rows`` are dicts with keys ``dataset``, ``cell_volume``, ``lattice``, ``rotation``,
    ``voxel_count``, ``mse_per_dim``, ``distortion`` (one per rotation and lattice).
    """
    groups: dict[tuple, list[dict]] = {}
    for r in rows:
        groups.setdefault((r["dataset"], float(r["cell_volume"]), r["lattice"]), []).append(r)
    keys = ("voxel_count", "mse_per_dim", "distortion")
    med = {g: {k: float(np.median([float(r[k]) for r in v])) for k in keys}
           for g, v in groups.items()}
    out = []
    for (ds, vol, lat), m in med.items():
        ref = med.get((ds, vol, reference))
        row = {"dataset": ds, "cell_volume": vol, "lattice": lat,
               "rotations": len(groups[(ds, vol, lat)]), **m}
        for k in keys:
            row[f"rel_{k}"] = 100.0 * (m[k] / ref[k] - 1.0) if ref else float("nan")
        out.append(row)
    return out


TABLE_COLUMNS = (
    "lattice", "n_face", "n_full", "face_min", "face_max", "full_mean", "full_max",
    "packing_radius", "covering_radius", "nsm_exact", "nsm_mc", "mean_error", "points_per_s",
)
"""The columns ``planner lattices`` prints by default."""


# -- Table I (the paper's protocol) and the hex prism height ------------------------------
def hex_prism(cell_volume: float, height: float) -> Lattice:
    """Hexagonal prismatic lattice of cell volume ``cell_volume`` (m^3) and prism ``height``
    (m): hexagons in the x-y plane, prism axis along z.

    >>> lat = hex_prism(1.0, 3 ** (-1 / 6))
    >>> bool(np.allclose(lat.generator, Lattice.named("hex").generator))
    True
    """
    a = math.sqrt(2.0 * cell_volume / (math.sqrt(3.0) * height))
    g = np.array([[a, -a / 2, 0.0], [0.0, a * math.sqrt(3.0) / 2, 0.0], [0.0, 0.0, height]])
    return Lattice(g, name=f"hex h={height:.4g}")


def optimal_hex_height(cell_volume: float = 1.0) -> float:
    """Prism height (m) that minimises the mean squared quantization error of uniform points.

    The second moment of a prism of hexagon area ``A`` and height ``h`` is
    ``2 G2 A + h^2 / 12`` with ``G2 = 5 / (36 sqrt 3)`` (the hexagon's normalised second
    moment); with ``A = V / h`` the minimum is at ``h^3 = 12 G2 V``.  The paper's height
    ``3^(-1/6) V^(1/3) = 0.833 V^(1/3)`` is 16% lower.

    >>> round(optimal_hex_height(1.0), 4)
    0.9873
    """
    g2 = 5.0 / (36.0 * math.sqrt(3.0))
    return (12.0 * g2 * cell_volume) ** (1.0 / 3.0)


def table1(points: np.ndarray, cell_volume: float = 0.125,
           names: Iterable[str] = NAMED) -> list[dict]:
    """The paper's Table I protocol: one gravity-aligned map quantized without rotation.

    Parameters
    ----------
    points : ndarray, shape (N, 3)
        The map (metres), as recorded (no rotation).
    cell_volume : float
        m^3 (the paper's 0.125).
    names : iterable of str
        Named lattices; the hex prism is also reported at :func:`optimal_hex_height`.

    Returns
    -------
    list of dict
        Per lattice: ``cell_volume``, ``voxel_count``, ``mse_per_dim`` (m^2),
        ``rms_distance_error`` = sqrt(3 x MSE/dimension) (m; the paper's "distance error"
        column) and ``mean_distance_eq13`` (eq. 13's mean |Q(x) - x|, m), plus
        ``rel_voxel_count`` (% vs cubic).
    """
    lats = [Lattice.named(n, cell_volume) for n in names]
    if "hex" in names:
        lats.append(hex_prism(cell_volume, optimal_hex_height(cell_volume)))
    rows = []
    for lat in lats:
        m = quantization_metrics(lat, points)
        rows.append({"lattice": lat.name, "cell_volume": cell_volume,
                     "height": float(lat.generator[2, 2]) if "hex" in str(lat.name) else None,
                     "voxel_count": m["voxel_count"], "mse_per_dim": m["mse_per_dim"],
                     "rms_distance_error": math.sqrt(lat.dim * m["mse_per_dim"]),
                     "mean_distance_eq13": m["distortion"]})
    ref = next((r for r in rows if r["lattice"] == "cubic"), None)
    for r in rows:
        r["rel_voxel_count"] = (100.0 * (r["voxel_count"] / ref["voxel_count"] - 1.0)
                                if ref else float("nan"))
    return rows
