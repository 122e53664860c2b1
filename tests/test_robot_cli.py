"""Robot data goes in without conversion: the same scene as a ROS 2 bag, LAS, LAZ, E57 and an
organized PCD with NaN holes plans end to end from the command line, with the same answer."""

import subprocess
import sys

import numpy as np
import pytest

import planner

PLAN = ["--lattice", "fcc", "--radius", "0.25", "--cell-volume", "0.004", "--bounds",
        "0,0,0,20,12,3", "--unknown", "free", "--start", "2.5,2.5,1.2", "--goal",
        "18.3,10.5,1.2", "--json"]


@pytest.fixture(scope="module")
def office():
    # float32-exact coordinates, so that every format stores the same points
    return planner.maps.load_map_points("office").astype(np.float32).astype(np.float64)


def plan_json(path) -> dict:
    import json

    r = subprocess.run([sys.executable, "-m", "planner", "plan", str(path), *PLAN],
                       capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    return json.loads(r.stdout)


def write_bag(path, pts: np.ndarray) -> None:
    pytest.importorskip("rosbags")
    from rosbags.rosbag2 import Writer
    from rosbags.typesys import Stores, get_typestore

    ts = get_typestore(Stores.ROS2_HUMBLE)
    T = ts.types
    stamp = T["builtin_interfaces/msg/Time"](sec=1, nanosec=0)

    def header(frame):
        return T["std_msgs/msg/Header"](stamp=stamp, frame_id=frame)

    tf = T["geometry_msgs/msg/TransformStamped"](
        header=header("map"), child_frame_id="lidar",
        transform=T["geometry_msgs/msg/Transform"](
            translation=T["geometry_msgs/msg/Vector3"](x=0.0, y=0.0, z=0.0),
            rotation=T["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=0.0, w=1.0)))
    field = T["sensor_msgs/msg/PointField"]
    rec = np.ascontiguousarray(pts, dtype="<f4")
    cloud = T["sensor_msgs/msg/PointCloud2"](
        header=header("lidar"), height=1, width=len(rec),
        fields=[field(name=n, offset=4 * i, datatype=7, count=1) for i, n in enumerate("xyz")],
        is_bigendian=False, point_step=12, row_step=12 * len(rec),
        data=np.frombuffer(rec.tobytes(), dtype=np.uint8), is_dense=True)
    tfm = T["tf2_msgs/msg/TFMessage"](transforms=[tf])
    with Writer(path, version=9) as w:
        c_tf = w.add_connection("/tf_static", "tf2_msgs/msg/TFMessage", typestore=ts)
        c_pc = w.add_connection("/points", "sensor_msgs/msg/PointCloud2", typestore=ts)
        w.write(c_tf, 1, ts.serialize_cdr(tfm, tfm.__msgtype__))
        w.write(c_pc, 1_000_000_001, ts.serialize_cdr(cloud, cloud.__msgtype__))


def write_las(path, pts: np.ndarray) -> None:
    laspy = pytest.importorskip("laspy")
    if path.suffix == ".laz":
        pytest.importorskip("lazrs")
    h = laspy.LasHeader(point_format=3, version="1.2")
    h.scales = [1e-7] * 3  # fine enough to keep the float32 coordinates
    h.offsets = [0.0, 0.0, 0.0]
    las = laspy.LasData(h)
    las.x, las.y, las.z = pts.T
    las.write(str(path))


def write_e57(path, pts: np.ndarray) -> None:
    pye57 = pytest.importorskip("pye57")
    e57 = pye57.E57(str(path), mode="w")
    e57.write_scan_raw({"cartesianX": pts[:, 0], "cartesianY": pts[:, 1],
                        "cartesianZ": pts[:, 2]},
                       rotation=np.array([1.0, 0.0, 0.0, 0.0]), translation=np.zeros(3))
    e57.close()


def write_organized_pcd(path, pts: np.ndarray) -> None:
    """An organized cloud (width x height) whose missing returns are NaN, as RGB-D and
    organized lidar drivers write them."""
    width = 100
    height = -(-len(pts) // width) + 3  # three extra rows of holes
    grid = np.full((height * width, 3), np.nan, dtype="<f4")
    grid[:len(pts)] = pts
    head = (f"# .PCD v0.7\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n"
            f"WIDTH {width}\nHEIGHT {height}\nVIEWPOINT 0 0 0 1 0 0 0\n"
            f"POINTS {width * height}\nDATA binary\n")
    path.write_bytes(head.encode() + grid.tobytes())


WRITERS = {"bag": ("office_bag", write_bag), "las": ("office.las", write_las),
           "laz": ("office.laz", write_las), "e57": ("office.e57", write_e57),
           "pcd": ("office_organized.pcd", write_organized_pcd)}


@pytest.mark.slow
def test_every_robot_format_plans_the_same_path(tmp_path, office):
    ref = plan_json(_write_ply(tmp_path, office))
    assert ref["found"]
    for kind, (name, write) in WRITERS.items():
        path = tmp_path / name
        write(path, office)
        got = plan_json(path)
        assert got["found"], kind
        assert abs(got["length"] - ref["length"]) < 1e-6, kind


def _write_ply(tmp_path, pts):
    path = tmp_path / "office.ply"
    planner.io.save_points(path, pts)
    return path
