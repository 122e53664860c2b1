"""Exports read back by their ecosystems' own readers: a ROS 2 bag (rosbags), a TUM
trajectory, a CSV path, a PLY of cells (plyfile), an OctoMap .bt (the project's reader and,
where it installs, the octomap-python binding) and the Planner Arena database (sqlite3)."""

import json
import math
import sqlite3
from pathlib import Path

import numpy as np
import pytest

from planner.cli import main

OFFICE = ["office", "--cell-volume", "0.01", "--radius", "0.1"]
QUERY = ["--start", "1,1,1", "--goal", "7.9,5.4,1.1"]


@pytest.fixture(scope="module")
def planned(tmp_path_factory):
    """One path planned by the CLI, written as JSON, CSV, TUM and a ROS 2 bag."""
    d = tmp_path_factory.mktemp("plan")
    base = ["plan", *OFFICE, "--lattice", "cubic", *QUERY]
    assert main([*base, "--out", str(d / "p.json"), "--bag", str(d / "bag")]) == 0
    assert main([*base, "--out", str(d / "p.tum")]) == 0
    assert main([*base, "--out", str(d / "c.csv")]) == 0
    return d


def _waypoints(d: Path) -> np.ndarray:
    return np.array(json.loads((d / "p.json").read_text())["path"])


def test_bag_holds_a_nav_msgs_path_in_the_map_frame(planned):
    from rosbags.highlevel import AnyReader
    from rosbags.typesys import Stores, get_typestore

    with AnyReader([planned / "bag"], default_typestore=get_typestore(Stores.ROS2_HUMBLE)) as r:
        (conn,) = [c for c in r.connections if c.topic == "/plan"]
        assert conn.msgtype == "nav_msgs/msg/Path"
        msgs = [r.deserialize(raw, conn.msgtype) for _, _, raw in r.messages([conn])]
    (msg,) = msgs
    assert msg.header.frame_id == "map"
    xyz = np.array([[p.pose.position.x, p.pose.position.y, p.pose.position.z]
                    for p in msg.poses])
    np.testing.assert_allclose(xyz, _waypoints(planned), atol=1e-6)
    q = np.array([[p.pose.orientation.x, p.pose.orientation.y, p.pose.orientation.z,
                   p.pose.orientation.w] for p in msg.poses])
    np.testing.assert_allclose(np.linalg.norm(q, axis=1), 1.0)
    d = np.diff(xyz[:, :2], axis=0)
    moving = np.linalg.norm(d, axis=1) > 1e-9
    yaw = 2 * np.arctan2(q[:-1, 2], q[:-1, 3])
    heading = np.arctan2(d[:, 1], d[:, 0])
    np.testing.assert_allclose(np.cos(yaw - heading)[moving], 1.0, atol=1e-9)
    stamps = [p.header.stamp.sec * 10**9 + p.header.stamp.nanosec for p in msg.poses]
    assert all(b > a for a, b in zip(stamps, stamps[1:], strict=False))


def test_tum_rows_are_stamped_poses_of_the_path(planned):
    rows = np.loadtxt(planned / "p.tum")
    assert rows.shape[1] == 8
    np.testing.assert_allclose(rows[:, 1:4], _waypoints(planned), atol=1e-6)
    assert np.all(np.diff(rows[:, 0]) > 0)
    np.testing.assert_allclose(np.linalg.norm(rows[:, 4:], axis=1), 1.0)


def test_csv_has_one_header_row_no_comments_and_distinct_waypoints(planned):
    lines = (planned / "c.csv").read_text().splitlines()
    assert lines[0] == "x,y,z,yaw"
    assert not any(line.startswith("#") for line in lines)
    rows = np.array([[float(v) for v in line.split(",")] for line in lines[1:]])
    assert np.all(np.any(rows[1:, :3] != rows[:-1, :3], axis=1))
    side = json.loads((planned / "c.json").read_text())  # the metadata, beside it
    assert side["lattice"] == "cubic" and len(side["waypoints"]) == len(rows)


@pytest.fixture(scope="module")
def cubic_world(tmp_path_factory):
    from planner import build_world

    d = tmp_path_factory.mktemp("world")
    assert main(["world", *OFFICE, "--lattice", "cubic", "--out", str(d / "w.npz")]) == 0
    assert main(["world", str(d / "w.npz"), "--out", str(d / "w.ply")]) == 0
    assert main(["world", str(d / "w.npz"), "--out", str(d / "w.bt"), "--bt-cspace"]) == 0
    world = build_world(str(d / "w.npz"))
    return d, world, np.unique(world.blocked, axis=0)


