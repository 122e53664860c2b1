"""Robot formats (the ``robot`` extra): ROS 1 / ROS 2 bags, LAS / LAZ, E57.

Every file is written by the format's own library (rosbags writers, laspy, pye57) and read
back through :func:`planner.io.load_obstacles`; each test skips when its library is absent.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from planner.errors import MapError
from planner.io import load_obstacles, load_points

# Sensor-frame points of every cloud: a NaN row (organized clouds' missing return) and a
# no-return (0, 0, 0) row that the reader must drop.
SCAN = np.array([[1.0, 0.0, 0.0], [0.0, 2.0, 0.0], [np.nan, np.nan, np.nan], [0.0, 0.0, 0.0],
                 [1.0, 1.0, 0.5]], dtype=np.float32)


def _yaw_quat(yaw: float) -> tuple[float, float, float, float]:
    return (0.0, 0.0, math.sin(yaw / 2), math.cos(yaw / 2))


def _pose(x: float, yaw: float) -> np.ndarray:
    c, s = math.cos(yaw), math.sin(yaw)
    return np.array([[c, -s, 0, x], [s, c, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1.0]])


# odom -> base_link moves along x and turns: at time t, x = t, yaw = 0.5 t (sampled each second).
# base_link -> lidar is static: 0.2 m up.
CLOUD_TIMES = [0.5, 1.0, 2.25]
TF_TIMES = [0.0, 1.0, 2.0, 3.0]


def _expected(t: float) -> tuple[np.ndarray, np.ndarray]:
    """World points and sensor origin of the cloud stamped ``t`` (interpolation is exact for
    x; for the yaw, slerp between samples of one axis is linear in the angle)."""
    lidar = np.eye(4)
    lidar[2, 3] = 0.2
    pose = _pose(t, 0.5 * t) @ lidar
    keep = np.isfinite(SCAN).all(axis=1) & ~(SCAN == 0).all(axis=1)
    pts = SCAN[keep].astype(np.float64)
    return pts @ pose[:3, :3].T + pose[:3, 3], pose[:3, 3]


def _write_bag(path: Path, ros1: bool, topic: str = "/points", with_tf: bool = True) -> None:
    pytest.importorskip("rosbags")
    from rosbags.typesys import Stores, get_typestore

    ts = get_typestore(Stores.ROS1_NOETIC if ros1 else Stores.ROS2_HUMBLE)
    if ros1:  # the noetic store lacks tf2_msgs; ROS 1 bags carry their own definitions
        from rosbags.typesys import get_types_from_msg

        ts.register(get_types_from_msg("geometry_msgs/TransformStamped[] transforms",
                                       "tf2_msgs/msg/TFMessage"))
    T = ts.types
    Time = T["builtin_interfaces/msg/Time"]

    def header(t: float, frame: str):
        stamp = Time(sec=int(t), nanosec=int(round((t - int(t)) * 1e9)))
        if ros1:
            return T["std_msgs/msg/Header"](seq=0, stamp=stamp, frame_id=frame)
        return T["std_msgs/msg/Header"](stamp=stamp, frame_id=frame)

    def tf(t: float, parent: str, child: str, xyz, quat):
        return T["geometry_msgs/msg/TransformStamped"](
            header=header(t, parent), child_frame_id=child,
            transform=T["geometry_msgs/msg/Transform"](
                translation=T["geometry_msgs/msg/Vector3"](x=xyz[0], y=xyz[1], z=xyz[2]),
                rotation=T["geometry_msgs/msg/Quaternion"](x=quat[0], y=quat[1], z=quat[2],
                                                           w=quat[3])))

    field = T["sensor_msgs/msg/PointField"]
    # x, y, z float32 plus a float32 intensity between y and z: offsets matter.
    rec = np.zeros(len(SCAN), dtype=[("x", "<f4"), ("y", "<f4"), ("i", "<f4"), ("z", "<f4")])
    rec["x"], rec["y"], rec["z"] = SCAN[:, 0], SCAN[:, 1], SCAN[:, 2]
    fields = [field(name="x", offset=0, datatype=7, count=1),
              field(name="y", offset=4, datatype=7, count=1),
              field(name="intensity", offset=8, datatype=7, count=1),
              field(name="z", offset=12, datatype=7, count=1)]

    def cloud(t: float):
        return T["sensor_msgs/msg/PointCloud2"](
            header=header(t, "/lidar" if ros1 else "lidar"), height=1, width=len(SCAN),
            fields=fields, is_bigendian=False, point_step=16, row_step=16 * len(SCAN),
            data=np.frombuffer(rec.tobytes(), dtype=np.uint8), is_dense=False)

    tfm = T["tf2_msgs/msg/TFMessage"]
    msgs = [("/tf_static", 0.0, tfm(transforms=[tf(0.0, "base_link", "lidar", (0, 0, 0.2),
                                                   (0, 0, 0, 1))]))]
    msgs += [("/tf", t, tfm(transforms=[tf(t, "odom", "base_link", (t, 0, 0),
                                           _yaw_quat(0.5 * t))])) for t in TF_TIMES]
    msgs = msgs if with_tf else []
    msgs += [(topic, t, cloud(t)) for t in CLOUD_TIMES]
    msgs.sort(key=lambda m: m[1])
    if ros1:
        from rosbags.rosbag1 import Writer
        writer, serialize = Writer(path), ts.serialize_ros1
    else:
        from rosbags.rosbag2 import Writer
        writer, serialize = Writer(path, version=9), ts.serialize_cdr
    with writer:
        conns = {}
        for name, mtype in (("/tf_static", "tf2_msgs/msg/TFMessage"),
                            ("/tf", "tf2_msgs/msg/TFMessage"),
                            (topic, "sensor_msgs/msg/PointCloud2")):
            conns[name] = writer.add_connection(name, mtype, typestore=ts)
        for name, t, msg in msgs:
            writer.write(conns[name], int(t * 1e9) + 1, serialize(msg, msg.__msgtype__))


@pytest.mark.parametrize("ros1", [True, False], ids=["ros1", "ros2"])
def test_bag_clouds_are_moved_into_the_fixed_frame_by_tf_at_their_stamp(tmp_path, ros1):
    path = tmp_path / ("run.bag" if ros1 else "run")
    _write_bag(path, ros1)
    obst = load_obstacles(path)
    want = [_expected(t) for t in CLOUD_TIMES]
    np.testing.assert_allclose(obst.points, np.concatenate([w[0] for w in want]), atol=1e-5)
    np.testing.assert_allclose(obst.origins, [w[1] for w in want], atol=1e-6)
    assert obst.point_origin.tolist() == [0, 0, 0, 1, 1, 1, 2, 2, 2]
    assert obst.dropped_nonfinite == 3 and obst.unknown_default == "blocked"


@pytest.mark.parametrize("ros1", [True, False], ids=["ros1", "ros2"])
def test_bag_without_tf_names_the_missing_transform_and_keeps_its_frame(tmp_path, ros1):
    path = tmp_path / ("run.bag" if ros1 else "run")
    _write_bag(path, ros1, with_tf=False)
    with pytest.raises(MapError, match=r"no /tf transform from the cloud frame 'lidar'.*"
                                       r"--fixed-frame lidar"):
        load_obstacles(path)
    obst = load_obstacles(path, fixed_frame="lidar")  # the clouds as recorded
    assert obst.frame == "lidar" and len(obst.origins) == len(CLOUD_TIMES)
    np.testing.assert_allclose(obst.origins, 0.0)
    with_tf = tmp_path / ("tf.bag" if ros1 else "tf")
    _write_bag(with_tf, ros1)
    assert load_obstacles(with_tf).frame == "odom"  # the root of the tf tree


def test_ros2_bag_by_folder_storage_file_or_metadata(tmp_path):
    _write_bag(tmp_path / "run", ros1=False)
    want = load_points(tmp_path / "run")
    for name in ("run/run.db3", "run/metadata.yaml"):
        np.testing.assert_array_equal(load_points(tmp_path / name), want)


def test_bag_options_topic_fixed_frame_max_clouds(tmp_path):
    path = tmp_path / "run.bag"
    _write_bag(path, ros1=True, topic="/velodyne_points")
    obst = load_obstacles(path, topic="/velodyne_points", fixed_frame="base_link", max_clouds=2)
    # In base_link the static 0.2 m lift is all that applies, whatever the robot's motion.
    keep = np.isfinite(SCAN).all(axis=1) & ~(SCAN == 0).all(axis=1)
    one = SCAN[keep].astype(np.float64) + [0, 0, 0.2]
    np.testing.assert_allclose(obst.points, np.concatenate([one, one]), atol=1e-6)
    with pytest.raises(MapError, match="no PointCloud2 topic '/nope'"):
        load_obstacles(path, topic="/nope")
    with pytest.raises(MapError, match="no tf path"):
        load_obstacles(path, fixed_frame="map")


def test_bag_cloud_outside_the_tf_span_is_an_error(tmp_path, monkeypatch):
    import planner.io.bag as bag

    path = tmp_path / "run.bag"
    _write_bag(path, ros1=True)
    monkeypatch.setattr(bag, "TF_TOPICS", ("/tf_static",))  # odom -> base_link unknown
    with pytest.raises(MapError, match="no tf path"):
        load_obstacles(path, fixed_frame="odom")


def test_las_and_laz_apply_scale_and_offset(tmp_path):
    laspy = pytest.importorskip("laspy")
    pts = np.array([[500_000.123, 4_000_000.456, 12.789], [500_010.0, 4_000_020.5, -3.25],
                    [np.nan, 0, 0]])
    for name in ("a.las", "a.laz"):
        if name.endswith("laz"):
            pytest.importorskip("lazrs")
        header = laspy.LasHeader(point_format=3, version="1.2")
        header.offsets = [500_000.0, 4_000_000.0, 0.0]
        header.scales = [0.001, 0.001, 0.001]
        las = laspy.LasData(header)
        las.x, las.y, las.z = pts[:2, 0], pts[:2, 1], pts[:2, 2]
        las.write(str(tmp_path / name))
        got = load_points(tmp_path / name)
        np.testing.assert_allclose(got, pts[:2], atol=5e-4)
        # Stored as integers: offsets really were applied (raw values are small).
        assert np.abs(laspy.read(str(tmp_path / name)).X).max() < 30_000_000


def test_e57_scans_are_moved_by_their_poses(tmp_path):
    pye57 = pytest.importorskip("pye57")
    path = tmp_path / "s.e57"
    # The last point of scan 0 is flagged invalid (E57's way to mark a missing return).
    scans = [np.array([[1.0, 0, 0], [0, 2.0, 0], [9.0, 9, 9]]), np.array([[0.5, 0.5, 0.5]])]
    invalid = [np.array([0, 0, 1], dtype=np.int8), np.zeros(1, dtype=np.int8)]
    poses = [(0.0, (1.0, 2.0, 3.0)), (math.pi / 2, (-1.0, 0.0, 0.5))]
    e57 = pye57.E57(str(path), mode="w")
    for scan, bad, (yaw, xyz) in zip(scans, invalid, poses, strict=True):
        data = {"cartesianX": scan[:, 0], "cartesianY": scan[:, 1], "cartesianZ": scan[:, 2],
                "cartesianInvalidState": bad}
        q = _yaw_quat(yaw)
        e57.write_scan_raw(data, rotation=np.array([q[3], q[0], q[1], q[2]]),
                           translation=np.array(xyz))
    e57.close()
    obst = load_obstacles(path)
    want = []
    for scan, bad, (yaw, xyz) in zip(scans, invalid, poses, strict=True):
        pose = _pose(0.0, yaw)
        pose[:3, 3] = xyz
        ok = scan[bad == 0]
        want.append(ok @ pose[:3, :3].T + pose[:3, 3])
    np.testing.assert_allclose(obst.points, np.concatenate(want), atol=1e-9)
    np.testing.assert_allclose(obst.origins, [p[1] for p in poses])
    assert obst.point_origin.tolist() == [0, 0, 1]


@pytest.mark.parametrize(("name", "module"), [("x.bag", "rosbags"), ("x.las", "laspy"),
                                              ("x.e57", "pye57")])
def test_missing_robot_extra_names_it_in_one_line(tmp_path, monkeypatch, name, module):
    import sys

    (tmp_path / name).write_bytes(b"not really")
    monkeypatch.setitem(sys.modules, module, None)  # import fails as if not installed
    with pytest.raises(MapError) as info:
        load_obstacles(tmp_path / name)
    msg = str(info.value)
    assert "\n" not in msg and "'robot' extra" in msg and 'lattice-planner[robot]' in msg
    assert msg.startswith(name)


@pytest.mark.parametrize("name", ["x.bag", "x.las", "x.laz", "x.e57"])
def test_corrupt_robot_files_are_map_errors(tmp_path, name):
    pytest.importorskip({"bag": "rosbags", "las": "laspy", "laz": "lazrs",
                         "e57": "pye57"}[name[2:]])
    (tmp_path / name).write_bytes(b"\x00garbage" * 40)
    with pytest.raises(MapError, match=name.replace(".", r"\.")):
        load_obstacles(tmp_path / name)


def test_cli_bag_options_reach_the_reader_and_the_path_file_names_the_fixed_frame(tmp_path,
                                                                                    capsys):
    import json

    from planner.cli import main

    bag, no_tf = tmp_path / "run.bag", tmp_path / "bare.bag"
    _write_bag(bag, ros1=True, topic="/velodyne_points")
    _write_bag(no_tf, ros1=True, with_tf=False)
    query = ["--radius", "0.05", "--cell-volume", "0.001", "--unknown", "free",
             "--bounds", "-3,-3,-1,3,3,2", "--start", "-2.5,-2.5,1.5", "--goal", "2.5,2.5,1.5"]
    out = tmp_path / "path.json"
    assert main(["plan", str(bag), "--topic", "/velodyne_points", "--fixed-frame",
                 "base_link", "--max-clouds", "2", *query, "--out", str(out)]) == 0
    assert json.loads(out.read_text())["frame"] == "base_link"
    capsys.readouterr()
    assert main(["plan", str(no_tf), *query]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "no /tf transform" in err and "'lidar'" in err


@pytest.mark.parametrize("command", ["compare", "explore"])
def test_compare_and_explore_take_the_bag_options_of_plan(tmp_path, capsys, command):
    import json

    from planner.cli import main

    bag = tmp_path / "run.bag"
    _write_bag(bag, ros1=True, topic="/velodyne_points")
    query = ["--radius", "0.05", "--cell-volume", "0.001", "--bounds", "-3,-3,-1,3,3,2",
             "--start", "-2.5,-2.5,1.5", "--goal", "2.5,2.5,1.5", "--json"]
    extra = (["--lattices", "cubic", "--unknown", "free"] if command == "compare"
             else ["--lattice", "cubic", "--sensor-range", "1"])
    assert main([command, str(bag), "--topic", "/nowhere", *query, *extra]) == 2
    assert "/nowhere" in capsys.readouterr().err
    blocked = []
    for clouds in ("1", "3"):
        assert main([command, str(bag), "--topic", "/velodyne_points", "--fixed-frame",
                     "odom", "--max-clouds", clouds, *query, *extra]) == 0
        rows = json.loads(capsys.readouterr().out)
        if command == "compare":
            blocked.append(rows[0]["blocked_cells"])
        else:
            assert rows[0]["status"] == "reached"
    # three clouds from three poses block more cells than the first one alone
    assert command == "explore" or blocked[0] < blocked[1]
