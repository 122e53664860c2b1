"""Path files written by ``planner plan --out``: JSON (everything) or CSV (waypoints only,
with the JSON beside it as its sidecar).

Both carry the map (file name and sha256: of the file, or of a rosbag2 folder's files), frame,
what was read (``read``: a bag's topic, fixed frame, ``max_clouds`` and clouds read; the
world's local-frame offset when it has one), lattice, cell volume (area for
a 2D map), radius, unknown policy, start, goal, raw and smoothed length, the number of path
cells meeting unknown space, ``warnings`` (:func:`planner.world.caveats.world_warnings`: e.g. a
cloud without a sensor origin), and per distinct waypoint x, y, z and heading (yaw in the x-y plane,
radians, of the segment leaving the waypoint, :func:`headings`; the last repeats the one
before). Numbers are
rounded to 1 um / 1 urad so files carry no float noise.
"""

from __future__ import annotations

import csv
import json
import math
from pathlib import Path

import numpy as np

from planner.errors import PlanError
from planner.fsutil import atomic_path, source_sha256

__all__ = ["MIN_HEADING_MOVE", "SHORT_PATH", "headings", "path_length", "path_record",
           "read_record", "rows_length", "write_path"]

_DIGITS = 6


#: shortest move in the x-y plane (m) with a heading of its own: a shorter segment (a
#: sub-millimetre hop, a vertical move) takes the heading of the next longer one
MIN_HEADING_MOVE = 1e-3


def headings(path: np.ndarray) -> np.ndarray:
    """(K,) yaw of each waypoint (rad, ``atan2(dy, dx)``): the travel direction of the
    segment leaving it; the last waypoint keeps the one before. A segment shorter than
    :data:`MIN_HEADING_MOVE` in the x-y plane has no direction of its own (rounding decides
    it): it takes the next longer segment's heading (the last such ones, the previous).
    0 for K < 2 or a path that never moves that far.

    >>> np.round(headings(np.array([[0.0, 0], [1e-4, -2e-4], [1, 0], [2, 0], [2, 1]])), 3)
    array([0.   , 0.   , 0.   , 1.571, 1.571])
    """
    p = np.asarray(path, dtype=float)
    if len(p) < 2:
        return np.zeros(len(p))
    d = np.diff(p[:, :2], axis=0)
    yaw = np.arctan2(d[:, 1], d[:, 0])
    moves = np.hypot(d[:, 0], d[:, 1]) >= MIN_HEADING_MOVE
    if not moves.any():
        return np.zeros(len(p))
    idx = np.flatnonzero(moves)
    nxt = np.searchsorted(idx, np.arange(len(d)))  # the next moving segment, if any
    yaw = yaw[idx[np.minimum(nxt, len(idx) - 1)]]
    return np.append(yaw, yaw[-1])


def _r(x):
    return None if x is None or not math.isfinite(x) else round(float(x), _DIGITS)


def read_record(world) -> dict:
    """What was read to make ``world``: a bag's topic, fixed frame and clouds (``None``
    where the map is a single file read whole), and the offset (m) of the world's local
    frame from the input's when it has one (``None`` when the world plans in the map's own
    frame; the path record's ``local_offset`` gives it either way)."""
    obst = getattr(world, "obstacles", None)
    read = dict(getattr(obst, "read", None) or {})
    offset = np.asarray(getattr(world, "offset", np.zeros(3)), dtype=float)[:world.dim]
    return {"topic": read.get("topic"), "fixed_frame": read.get("fixed_frame"),
            "max_clouds": read.get("max_clouds"), "clouds": read.get("clouds"),
            "clouds_in_topic": read.get("clouds_in_topic"),
            "local_frame_offset": offset.tolist() if offset.any() else None}


