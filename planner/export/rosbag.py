"""A path as a ROS 2 bag: one ``nav_msgs/msg/Path`` message on ``/plan`` (``robot`` extra).

The message's header and every ``geometry_msgs/msg/PoseStamped`` carry ``frame`` (the map's
frame, ``map`` by default); pose stamps are the message stamp plus the nominal travel time
of :func:`planner.export.trajectory.path_poses`; orientations are the headings as
quaternions. The bag is a rosbag2 folder (``metadata.yaml`` + an sqlite3 ``.db3``, format
version 8, read by ROS 2 Humble and later and by ``rosbags``).
"""

from __future__ import annotations

import os
import shutil
import tempfile
import time
from pathlib import Path

from planner.errors import PlanError
from planner.export.trajectory import path_poses
from planner.fsutil import stage_rename, temp_prefix

__all__ = ["write_path_bag"]

TOPIC = "/plan"


def _require_rosbags():
    try:
        from rosbags.rosbag2 import Writer
        from rosbags.typesys import Stores, get_typestore
    except ImportError:
        raise PlanError("writing a ROS 2 bag needs the 'robot' extra: pip install "
                        "'lattice-planner[robot]'") from None
    return Writer, get_typestore(Stores.ROS2_HUMBLE)


def write_path_bag(out: str | os.PathLike, path, *, frame: str = "map",
                   stamp_ns: int | None = None, speed: float = 1.0) -> None:
    """Write ``path`` (K, 3) metres as a ROS 2 bag folder ``out`` (module docstring).

    ``stamp_ns``: the message time (ns since the epoch; None: now). The folder is written
    beside ``out`` under a temporary name and renamed; an existing ``out`` is refused.
    """
    Writer, ts = _require_rosbags()
    target = Path(out)
    if target.exists():
        raise PlanError(f"{target}: already exists (a bag is a new folder)")
    t, p, q = path_poses(path, speed)
    base = time.time_ns() if stamp_ns is None else int(stamp_ns)
    T = ts.types
    Time, Header = T["builtin_interfaces/msg/Time"], T["std_msgs/msg/Header"]

    def header(ns: int):
        return Header(stamp=Time(sec=ns // 10**9, nanosec=ns % 10**9), frame_id=frame)

    poses = [T["geometry_msgs/msg/PoseStamped"](
        header=header(base + round(ti * 1e9)),
        pose=T["geometry_msgs/msg/Pose"](
            position=T["geometry_msgs/msg/Point"](x=float(x), y=float(y), z=float(z)),
            orientation=T["geometry_msgs/msg/Quaternion"](
                x=float(a), y=float(b), z=float(c), w=float(d))))
        for ti, (x, y, z), (a, b, c, d) in zip(t, p, q, strict=True)]
    msg = T["nav_msgs/msg/Path"](header=header(base), poses=poses)
    target.parent.mkdir(parents=True, exist_ok=True)
    work = Path(tempfile.mkdtemp(prefix=temp_prefix(target.name, ""), dir=target.parent))
    bag = work / target.name
    staged = False
    try:
        with Writer(bag, version=8) as w:
            conn = w.add_connection(TOPIC, msg.__msgtype__, typestore=ts)
            w.write(conn, base, ts.serialize_cdr(msg, msg.__msgtype__))
        # with the command's other outputs (planner.fsutil.staged_outputs), or now
        staged = not stage_rename(bag, target, lambda: shutil.rmtree(work, ignore_errors=True))
    finally:
        if not staged:
            shutil.rmtree(work, ignore_errors=True)
