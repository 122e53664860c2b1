"""KITTI velodyne scans (``.bin``): one lidar sweep as raw float32 records.

Each point is 16 bytes, little-endian float32 ``x, y, z, reflectance`` (metres in the
sensor frame; the KITTI odometry and raw datasets' ``velodyne/*.bin``), no header. The
reflectance is dropped; a file whose size is not a whole number of records is refused.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from planner.budget import require
from planner.errors import MapError
from planner.io._files import check_file
from planner.io.obstacles import Obstacles
from planner.io.validate import cloud

__all__ = ["RECORD", "read_kitti"]

RECORD = np.dtype([("x", "<f4"), ("y", "<f4"), ("z", "<f4"), ("reflectance", "<f4")])


def read_kitti(p: Path) -> Obstacles:
    """The points of a KITTI ``.bin`` scan (module docstring), float64 metres, sensor frame
    (no-return ``(0, 0, 0)`` rows and NaNs dropped, as for every scan)."""
    check_file(p)
    size = p.stat().st_size
    if size % RECORD.itemsize:
        raise MapError(f"{p.name}: a KITTI .bin scan is 16-byte float32 x, y, z, reflectance "
                       f"records; {size} bytes is not a whole number of them")
    require(size / RECORD.itemsize * 24 + size, f"reading {p.name}")
    rec = np.fromfile(p, dtype=RECORD)
    xyz = np.column_stack([rec["x"], rec["y"], rec["z"]]).astype(np.float64)
    return cloud(xyz, p.name)
