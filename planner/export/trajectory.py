"""Poses along a path, and the TUM trajectory format.

A path has no clock: pose ``i`` is stamped with the arc length to it divided by a nominal
speed (``speed`` m/s, 1 by default), so stamps strictly increase and differences are travel
times. Orientation is the heading (:func:`planner.path.headings`: yaw of the segment leaving
the waypoint, about +z, a sub-millimetre hop taking the next segment's; the last waypoint
keeps the one before) as a unit quaternion ``(x, y, z, w) = (0, 0, sin(yaw/2),
cos(yaw/2))``. Consecutive identical waypoints are merged first (a start at a cell centre
would otherwise appear twice).

TUM (the TUM RGB-D benchmark's trajectory files, read by evo and most SLAM tools): one line
per pose, ``timestamp tx ty tz qx qy qz qw``, space separated, seconds and metres.
"""

from __future__ import annotations

import os

import numpy as np

from planner.errors import PlanError
from planner.fsutil import atomic_path
from planner.path import headings

__all__ = ["distinct_waypoints", "path_poses", "write_tum"]


def distinct_waypoints(path) -> np.ndarray:
    """(K', 3) the waypoints of ``path`` (K, 3) or (K, 2) (metres; a 2D path gets z = 0) with
    consecutive duplicates (equal to 1 um) merged."""
    p = np.asarray(path, dtype=float)
    if p.ndim != 2 or p.shape[1] not in (2, 3) or not len(p) or not np.isfinite(p).all():
        raise PlanError(f"a path must be a non-empty (K, 3) array of finite metres, got shape "
                        f"{p.shape}")
    if p.shape[1] == 2:
        p = np.column_stack([p, np.zeros(len(p))])
    r = np.round(p, 6)
    keep = np.ones(len(p), dtype=bool)
    keep[1:] = np.any(r[1:] != r[:-1], axis=1)
    return p[keep]


def path_poses(path, speed: float = 1.0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Stamps (K,) s, positions (K, 3) m and quaternions (K, 4) ``x, y, z, w`` of ``path``."""
    if not speed > 0:
        raise PlanError(f"speed must be positive, got {speed!r}")
    p = distinct_waypoints(path)
    seg = np.linalg.norm(np.diff(p, axis=0), axis=1)
    t = np.concatenate([[0.0], np.cumsum(seg)]) / speed
    yaw = headings(p)  # the path files' headings
    q = np.column_stack([np.zeros(len(p)), np.zeros(len(p)), np.sin(yaw / 2), np.cos(yaw / 2)])
    return t, p, q


def write_tum(out: str | os.PathLike, path, speed: float = 1.0) -> None:
    """Write ``path`` (K, 3) metres as a TUM trajectory (module docstring), atomically."""
    t, p, q = path_poses(path, speed)
    rows = np.column_stack([t, p, q])
    with atomic_path(out) as tmp:
        np.savetxt(tmp, rows, fmt="%.9f", delimiter=" ")
