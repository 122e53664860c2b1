"""What was read is recorded and said: a bag's default topic and fixed frame are reported, path
files carry the topic, frame, max-clouds and the bag's SHA-256, a long bag read shows
progress, and a default cell volume that follows what was read says so."""

import json

import numpy as np
import pytest

from planner import progress
from planner.cli import main
from planner.fsutil import source_sha256
from planner.io import bag as bag_reader

PLAN = ["--lattice", "cubic", "--radius", "0.1", "--unknown", "free", "--start", "1,1,1",
        "--goal", "3,3,1"]


def _room(seed: int) -> np.ndarray:
    """Points on the walls of a 4 x 4 x 2 m box."""
    rng = np.random.default_rng(seed)
    u = rng.uniform(0, 1, (4000, 3)) * [4, 4, 2]
    side = rng.integers(0, 4, len(u))
    u[side == 0, 0], u[side == 1, 0] = 0, 4
    u[side == 2, 1], u[side == 3, 1] = 0, 4
    return u


@pytest.fixture(scope="module")
def bag(tmp_path_factory):
    """A rosbag2 with two PointCloud2 topics, /b (3 clouds, written first) and /a (1)."""
    pytest.importorskip("rosbags")
    from rosbags.rosbag2 import Writer
    from rosbags.typesys import Stores, get_typestore

    ts = get_typestore(Stores.ROS2_HUMBLE)
    T = ts.types

    def header(frame, sec):
        return T["std_msgs/msg/Header"](stamp=T["builtin_interfaces/msg/Time"](
            sec=sec, nanosec=0), frame_id=frame)

    def cloud(pts, sec):
        rec = np.ascontiguousarray(pts, dtype="<f4")
        field = T["sensor_msgs/msg/PointField"]
        return T["sensor_msgs/msg/PointCloud2"](
            header=header("lidar", sec), height=1, width=len(rec),
            fields=[field(name=n, offset=4 * i, datatype=7, count=1)
                    for i, n in enumerate("xyz")],
            is_bigendian=False, point_step=12, row_step=12 * len(rec),
            data=np.frombuffer(rec.tobytes(), dtype=np.uint8), is_dense=True)

    tf = T["geometry_msgs/msg/TransformStamped"](
        header=header("map", 1), child_frame_id="lidar",
        transform=T["geometry_msgs/msg/Transform"](
            translation=T["geometry_msgs/msg/Vector3"](x=2.0, y=2.0, z=1.0),
            rotation=T["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=0.0, w=1.0)))
    tfm = T["tf2_msgs/msg/TFMessage"](transforms=[tf])
    path = tmp_path_factory.mktemp("bag") / "room"
    with Writer(path, version=9) as w:
        c_tf = w.add_connection("/tf_static", "tf2_msgs/msg/TFMessage", typestore=ts)
        c_b = w.add_connection("/b", "sensor_msgs/msg/PointCloud2", typestore=ts)
        c_a = w.add_connection("/a", "sensor_msgs/msg/PointCloud2", typestore=ts)
        w.write(c_tf, 1, ts.serialize_cdr(tfm, tfm.__msgtype__))
        for i in range(3):  # the sensor sits at (2, 2, 1) in map: points in its frame
            msg = cloud(_room(i) - [2, 2, 1], 2 + i)
            w.write(c_b, (2 + i) * 10**9, ts.serialize_cdr(msg, msg.__msgtype__))
        msg = cloud(_room(9) - [2, 2, 1], 2)
        w.write(c_a, 2 * 10**9, ts.serialize_cdr(msg, msg.__msgtype__))
    return path


def test_the_default_topic_frame_and_clouds_are_reported_and_recorded(bag, tmp_path, capsys,
                                                                      monkeypatch):
    from planner.world import build

    monkeypatch.setattr(build, "DEFAULT_CELLS", 50_000)  # the rule, on a small world
    out = tmp_path / "p.json"
    assert main(["plan", str(bag), *PLAN, "--max-clouds", "2", "--out", str(out)]) == 0
    err = capsys.readouterr().err
    assert ("topic /b (the first of 2 PointCloud2 topics: /a, /b; --topic picks another)"
            in err)
    assert "fixed frame 'map' (the root of the tf tree" in err
    assert "2 of 3 clouds (--max-clouds 2)" in err
    assert "note: cell volume" in err and "(~50,000 cells): it changes with --max-clouds" in err
    rec = json.loads(out.read_text())
    assert rec["read"] == {"topic": "/b", "fixed_frame": "map", "max_clouds": 2, "clouds": 2,
                           "clouds_in_topic": 3, "local_frame_offset": None}
    assert rec["map"] == "room" and rec["map_sha256"] == source_sha256(bag)
    assert len(rec["map_sha256"]) == 64


def test_given_options_are_not_called_defaults(bag, tmp_path, capsys):
    out = tmp_path / "p.json"
    assert main(["plan", str(bag), *PLAN, "--topic", "/a", "--fixed-frame", "map",
                 "--cell-volume", "0.001", "--out", str(out)]) == 0
    err = capsys.readouterr().err
    assert "topic /a, fixed frame 'map', 1 of 1 clouds" in err
    assert "first of" not in err and "note: cell volume" not in err
    rec = json.loads(out.read_text())
    assert rec["read"]["topic"] == "/a" and rec["read"]["max_clouds"] is None


def test_a_plain_file_records_no_topic_and_its_sha256(tmp_path):
    np.save(tmp_path / "room.npy", _room(0))
    out = tmp_path / "p.json"
    assert main(["plan", str(tmp_path / "room.npy"), *PLAN, "--cell-volume", "0.001",
                 "--out", str(out)]) == 0
    rec = json.loads(out.read_text())
    assert rec["read"]["topic"] is None and rec["map_sha256"] == source_sha256(
        tmp_path / "room.npy")


def test_a_folders_sha256_changes_with_any_file(bag, tmp_path):
    import shutil

    copy = tmp_path / "copy"
    shutil.copytree(bag, copy)
    assert source_sha256(copy) == source_sha256(bag)
    (copy / "extra.txt").write_text("x")
    assert source_sha256(copy) != source_sha256(bag)


def test_a_long_bag_read_shows_progress(bag, tmp_path, capsys, monkeypatch):
    class Eager(progress.Progress):  # as after the first 5 s of a long read
        def __init__(self, *args, **kw):
            super().__init__(*args, **{**kw, "quiet": 0.0})

    monkeypatch.setattr(bag_reader, "Progress", Eager)
    assert main(["world", str(bag), "--radius", "0.1", "--cell-volume", "0.001", "--out",
                 str(tmp_path / "w.npz")]) == 0
    err = capsys.readouterr().err
    assert "progress 100%: reading room /b 3/3 clouds" in err
