"""Input checks and budget helpers shared by the voxel modules."""

from __future__ import annotations

import numpy as np

from planner.budget import memory_budget
from planner.errors import LatticeError, MapError
from planner.lattice import Lattice
from planner.occupancy.keys import BITS

DEFAULT_BUDGET = None  # bytes of scratch + result an inflation may use: planner.budget's
REL_TOL = 1e-9  # geometric tolerance, relative to the cell diameter


# -- input checks ---------------------------------------------------------------------------
def check_lattice(lattice) -> Lattice:
    if not isinstance(lattice, Lattice):
        raise MapError(f"lattice must be a Lattice, got {type(lattice).__name__}")
    return lattice


def as_points(points, dim: int, what: str = "points") -> np.ndarray:
    """(N, dim) finite float64 contiguous array, or MapError naming the problem."""
    try:
        x = np.asarray(points, dtype=float)
    except (TypeError, ValueError):
        raise MapError(f"{what} must be a numeric (N, {dim}) array") from None
    if x.ndim == 1 and x.shape[0] == dim:
        x = x[None, :]
    if x.ndim != 2 or x.shape[1] != dim:
        raise MapError(f"{what} must have shape (N, {dim}), got {x.shape}")
    if not np.isfinite(x).all():
        row = int(np.flatnonzero(~np.isfinite(x).all(axis=1))[0])
        raise MapError(f"{what} contain NaN or infinite coordinates (row {row})")
    return np.ascontiguousarray(x)


def as_indices(indices, dim: int) -> np.ndarray:
    """(N, dim) int64 array, or MapError."""
    w = np.asarray(indices)
    if w.size == 0:
        return np.zeros((0, dim), dtype=np.int64)
    if w.ndim == 1 and w.shape[0] == dim:
        w = w[None, :]
    if w.ndim != 2 or w.shape[1] != dim:
        raise MapError(f"indices must have shape (N, {dim}), got {w.shape}")
    if not np.issubdtype(w.dtype, np.integer):
        raise MapError(f"indices must be integers, got dtype {w.dtype}")
    return np.ascontiguousarray(w, dtype=np.int64)


def gb(nbytes: float) -> str:
    return f"{nbytes / 2**30:.3g} GB"


def cell_diameter(lat: Lattice) -> float:
    """Edge of a cube of the cell's volume (m): the unit of geometric tolerances."""
    return lat.cell_volume ** (1 / lat.dim)


def key_offsets(offsets: np.ndarray) -> np.ndarray:
    """Key difference of each index offset: ``key(w + o) - key(w)`` when both are packable."""
    d = offsets.shape[1]
    bits = BITS[d]
    out = np.zeros(len(offsets), dtype=np.int64)
    for j in range(d):
        out += offsets[:, j].astype(np.int64) << (bits * (d - 1 - j))
    return out


def resolve_budget(budget: float | None) -> float:
    """Bytes allowed: ``budget``, or the one memory budget (:mod:`planner.budget`)."""
    return float(memory_budget() if budget is None else budget)


def over_budget(radius: float, need: float, budget: float) -> MapError:
    return MapError(f"building the inflation for radius {radius:.6g} m needs ~{gb(need)}, over "
                    f"the memory budget of {gb(budget)} (--memory-budget / memory_budget); "
                    "use a larger cell volume")


def grid_strides(dims: np.ndarray) -> np.ndarray:
    s = np.ones(len(dims), dtype=np.int64)
    for j in range(len(dims) - 2, -1, -1):
        s[j] = s[j + 1] * dims[j + 1]
    return s



def offsets_within(lat: Lattice, radius: float, budget: float, asked: float) -> np.ndarray:
    """``lat.voronoi.offsets_within(radius)``, refused as a MapError naming the caller's
    radius ``asked`` when the enumeration alone would exceed ``budget`` bytes (None: the
    memory budget)."""
    budget = resolve_budget(budget)
    try:
        return lat.voronoi.offsets_within(radius, budget)
    except LatticeError:
        need = lat.voronoi.count_within(radius) * lat.dim * 8 * 3
        raise over_budget(asked, need, budget) from None
