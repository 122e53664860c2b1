"""The lattice cells a set of boxes meets with positive volume (the radius-0 case of
:func:`planner.voxels.inflate.exact_box_inflation`), as sorted packed keys."""

from __future__ import annotations

import math

import numpy as np

from planner.budget import require
from planner.errors import MapError
from planner.lattice import Lattice
from planner.occupancy.keys import check_range, pack, unique_keys
from planner.voxels import _box_kernels as bk
from planner.voxels._checks import as_points, check_lattice, key_offsets

__all__ = ["box_cell_keys", "box_frame", "box_keys", "overlap_keys"]

_BOX_CHUNK_KEYS = 1 << 24  # candidate keys per box chunk (of int64)


def box_cell_keys(lo: np.ndarray, hi: np.ndarray, lattice: Lattice) -> np.ndarray:
    """Sorted keys (M,) of the cells overlapping the axis-aligned boxes ``[lo[k], hi[k]]``
    ((K, d), m) with positive volume, plus the cell of each box centre."""
    lat = check_lattice(lattice)
    return overlap_keys(*box_frame(lo, hi, None, None, lat.dim), lat)


# -- cells meeting boxes ---------------------------------------------------------------------
def box_keys(centres: np.ndarray, size: float, lattice: Lattice) -> np.ndarray:
    """Sorted unique keys of the cells whose Voronoi cell overlaps a box (positive volume).

    Exact up to a tolerance of 1e-9 cell diameters: overlaps thinner than that (touching
    faces, edges, corners) do not count. The cell containing each box centre always counts.
    A box of size 0 is a point (its containing cell).

    Parameters
    ----------
    centres : ndarray, shape (M, d)
        Centres of axis-aligned cubes (m).
    size : float
        Cube edge length (m), >= 0.
    lattice : Lattice

    Returns
    -------
    ndarray, shape (K,), int64
    """
    lat = check_lattice(lattice)
    c = as_points(centres, lat.dim, "box centres")
    s = float(size)
    if not math.isfinite(s) or s < 0:
        raise MapError(f"box size must be a non-negative number of metres, got {size!r}")
    return overlap_keys(c, np.full(c.shape, s / 2), np.eye(lat.dim), lat)


def overlap_keys(centres: np.ndarray, half: np.ndarray, rot: np.ndarray, lat: Lattice
                  ) -> np.ndarray:
    """Keys of the cells overlapping boxes ``{C + R x : |x| <= H}`` with positive volume,
    plus the cell of each centre; ``centres``, ``half`` (K, d) metres, ``rot`` (d, d)."""
    d = lat.dim
    if not len(centres):
        return np.zeros(0, dtype=np.int64)
    base = lat.quantize(centres)
    base_keys = pack(base)
    if not half.any():
        return unique_keys(base_keys)
    # Each box overlaps at least its volume in cells (per chunk, before the merge): refuse a
    # box set whose key lists alone exceed the budget before enumerating anything.
    need = 8.0 * float(np.prod(2 * half, axis=1).sum()) / lat.cell_volume
    require(need, f"the cells of {len(centres)} boxes")
    t = bk.overlap_tests(lat, half, rot)
    offs = t.offsets
    ext = np.abs(offs).max(axis=0)
    check_range(base.min(axis=0) - ext, base.max(axis=0) + ext, d)
    base_world = lat.to_world(base)
    offs_key = key_offsets(offs)
    chunk = max(1, _BOX_CHUNK_KEYS // len(offs))
    parts = []
    buf = np.empty(min(chunk, len(centres)) * len(offs), dtype=np.int64)
    for i in range(0, len(centres), chunk):
        sl = slice(i, i + chunk)
        n = bk.overlap_keys(np.ascontiguousarray(centres[sl]), np.ascontiguousarray(half[sl]),
                            base_keys[sl], np.ascontiguousarray(base_world[sl]), t.offs_world,
                            offs_key, t.axes, t.axes_box, t.support_v, t.packing, t.covering,
                            t.tol, buf)
        parts.append(unique_keys(buf[:n]))  # per chunk: neighbouring boxes share cells
    parts.append(base_keys)  # the centre's cell, even for boxes thinner than the tolerance
    return unique_keys(np.concatenate(parts))


def box_frame(lo, hi, rotation, translation, d: int) -> tuple[np.ndarray, ...]:
    """Checked ``(centres (K, d) world, half sizes (K, d), R (d, d))`` of boxes
    ``{R x + t : lo <= x <= hi}``."""
    a = as_points(lo, d, "box lower corners")
    b = as_points(hi, d, "box upper corners")
    if a.shape != b.shape:
        raise MapError(f"box corners differ in shape: lo {a.shape}, hi {b.shape}")
    if len(a) and (b < a).any():
        row = int(np.flatnonzero((b < a).any(axis=1))[0])
        raise MapError(f"box {row}: upper corner {b[row].tolist()} is below the lower corner "
                       f"{a[row].tolist()}")
    rot = np.eye(d) if rotation is None else np.asarray(rotation, dtype=float)
    if rot.shape != (d, d) or not np.isfinite(rot).all() or not np.allclose(
            rot.T @ rot, np.eye(d), atol=1e-9) or np.linalg.det(rot) < 0:
        raise MapError(f"rotation must be a proper {d}x{d} rotation matrix, got "
                       f"{np.array2string(rot, separator=', ').replace(chr(10), '')}")
    t = np.zeros(d) if translation is None else np.asarray(translation, dtype=float).ravel()
    if t.shape != (d,) or not np.isfinite(t).all():
        raise MapError(f"translation must be {d} finite numbers (m), got {translation!r}")
    mid = (a + b) / 2
    # No product with the identity (the same numbers; a small BLAS call can cost more than
    # the whole inflation on a loaded machine).
    centres = np.ascontiguousarray((mid if rotation is None else mid @ rot.T) + t)
    return centres, np.ascontiguousarray((b - a) / 2), np.ascontiguousarray(rot)
