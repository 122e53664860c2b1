"""A single scan is safe by default: with its sensor origin (``--origin``, or the scan's own
PCD VIEWPOINT) free space is ray-cast and space the sensor never saw is blocked; without one,
the printed result, ``--json`` and the path file say so.

The scene: a 10 x 4 x 3 m room split at x = 2 m by a floor-to-ceiling wall with a door
(y 1.7-2.3 m, up to z = 2 m). A lidar at (1, 2, 1) m with a +-15 degree vertical field of view
sees only a band of that wall (z ~0.5-1.5 m), so the cloud shows a low wall one could fly over,
a shorter way to the goal than the door.
"""

import json

import numpy as np
import pytest

from planner.cli import main
from planner.errors import MapError
from planner.io import load_obstacles, with_origin

SENSOR = np.array([1.0, 2.0, 1.0])
# the true scene: axis-aligned solid boxes [lo, hi] (m)
BOXES = np.array([
    [[-0.2, -0.2, -0.2], [10.2, 4.2, 0.0]],  # floor
    [[-0.2, -0.2, 3.0], [10.2, 4.2, 3.2]],  # ceiling
    [[-0.2, -0.2, -0.2], [0.0, 4.2, 3.2]], [[10.0, -0.2, -0.2], [10.2, 4.2, 3.2]],  # x walls
    [[-0.2, -0.2, -0.2], [10.2, 0.0, 3.2]], [[-0.2, 4.0, -0.2], [10.2, 4.2, 3.2]],  # y walls
    [[2.0, -0.2, -0.2], [2.1, 1.7, 3.2]], [[2.0, 2.3, -0.2], [2.1, 4.2, 3.2]],  # the wall
    [[2.0, 1.7, 2.0], [2.1, 2.3, 3.2]],  # above the door
])
RADIUS = 0.05
START, GOAL = "1.5,0.5,1", "9,0.5,1"
BASE = ["--lattice", "fcc", "--cell-volume", "0.0005", "--radius", str(RADIUS), "--start",
        START, "--goal", GOAL]


def _scan() -> np.ndarray:
    """The lidar's returns: 0.25 degree steps, 360 x +-15 degrees, first box hit per ray."""
    az, el = np.meshgrid(np.radians(np.arange(0, 360, 0.25)),
                         np.radians(np.arange(-15, 15.01, 0.25)))
    d = np.stack([np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)], -1)
    d = d.reshape(-1, 3)
    with np.errstate(divide="ignore", invalid="ignore"):
        t0 = (BOXES[None, :, 0] - SENSOR) / d[:, None]
        t1 = (BOXES[None, :, 1] - SENSOR) / d[:, None]
    near = np.nanmax(np.minimum(t0, t1), axis=2)
    far = np.nanmin(np.maximum(t0, t1), axis=2)
    t = np.where((far >= near) & (far > 0), np.maximum(near, 0), np.inf).min(axis=1)
    return SENSOR + t[:, None] * d


def _clearance(path: np.ndarray) -> float:
    """Least distance (m) from the path (polyline, sampled every 5 mm) to the true boxes."""
    seg = [a + np.linspace(0, 1, max(2, int(np.linalg.norm(b - a) / 0.005)))[:, None] * (b - a)
           for a, b in zip(path[:-1], path[1:], strict=True)]
    p = np.concatenate(seg)
    gap = np.maximum(np.maximum(BOXES[None, :, 0] - p[:, None], p[:, None] - BOXES[None, :, 1]),
                     0)
    return float(np.linalg.norm(gap, axis=2).min())


@pytest.fixture(scope="module")
def scan(tmp_path_factory):
    d = tmp_path_factory.mktemp("scan")
    pts = _scan()
    assert np.isfinite(pts).all()
    np.save(d / "scan.npy", pts)
    head = ["# .PCD v0.7", "VERSION 0.7", "FIELDS x y z", "SIZE 4 4 4", "TYPE F F F",
            "COUNT 1 1 1", f"WIDTH {len(pts)}", "HEIGHT 1",
            "VIEWPOINT 1 2 1 1 0 0 0", f"POINTS {len(pts)}", "DATA ascii"]
    (d / "scan.pcd").write_text("\n".join(head + [f"{x:.9g} {y:.9g} {z:.9g}"
                                                  for x, y, z in pts.astype(np.float32)]) + "\n")
    return d