def path_record(res, world, start, goal) -> dict:
    """The metadata and waypoints of a :class:`planner.PlanResult` as a JSON-ready dict."""
    from planner.world.caveats import world_warnings  # lazy: planner.world loads numba
    src = world.source or ""
    raw = res.extra.get("raw_length", res.length)
    smooth = res.extra.get("smoothed_length")
    path = np.asarray(res.path, dtype=float)
    digest = getattr(world, "source_sha256", "") or ""
    src_file = getattr(world, "source_file", "")
    if not digest and src_file and Path(src_file).exists():
        digest = source_sha256(src_file)  # a file, or a rosbag2 folder
    if len(path) > 1:  # a start at a cell centre would appear twice
        r = np.round(path, _DIGITS)
        path = path[np.concatenate([[True], np.any(r[1:] != r[:-1], axis=1)])]
    yaw = headings(path)
    pts = path[:, :2] if world.dim == 2 else path
    return {
        "map": Path(src).name if src else None,
        "map_sha256": digest or None,
        "frame": getattr(world.obstacles, "frame", None) or "map",
        "read": read_record(world),
        # the world's local frame in the map's (m): planned in map - offset, all points here
        # are the map's
        "local_offset": world.offset[:world.dim].tolist(),
        "dim": world.dim,
        "lattice": res.lattice, "cell_volume": _r(res.cell_volume),
        "cell_volume_unit": "m^2" if world.dim == 2 else "m^3",
        "radius": _r(world.radius), "unknown_policy": world.unknown_policy,
        "method": res.method, "neighbors": res.neighbors,
        "start": [_r(v) for v in np.asarray(start, dtype=float)],
        "goal": [_r(v) for v in np.asarray(goal, dtype=float)],
        "found": res.found, "status": res.status, "reason": res.reason,
        "raw_length": _r(raw), "smoothed_length": _r(smooth),
        "unknown_cells": int(res.unknown_cells), "guarantee": res.guarantee,
        "warnings": world_warnings(world),
        "path": [[_r(v) for v in p] for p in path],
        "waypoints": [[_r(v) for v in p] + [_r(h)] for p, h in zip(pts, yaw, strict=True)],
        "waypoint_columns": (["x", "y"] if world.dim == 2 else ["x", "y", "z"]) + ["yaw"],
    }


def write_path(path: str, res, world, start, goal) -> None:
    """Write the path as JSON (:func:`path_record`) or CSV (one header row, then
    ``x,y[,z],yaw`` rows; the metadata goes to the JSON sidecar beside it, the same name
    with ``.json``), atomically."""
    suffix = Path(path).suffix.lower()
    if suffix not in (".csv", ".json"):
        raise PlanError(f"{path}: unknown output format {suffix!r}; use .csv or .json")
    rec = path_record(res, world, start, goal)
    with atomic_path(path) as tmp:
        if suffix == ".json":
            tmp.write_text(json.dumps(rec, indent=1))
            return
        with open(tmp, "w", newline="") as f:
            w = csv.writer(f)
            w.writerow(rec["waypoint_columns"])
            w.writerows(rec["waypoints"])
    if suffix == ".csv":
        with atomic_path(Path(path).with_suffix(".json")) as tmp:
            tmp.write_text(json.dumps(rec, indent=1))


#: longest 3D path (points) :func:`path_length` measures with :func:`rows_length`: below 8
#: segments numpy sums the segment lengths in order, so that gives the same float with a few
#: numpy calls fewer
SHORT_PATH = 8
_F8 = np.dtype(np.float64)  # compared by identity: a float64 array's own dtype


def rows_length(rows: list) -> float:
    """:func:`path_length` (m) of a path of at most :data:`SHORT_PATH` points given as
    ``(x, y, z)`` rows of Python floats (``ndarray.tolist()``), in numpy's order of
    operations (each segment's squares summed left to right, then the segments): the
    identical float, without numpy's per-call cost. A caller that has already checked its
    array uses it instead of :func:`path_length`'s own checks."""
    tot = 0.0
    a0, a1, a2 = rows[0]
    for b0, b1, b2 in rows[1:]:
        d0, d1, d2 = b0 - a0, b1 - a1, b2 - a2
        tot += math.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
        a0, a1, a2 = b0, b1, b2
    return tot


def path_length(path: np.ndarray, empty: float = math.nan) -> float:
    """Length (m) of a polyline ``path`` of shape (K, d); ``empty`` when K < 2.

    >>> path_length(np.array([[0.0, 0, 0], [3, 4, 0], [3, 4, 1]]))
    6.0
    >>> path_length(np.zeros((1, 3)), empty=0.0)
    0.0
    """
    if (type(path) is np.ndarray and 2 <= len(path) <= SHORT_PATH and path.ndim == 2
            and path.shape[1] == 3 and path.dtype is _F8):
        return rows_length(path.tolist())
    p = np.asarray(path, dtype=float)
    if len(p) < 2:
        return float(empty)
    d = p[1:] - p[:-1]
    # np.linalg.norm's own arithmetic (sqrt of the row sums of squares) without its
    # dispatch: every plan() measures its path
    return float(np.sqrt(np.add.reduce(d * d, axis=1)).sum())
