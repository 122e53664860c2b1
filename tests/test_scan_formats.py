"""Common scan formats: a KITTI velodyne ``.bin`` (float32 x, y, z, reflectance records)
and ``.npy`` arrays with columns after x, y, z are read as clouds and planned on."""

from __future__ import annotations

import json

import numpy as np
import pytest

from planner.bench.metrics import Clearance
from planner.cli import main
from planner.errors import MapError
from planner.io import load_obstacles, load_points
from planner.maps import map_path

SENSOR = np.array([10.0, 6.0, 1.5])  # the office seen from its corridor's middle


def _scan() -> np.ndarray:
    """(N, 4) float32 x, y, z, reflectance: the office in a sensor frame at :data:`SENSOR`,
    with two no-return rows (0, 0, 0) as a lidar driver writes them."""
    pts = (load_points(map_path("office")) - SENSOR).astype(np.float32)
    refl = np.linspace(0, 1, len(pts), dtype=np.float32)
    rows = np.column_stack([pts, refl])
    return np.concatenate([rows[:100], np.zeros((2, 4), np.float32), rows[100:]])


def test_kitti_bin_is_a_scan(tmp_path):
    scan = _scan()
    scan.tofile(tmp_path / "000042.bin")
    obst = load_obstacles(tmp_path / "000042.bin")
    want = scan[np.any(scan[:, :3] != 0, axis=1), :3].astype(np.float64)
    np.testing.assert_array_equal(obst.points, want)
    assert obst.unknown_default == "free"
    (tmp_path / "cut.bin").write_bytes(scan.tobytes()[:-6])
    with pytest.raises(MapError, match="16-byte float32 x, y, z, reflectance"):
        load_obstacles(tmp_path / "cut.bin")


def test_npy_with_extra_columns_uses_the_first_three(tmp_path):
    scan = _scan()
    np.save(tmp_path / "scan.npy", scan.astype(np.float64))
    np.testing.assert_array_equal(load_points(tmp_path / "scan.npy"),
                                  scan[np.any(scan[:, :3] != 0, axis=1), :3])
    np.save(tmp_path / "flat.npy", np.zeros((4, 2)))
    with pytest.raises(MapError, match=r"\(N, 3\)"):
        load_obstacles(tmp_path / "flat.npy")


def test_a_kitti_scan_plans_end_to_end(tmp_path):
    scan = _scan()
    scan.tofile(tmp_path / "scan.bin")
    out = tmp_path / "p.json"
    # along the corridor, 1.5 m above the floor (the sensor's height): from room to room
    assert main(["plan", str(tmp_path / "scan.bin"), "--radius", "0.25", "--cell-volume",
                 "0.004", "--start", "-8,0,0", "--goal", "8,0,0", "--out", str(out)]) == 0
    path = np.array(json.loads(out.read_text())["path"])
    assert path[0].tolist() == [-8, 0, 0] and path[-1].tolist() == [8, 0, 0]
    raw = scan[np.any(scan[:, :3] != 0, axis=1), :3].astype(np.float64)
    assert Clearance(raw, np.zeros((0, 3))).of_path(path, 0.02) >= 0.25