def _plan(capsys, *args):
    code = main(["plan", *args, *BASE])
    return code, capsys.readouterr().out


def test_without_an_origin_the_report_warns_and_the_path_flies_over_the_unseen_wall(
        scan, capsys, tmp_path):
    code, out = _plan(capsys, str(scan / "scan.npy"), "--out", str(tmp_path / "p.json"))
    assert code == 0
    line, warning = out.strip().splitlines()
    assert warning.startswith("WARNING: no sensor origin") and "--origin" in warning
    rec = json.loads((tmp_path / "p.json").read_text())
    assert rec["warnings"] and rec["warnings"][0].startswith("no sensor origin")
    path = np.array(rec["path"])
    assert _clearance(path) < RADIUS  # what the warning is about: it crosses the true wall
    code, out = _plan(capsys, str(scan / "scan.npy"), "--json")
    assert json.loads(out)["warnings"] == rec["warnings"]


@pytest.mark.parametrize("how", ["origin", "viewpoint"])
def test_with_its_origin_the_path_keeps_to_seen_space(scan, capsys, tmp_path, how):
    args = ([str(scan / "scan.npy"), "--origin", "1,2,1"] if how == "origin" else
            [str(scan / "scan.pcd")])
    code, out = _plan(capsys, *args, "--out", str(tmp_path / "p.json"))
    assert code == 0, out
    assert "WARNING" not in out
    rec = json.loads((tmp_path / "p.json").read_text())
    assert rec["unknown_policy"] == "blocked" and rec["warnings"] == []
    assert rec["unknown_cells"] == 0
    path = np.array(rec["path"])
    assert _clearance(path) >= RADIUS - 1e-6  # the true scene, every point of the path
    assert np.all(path[:, 2] < 2.0)  # through the door, not over the wall


def test_pcl_default_viewpoint_says_nothing_and_an_origin_is_refused_where_it_cannot_apply(
        scan, tmp_path, capsys):
    text = (scan / "scan.pcd").read_text().replace("VIEWPOINT 1 2 1 1 0 0 0",
                                                  "VIEWPOINT 0 0 0 1 0 0 0")
    (tmp_path / "d.pcd").write_text(text)
    assert load_obstacles(tmp_path / "d.pcd").origins is None
    (tmp_path / "b.pcd").write_text(text.replace("VIEWPOINT 0 0 0 1 0 0 0", "VIEWPOINT 1 2"))
    with pytest.raises(MapError, match="VIEWPOINT"):
        load_obstacles(tmp_path / "b.pcd")
    with pytest.raises(MapError, match="single point cloud"):
        with_origin(load_obstacles(scan / "scan.pcd"), [0, 0, 0])
    assert main(["plan", "office", "--origin", "1,2", *BASE[:-4], "--start", "1,1,1",
                 "--goal", "2,2,1"]) == 2
    assert len(capsys.readouterr().err.strip().splitlines()) == 1


def test_the_readme_pose_list_reads_as_documented(tmp_path):
    """The pose-list block of the README, with two small scans beside it."""
    from pathlib import Path

    readme = (Path(__file__).resolve().parents[1] / "README.md").read_text()
    block = readme.split("```text\n# scan ")[1].split("```")[0]
    (tmp_path / "scans").mkdir()
    for name in ("000", "001"):
        np.save(tmp_path / "scans" / f"{name}.npy", np.array([[1.0, 0, 0], [0, 1, 0]]))
    (tmp_path / "poses.txt").write_text("# scan " + block.replace(".pcd", ".npy"))
    obst = load_obstacles(tmp_path / "poses.txt", "poses")
    np.testing.assert_allclose(obst.origins, [[0, 0, 1.2], [2, 0, 1.2]])
    # the second scan is turned 45 degrees about z: its (1, 0, 0) lands at 2 + (0.707, 0.707)
    np.testing.assert_allclose(obst.points[2], [2 + 0.5 ** 0.5, 0.5 ** 0.5, 1.2], atol=1e-6)
    assert obst.unknown_default == "blocked"
