"""Posed scans: sensor-frame clouds with sensor-to-world poses, merged into one world cloud.

The sensor origin of each scan (its pose's translation) is kept, so free space can be
ray-cast from it to every point of the scan.
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from planner.errors import MapError
from planner.io._files import read_text
from planner.io.obstacles import Obstacles
from planner.io.validate import finite_points, no_return_mask


def merge_scans(scans: list[np.ndarray], poses) -> np.ndarray:
    """Transform sensor-frame scans into the world frame and concatenate them.

    Parameters
    ----------
    scans : list of ndarray, each shape (N_i, 3)
        Points in each scan's sensor frame, metres.  Rows exactly ``(0, 0, 0)`` are no-returns
        and rows with a NaN / inf coordinate are missing returns; both are dropped before
        transforming.
    poses : sequence of ndarray shape (4, 4), or ndarray shape (K, 4, 4)
        Sensor-to-world homogeneous transforms, one per scan (``p_world = R @ p + t``).

    Returns
    -------
    ndarray, shape (sum N_i, 3), float64
        World-frame points, metres, in scan order.

    Raises
    ------
    MapError
        Count mismatch, a pose that is not a finite rigid transform, bad scan shapes, or no
        points at all.
    """
    return merge_posed(scans, poses, "merge_scans").points


def merge_posed(scans: list[np.ndarray], poses, name: str) -> Obstacles:
    """:func:`merge_scans` keeping sensor origins and the count of dropped non-finite points."""
    poses_arr = np.asarray(poses, dtype=np.float64)
    if poses_arr.ndim != 3 or poses_arr.shape[1:] != (4, 4):
        raise MapError(f"{name}: poses must be 4x4 matrices, got shape {poses_arr.shape}")
    if len(scans) != len(poses_arr):
        raise MapError(f"{name}: {len(scans)} scans but {len(poses_arr)} poses")
    out, owner, dropped = [], [], 0
    for i, (scan, pose) in enumerate(zip(scans, poses_arr, strict=True)):
        check_pose(pose, f"{name}: pose {i}")
        pts, keep = finite_points(scan, f"{name}: scan {i}")
        dropped += len(keep) - len(pts)
        pts = pts[~no_return_mask(pts)]
        out.append(pts @ pose[:3, :3].T + pose[:3, 3])
        owner.append(np.full(len(pts), i, dtype=np.int64))
    merged = np.concatenate(out) if out else np.zeros((0, 3))
    if not len(merged):
        raise MapError(f"{name}: no points to merge")
    return Obstacles(points=merged, boxes=np.zeros((0, 3)), box_size=0.0, bounds=None,
                     resolution=None, source=name, origins=poses_arr[:, :3, 3],
                     point_origin=np.concatenate(owner), dropped_nonfinite=dropped)


def read_pose_list(p: Path, load_obstacles: Callable[..., Obstacles]) -> Obstacles:
    """:func:`planner.io.load_posed_scans` as :class:`Obstacles` with the scans' sensor
    origins; each scan is read by ``load_obstacles`` (the dispatcher of
    :mod:`planner.io.load`, passed in: a pose list's scans are maps of any format)."""

    text = read_text(p)
    scans, poses, dropped = [], [], 0
    for lineno, raw in enumerate(text.splitlines(), start=1):
        line = raw.split("#", 1)[0].strip()
        if not line:
            continue
        tokens = [t for t in re.split(r"[\s,]+", line) if t]
        where = f"{p.name}:{lineno}"
        try:
            nums = [float(t) for t in tokens[1:]]
        except ValueError:
            raise MapError(f"{where}: pose values must be numbers") from None
        if len(nums) == 16:
            pose = np.array(nums).reshape(4, 4)
        elif len(nums) == 7:
            pose = pose_from_quaternion(nums, where)
        else:
            raise MapError(f"{where}: expected a scan path then 16 (4x4) or 7 (x y z qx qy qz "
                           f"qw) numbers, got {len(nums)}")
        check_pose(pose, where)
        scan_path = Path(tokens[0])
        if not scan_path.is_absolute():
            scan_path = p.parent / scan_path
        if scan_path.resolve() == p.resolve():
            raise MapError(f"{where}: a pose list cannot list itself as a scan")
        scan = load_obstacles(scan_path)
        scans.append(scan.points if len(scan.points) else scan.box_centre_points())
        dropped += scan.dropped_nonfinite
        poses.append(pose)
    if not scans:
        raise MapError(f"{p.name}: lists no scans")
    merged = merge_posed(scans, poses, p.name)
    return Obstacles(points=merged.points, boxes=merged.boxes, box_size=0.0, bounds=None,
                     resolution=None, source=p.name, origins=merged.origins,
                     point_origin=merged.point_origin,
                     dropped_nonfinite=dropped + merged.dropped_nonfinite)


def pose_from_quaternion(nums: list[float], where: str) -> np.ndarray:
    """4x4 pose from ``x y z qx qy qz qw`` (the quaternion is normalised)."""
    x, y, z, qx, qy, qz, qw = nums
    n = math.sqrt(qx * qx + qy * qy + qz * qz + qw * qw)
    if not math.isfinite(n) or n < 1e-12:
        raise MapError(f"{where}: quaternion has zero or non-finite norm")
    pose = np.eye(4)
    pose[:3, :3] = Rotation.from_quat([qx, qy, qz, qw]).as_matrix()
    pose[:3, 3] = (x, y, z)
    return pose


def check_pose(pose: np.ndarray, where: str) -> None:
    """MapError unless ``pose`` is a finite proper rigid transform."""
    if not np.isfinite(pose).all():
        raise MapError(f"{where}: pose contains NaN or infinite values")
    if not np.allclose(pose[3], (0.0, 0.0, 0.0, 1.0), atol=1e-9):
        raise MapError(f"{where}: pose last row must be 0 0 0 1")
    r = pose[:3, :3]
    # Loose tolerance: poses saved with 6 significant digits are still accepted.
    if not np.allclose(r @ r.T, np.eye(3), atol=1e-3) or np.linalg.det(r) < 0:
        raise MapError(f"{where}: pose rotation is not a proper rotation matrix")


def with_origin(obst: Obstacles, origin) -> Obstacles:
    """A single scan with its sensor origin: free space is then ray-cast from ``origin`` to
    every point and the rest is unknown (blocked by default), so a path cannot cross space
    the sensor never saw (a wall above a lidar's vertical field of view).

    Parameters
    ----------
    obst : Obstacles
        A 3D point cloud that records no free space (no boxes, no origins).
    origin : array_like, shape (3,)
        Sensor position in the cloud's frame (m).

    Returns
    -------
    Obstacles
        ``obst`` with ``origins`` = [origin], every point from it, ``unknown_default``
        ``"blocked"``.

    Raises
    ------
    MapError
        A 2D map, a map of boxes or one that already records free space or origins, or a
        non-finite origin.
    """
    o = np.asarray(origin, dtype=np.float64).reshape(-1)
    if o.shape != (3,) or not np.isfinite(o).all():
        raise MapError(f"{obst.source}: a sensor origin is three finite numbers x,y,z")
    if obst.dim != 3 or len(obst.boxes) or obst.has_free_space:
        what = ("a 2D map" if obst.dim != 3 else "records its free space already"
                if obst.has_free_space else "is a map of boxes, not a scan")
        raise MapError(f"{obst.source}: {what}; a sensor origin applies to a single point "
                       f"cloud only")
    from dataclasses import replace

    return replace(obst, origins=o[None, :], point_origin=np.zeros(len(obst.points), np.int64),
                   unknown_default=None)
