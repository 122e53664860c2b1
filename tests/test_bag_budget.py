"""A compressed bag chunk is inflated under the decompression budget (a quarter of the
memory budget): a chunk that expands past it is refused in one line before it is held,
in every compression a bag reader meets (ROS 1 bz2 and lz4, rosbag2 zstd per message and
per file, mcap chunks); under the default budget the same bags read as usual."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from planner.errors import MapError
from planner.io import load_obstacles

pytest.importorskip("rosbags")

N = 400_000  # points of 16 bytes: a 6.4 MB cloud of zeros that compresses to a few kB


def _write(path: Path, kind: str) -> None:
    from rosbags.typesys import Stores, get_typestore

    ros1 = kind.startswith("ros1")
    ts = get_typestore(Stores.ROS1_NOETIC if ros1 else Stores.ROS2_HUMBLE)
    T = ts.types
    stamp = T["builtin_interfaces/msg/Time"](sec=1, nanosec=0)
    head = (T["std_msgs/msg/Header"](seq=0, stamp=stamp, frame_id="map") if ros1 else
            T["std_msgs/msg/Header"](stamp=stamp, frame_id="map"))
    f = T["sensor_msgs/msg/PointField"]
    data = np.zeros(16 * N, np.uint8)
    data[:16] = np.frombuffer(np.array([1, 2, 0, 3], "<f4").tobytes(), np.uint8)
    msg = T["sensor_msgs/msg/PointCloud2"](
        header=head, height=1, width=N, is_bigendian=False, point_step=16, row_step=16 * N,
        fields=[f(name=c, offset=o, datatype=7, count=1)
                for c, o in (("x", 0), ("y", 4), ("i", 8), ("z", 12))],
        data=data, is_dense=True)
    if ros1:
        from rosbags.rosbag1 import Writer

        w, ser = Writer(path), ts.serialize_ros1
        w.set_compression({"ros1_bz2": Writer.CompressionFormat.BZ2,
                           "ros1_lz4": Writer.CompressionFormat.LZ4}[kind])
    else:
        from rosbags.rosbag2 import CompressionFormat, CompressionMode, StoragePlugin, Writer

        plugin = StoragePlugin.MCAP if kind == "mcap" else StoragePlugin.SQLITE3
        w, ser = Writer(path, version=8, storage_plugin=plugin), ts.serialize_cdr
        mode = CompressionMode.FILE if kind == "ros2_file" else CompressionMode.MESSAGE
        w.set_compression(mode, CompressionFormat.ZSTD)
    with w:
        conn = w.add_connection("/points", "sensor_msgs/msg/PointCloud2", typestore=ts)
        w.write(conn, 10**9, ser(msg, msg.__msgtype__))


@pytest.mark.parametrize("kind", ["ros1_bz2", "ros1_lz4", "ros2_message", "ros2_file",
                                  "mcap"])
def test_a_chunk_inflating_past_the_budget_is_refused(tmp_path, kind, monkeypatch):
    path = tmp_path / ("b.bag" if kind.startswith("ros1") else "b")
    try:
        _write(path, kind)
    except ImportError as exc:  # a compressor rosbags needs is not installed
        pytest.skip(str(exc))
    # the zeros are "no return" points: one point is left
    assert load_obstacles(path, fixed_frame="map").points.tolist() == [[1, 2, 3]]
    monkeypatch.setenv("PLANNER_MEMORY_BUDGET", "8M")  # 2 MB of decompression budget
    with pytest.raises(MapError) as got:
        load_obstacles(path, fixed_frame="map")
    msg = str(got.value)
    assert "\n" not in msg and "decompress" in msg and "--memory-budget" in msg, msg