def test_ply_holds_every_cell_centre_with_its_state(cubic_world):
    from plyfile import PlyData

    d, world, cells = cubic_world
    v = PlyData.read(str(d / "w.ply"))["vertex"]
    ijk = np.column_stack([v["i"], v["j"], v["k"]])
    assert set(np.unique(v["state"])) <= {1, 2}
    assert len(ijk) == world.n_blocked + world.n_unknown
    np.testing.assert_array_equal(np.unique(ijk[v["state"] == 1], axis=0), cells)
    xyz = np.column_stack([v["x"], v["y"], v["z"]])
    np.testing.assert_allclose(xyz, world.lattice.to_world(ijk))


def _leaf_cells(centres: np.ndarray, sizes: np.ndarray, h: float) -> np.ndarray:
    """Every cell of edge h inside the cube leaves (centre, edge), as integer indices of
    cell centres at k h."""
    out = []
    for c, s in zip(centres, sizes, strict=True):
        n = int(round(s / h))
        lo = np.rint(c / h - (n - 1) / 2).astype(np.int64)
        g = np.stack(np.meshgrid(*[np.arange(n)] * 3, indexing="ij"), -1).reshape(-1, 3)
        out.append(lo + g)
    return np.unique(np.concatenate(out), axis=0)


def test_cspace_octomap_reads_back_cell_for_cell(cubic_world):
    from planner.io import load_obstacles

    d, world, cells = cubic_world
    h = world.cell_size
    obst = load_obstacles(d / "w.bt")
    assert math.isclose(obst.resolution, h)
    # finest leaves are centred on k h exactly (the header's half-cell shift is applied)
    fine = obst.boxes[np.isclose(obst.box_sizes, h)] / h
    assert len(fine)
    np.testing.assert_allclose(fine, np.rint(fine), atol=1e-6)
    np.testing.assert_array_equal(_leaf_cells(obst.boxes, obst.box_sizes, h), cells)


def test_cspace_octomap_binding_sees_the_cells_half_a_cell_shifted(cubic_world):
    octomap = pytest.importorskip("octomap", reason="octomap-python does not install here")
    d, world, cells = cubic_world
    h = world.cell_size
    tree = octomap.OcTree(str(d / "w.bt").encode())
    assert math.isclose(tree.getResolution(), h)
    leaves = [(np.array(leaf.getCoordinate()), leaf.getSize()) for leaf in tree.begin_leafs()
              if tree.isNodeOccupied(leaf)]
    centres = np.array([c for c, _ in leaves]) - h / 2  # OctoMap's frame -> the world's
    sizes = np.array([s for _, s in leaves])
    np.testing.assert_array_equal(_leaf_cells(centres, sizes, h), cells)


def test_cspace_octomap_refuses_a_non_cubic_lattice(tmp_path, capsys):
    assert main(["world", *OFFICE, "--lattice", "bcc", "--out", str(tmp_path / "w.bt"),
                 "--bt-cspace"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "cubic" in err
    assert not (tmp_path / "w.bt").exists()


TINY = """
name = "tiny"
queries = 3
lattices = ["cubic", "fcc"]
neighbors = ["face", "full"]
methods = ["astar"]
[[maps]]
path = "office"
cell_volumes = [0.01]
radii = [0.1]
"""


@pytest.mark.slow
def test_every_suite_run_writes_the_planner_arena_database(tmp_path):
    (tmp_path / "tiny.toml").write_text(TINY)
    out = tmp_path / "out"
    assert main(["bench", str(tmp_path / "tiny.toml"), "--out", str(out), "--no-progress"]) == 0
    rows = [json.loads(x) for x in (out / "results.jsonl").read_text().splitlines() if x]
    con = sqlite3.connect(out / "planner_arena.db")
    try:
        (n_runs,) = con.execute("SELECT count(*) FROM runs").fetchone()
        (n_solved,) = con.execute("SELECT count(*) FROM runs WHERE solved").fetchone()
        names = {n for (n,) in con.execute("SELECT name FROM plannerConfigs")}
        (n_exp,) = con.execute("SELECT count(*) FROM experiments").fetchone()
        (checks,) = con.execute("SELECT sum(cell_checks) FROM runs").fetchone()
        tables = {n for (n,) in con.execute("SELECT name FROM sqlite_master WHERE type='table'")}
    finally:
        con.close()
    assert {"experiments", "plannerConfigs", "runs", "enums", "progress"} <= tables
    assert n_runs == len(rows)
    assert n_solved == sum(bool(r["found"]) for r in rows)
    assert names == {f"{r['lattice']}_{r['neighbors']}_{r['method']}" for r in rows}
    assert n_exp == len({(r["map"], r["cell_volume"], r["radius"], r.get("rotation"))
                         for r in rows})
    assert checks == sum(r["cell_checks"] for r in rows)
