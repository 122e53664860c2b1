"""The one point validator every reader uses (the geometry helpers over validated points,
:func:`fill_boxes` and :func:`robust_extent`, live beside the map model in
:mod:`planner.io.obstacles`)."""

from __future__ import annotations

import numpy as np

from planner.errors import MapError
from planner.io.obstacles import MAX_FILLED_POINTS, Obstacles, fill_boxes, robust_extent

__all__ = ["MAX_ABS_COORDINATE", "MAX_FILLED_POINTS", "cloud", "fill_boxes", "finite_points",
           "no_return_mask", "robust_extent"]

# Coordinates beyond this (m) are corrupt values, not places: they would overflow every
# lattice index downstream.  Geodetic coordinates (UTM, ECEF) stay far below it.
MAX_ABS_COORDINATE = 1e9


def finite_points(values, name: str, dim: int = 3) -> tuple[np.ndarray, np.ndarray]:
    """Validate a raw (N, dim) coordinate array and split off its non-finite rows.

    Parameters
    ----------
    values : array_like, shape (N, dim)
        Numeric coordinates, metres (any real dtype).
    name : str
        File or argument name for messages.
    dim : int
        Expected number of columns.

    Returns
    -------
    points : ndarray, shape (N', dim), float64, C-contiguous
        The rows whose coordinates are all finite.
    keep : ndarray, shape (N,), bool
        Which input rows were kept (to filter per-point side arrays alike).

    Raises
    ------
    MapError
        Wrong shape, a non-numeric dtype, or a finite coordinate beyond
        :data:`MAX_ABS_COORDINATE`.
    """
    arr = np.asarray(values)
    if arr.dtype.kind not in "fiub":
        raise MapError(f"{name}: coordinates must be numeric, got dtype {arr.dtype}")
    if arr.size == 0:
        arr = arr.reshape(0, dim)
    if arr.ndim != 2 or arr.shape[1] != dim:
        raise MapError(f"{name}: points must have shape (N, {dim}), got {arr.shape}")
    with np.errstate(over="ignore", invalid="ignore"):  # float128/int64 -> float64 may overflow
        pts = np.ascontiguousarray(arr, dtype=np.float64)
    keep = np.isfinite(pts).all(axis=1)
    pts = pts if keep.all() else pts[keep]
    far = int((np.abs(pts) > MAX_ABS_COORDINATE).any(axis=1).sum())
    if far:
        raise MapError(f"{name}: {far} points have coordinates beyond {MAX_ABS_COORDINATE:g} m "
                       f"(corrupt values?)")
    return pts, keep


def no_return_mask(pts: np.ndarray) -> np.ndarray:
    """Rows exactly (0, 0, 0) in the sensor frame: scanners' encoding of 'no return'.

    A real return at exactly the sensor origin is physically impossible, so dropping these
    loses nothing."""
    return (pts == 0.0).all(axis=1)


def cloud(values, name: str, *, dim: int = 3, sensor_frame: bool = True,
          **extra) -> Obstacles:
    """Validate a cloud and wrap it as :class:`Obstacles`.

    Non-finite rows are dropped and counted (``dropped_nonfinite``), then, in a sensor-frame
    cloud, no-return ``(0, 0, 0)`` rows are dropped.  Nothing left is an error.

    Parameters
    ----------
    values : array_like, shape (N, dim)
        Coordinates, metres.
    name : str
        Source name for messages and ``Obstacles.source``.
    sensor_frame : bool
        True for a file's cloud (origin rows are no-returns); False for world-frame points
        (the origin is a place like any other).
    **extra
        Further :class:`Obstacles` fields (``resolution``, ``bounds``).

    Raises
    ------
    MapError
        Bad shape or dtype; no finite point that is not a no-return.
    """
    pts, keep = finite_points(values, name, dim)
    dropped = int(len(keep) - len(pts))
    if not len(keep):
        raise MapError(f"{name}: point cloud is empty (no points)")
    if not len(pts):
        raise MapError(f"{name}: every point ({dropped}) has NaN or infinite coordinates")
    zero = no_return_mask(pts) if sensor_frame else np.zeros(len(pts), dtype=bool)
    if zero.all():
        raise MapError(f"{name}: point cloud is empty (only no-return (0,0,0) points, "
                       f"{len(pts)})")
    if zero.any():
        pts = pts[~zero]
    extra.setdefault("resolution", None)
    extra.setdefault("bounds", None)
    return Obstacles(points=pts, boxes=np.zeros((0, dim)), box_size=0.0, source=name,
                     dropped_nonfinite=dropped, dim=dim, **extra)
