"""ROS 1 and ROS 2 bags (``rosbags``, the ``robot`` extra): PointCloud2 clouds in a fixed frame.

Each ``sensor_msgs/PointCloud2`` on the chosen topic is transformed from its ``frame_id`` into
the fixed frame with the ``/tf`` and ``/tf_static`` transforms at its header stamp (dynamic
transforms interpolated: translation linearly, rotation by scipy's ``Slerp``).  The sensor
origin of each cloud (its frame's origin in the fixed frame) is kept for ray-cast free space.
"""

from __future__ import annotations

import math
from bisect import bisect_left
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation, Slerp

from planner.errors import MapError
from planner.io.bag_limits import limited_decompression
from planner.io.obstacles import Obstacles
from planner.io.validate import finite_points, no_return_mask
from planner.progress import Progress

CLOUD_TYPE = "sensor_msgs/msg/PointCloud2"
TF_TYPE = "tf2_msgs/msg/TFMessage"
TF_TOPICS = ("/tf", "/tf_static")
# A stamp this far (s) outside a dynamic transform's recorded span still uses its end sample.
EXTRAPOLATION_TOLERANCE = 0.1
_DATATYPES = {1: "i1", 2: "u1", 3: "i2", 4: "u2", 5: "i4", 6: "u4", 7: "f4", 8: "f8"}


def require(module: str, what: str, name: str):
    """Import an optional ``robot`` dependency or fail with one line naming the extra."""
    import importlib

    try:
        return importlib.import_module(module)
    except ImportError:
        raise MapError(f"{name}: reading {what} files needs the 'robot' extra: "
                       f"pip install \"lattice-planner[robot]\"") from None


def read_bag(p: Path, topic: str | None = None, fixed_frame: str | None = None,
             max_clouds: int | None = None, progress: bool = False) -> Obstacles:
    """Clouds of a ROS bag in one fixed frame, with each cloud's sensor origin.

    Parameters
    ----------
    p : Path
        A ROS 1 ``.bag`` file or a ROS 2 bag folder (or its ``.db3`` / ``.mcap`` file).
    topic : str, optional
        PointCloud2 topic; default the first one in the bag.
    fixed_frame : str, optional
        Frame to express the points in; default the root of the first cloud's tf tree.
        A bag without ``/tf`` is an error naming the missing transform unless this is the
        clouds' own frame.
    max_clouds : int, optional
        Read at most this many clouds.
    progress : bool
        Show the clouds read on stderr (:class:`planner.progress.Progress`: silent for the
        first 5 s).

    Returns
    -------
    Obstacles
        ``points`` (N, 3) in the fixed frame, ``origins`` (S, 3) one per cloud,
        ``point_origin`` (N,), ``dropped_nonfinite``, ``frame`` (the fixed frame), ``read``
        (the topic and frame chosen, whether given, the clouds read and in the topic).
    """

    require("rosbags", ".bag", p.name)
    if max_clouds is not None and (not isinstance(max_clouds, int) or max_clouds < 1):
        raise MapError(f"{p.name}: max_clouds must be a positive integer, got {max_clouds!r}")
    # A rosbag2 is a folder; its storage or metadata file stands for it.
    bag_path = p.parent if p.suffix.lower() in (".db3", ".mcap", ".yaml") else p
    # every chunk rosbags inflates is limited by the decompression budget (bag_limits)
    with limited_decompression(p.name):
        return _read_clouds(p, bag_path, topic, fixed_frame, max_clouds, progress)


def _read_clouds(p: Path, bag_path: Path, topic, fixed_frame, max_clouds,
                 progress: bool) -> Obstacles:
    from rosbags.highlevel import AnyReader
    from rosbags.typesys import Stores, get_typestore

    try:
        reader = AnyReader([bag_path], default_typestore=get_typestore(Stores.LATEST))
        reader.open()
    except MapError:  # over the decompression budget while opening
        raise
    except Exception as exc:  # rosbags raises its own error types on corrupt bags
        raise MapError(f"{p.name}: unreadable ROS bag ({first_line(exc)})") from None
    try:
        clouds = [c for c in reader.connections if c.msgtype == CLOUD_TYPE]
        if not clouds:
            raise MapError(f"{p.name}: bag has no {CLOUD_TYPE} topic")
        names = sorted({c.topic for c in clouds})
        chosen = topic if topic is not None else clouds[0].topic
        conns = [c for c in clouds if c.topic == chosen]
        if not conns:
            raise MapError(f"{p.name}: no PointCloud2 topic {chosen!r} (has {', '.join(names)})")
        tree = TfTree(p.name)
        tf_conns = [c for c in reader.connections if c.topic in TF_TOPICS and
                    c.msgtype == TF_TYPE]
        # An empty connection list means "all messages" to rosbags: skip it explicitly.
        for conn, _, raw in reader.messages(connections=tf_conns) if tf_conns else ():
            msg = reader.deserialize(raw, conn.msgtype)
            for tf in msg.transforms:
                tree.add(tf, static=conn.topic == "/tf_static")
        pts_all, owner, origins, dropped = [], [], [], 0
        in_topic = sum(int(getattr(c, "msgcount", 0) or 0) for c in conns)
        frame_given = fixed_frame is not None
        total = min(in_topic, max_clouds) if max_clouds is not None else in_topic
        bar = Progress(max(total, 1), "clouds", label=f"reading {p.name} {chosen}",
                       enabled=progress)
        for conn, _, raw in reader.messages(connections=conns):
            msg = reader.deserialize(raw, conn.msgtype)
            frame = _frame(msg.header.frame_id)
            stamp = _stamp(msg.header.stamp)
            if fixed_frame is None:
                fixed_frame = tree.root(frame)
                if fixed_frame == frame and frame not in tree.parent.values():
                    raise MapError(f"{p.name}: no /tf transform from the cloud frame "
                                   f"{frame!r} to a fixed frame; pass --fixed-frame {frame} "
                                   "to keep the clouds in the sensor frame")
            pose = tree.lookup(_frame(fixed_frame), frame, stamp)
            pts, keep = finite_points(cloud_xyz(msg, p.name), p.name)
            dropped += len(keep) - len(pts)
            pts = pts[~no_return_mask(pts)]
            pts_all.append(pts @ pose[:3, :3].T + pose[:3, 3])
            owner.append(np.full(len(pts), len(origins), dtype=np.int64))
            origins.append(pose[:3, 3])
            bar.step()
            if max_clouds is not None and len(origins) >= max_clouds:
                break
        bar.close()
    except MapError:
        raise
    except Exception as exc:  # deserialisation of corrupt messages
        raise MapError(f"{p.name}: corrupt ROS bag message ({first_line(exc)})") from None
    finally:
        reader.close()
    points = np.concatenate(pts_all) if pts_all else np.zeros((0, 3))
    if not len(points):
        raise MapError(f"{p.name}: topic {chosen!r} holds no finite points")
    return Obstacles(points=points, boxes=np.zeros((0, 3)), box_size=0.0, bounds=None,
                     resolution=None, source=p.name, origins=np.array(origins),
                     point_origin=np.concatenate(owner), dropped_nonfinite=dropped,
                     frame=_frame(fixed_frame),
                     read={"topic": chosen, "topic_given": topic is not None,
                           "topics": names, "fixed_frame": _frame(fixed_frame),
                           "fixed_frame_given": frame_given, "max_clouds": max_clouds,
                           "clouds": len(origins), "clouds_in_topic": in_topic})


def cloud_xyz(msg, name: str) -> np.ndarray:
    """(H*W, 3) float64 ``x, y, z`` of a deserialised ``sensor_msgs/PointCloud2``."""
    fields = {f.name: f for f in msg.fields}
    missing = [c for c in "xyz" if c not in fields]
    if missing:
        raise MapError(f"{name}: PointCloud2 lacks fields {missing}")
    order = ">" if msg.is_bigendian else "<"
    formats, offsets = [], []
    for c in "xyz":
        f = fields[c]
        if f.datatype not in _DATATYPES:
            raise MapError(f"{name}: PointCloud2 field {c!r} has unknown datatype {f.datatype}")
        formats.append(order + _DATATYPES[f.datatype])
        offsets.append(int(f.offset))
    h, w, step, row = int(msg.height), int(msg.width), int(msg.point_step), int(msg.row_step)
    if any(o + np.dtype(t).itemsize > step for o, t in zip(offsets, formats, strict=True)):
        raise MapError(f"{name}: PointCloud2 fields lie outside point_step {step}")
    data = np.asarray(msg.data, dtype=np.uint8)
    if h * w == 0:
        return np.zeros((0, 3))
    if row < w * step or len(data) < (h - 1) * row + w * step:
        raise MapError(f"{name}: PointCloud2 data is shorter than height x row_step")
    rec = np.dtype({"names": list("xyz"), "formats": formats, "offsets": offsets,
                    "itemsize": step})
    rows = [np.frombuffer(data, dtype=rec, count=w, offset=r * row) for r in range(h)]
    arr = np.concatenate(rows)
    return np.column_stack([arr[c].astype(np.float64) for c in "xyz"])


class TfTree:
    """Transforms between frames from ``tf2_msgs/TFMessage`` samples, looked up in time."""

    def __init__(self, name: str) -> None:
        self.name = name
        self.parent: dict[str, str] = {}
        self.samples: dict[str, list[tuple[float, np.ndarray, np.ndarray]]] = {}
        self.static: dict[str, bool] = {}

    def add(self, tf, static: bool) -> None:
        """Record one ``geometry_msgs/TransformStamped``."""
        child, parent = _frame(tf.child_frame_id), _frame(tf.header.frame_id)
        t = tf.transform.translation
        q = tf.transform.rotation
        trans = np.array([t.x, t.y, t.z], dtype=np.float64)
        quat = np.array([q.x, q.y, q.z, q.w], dtype=np.float64)
        norm = float(np.linalg.norm(quat))
        if not (np.isfinite(trans).all() and math.isfinite(norm) and norm > 1e-9):
            raise MapError(f"{self.name}: non-finite transform {parent} -> {child}")
        self.parent[child] = parent
        self.static[child] = static
        series = self.samples.setdefault(child, [])
        series.append((_stamp(tf.header.stamp), trans, quat / norm))
        series.sort(key=lambda s: s[0])

    def root(self, frame: str) -> str:
        """Topmost ancestor of ``frame``."""
        seen = {frame}
        while frame in self.parent:
            frame = self.parent[frame]
            if frame in seen:
                raise MapError(f"{self.name}: tf frames form a loop at {frame!r}")
            seen.add(frame)
        return frame

    def lookup(self, target: str, source: str, t: float) -> np.ndarray:
        """4x4 transform taking ``source``-frame points into ``target`` at time ``t`` (s)."""
        if target == source:
            return np.eye(4)
        if self.root(target) != self.root(source):
            raise MapError(f"{self.name}: no tf path from {source!r} to {target!r}")
        return np.linalg.inv(self._in_root(target, t)) @ self._in_root(source, t)

    def _in_root(self, frame: str, t: float) -> np.ndarray:
        pose = np.eye(4)
        while frame in self.parent:
            pose = self._edge(frame, t) @ pose
            frame = self.parent[frame]
        return pose

    def _edge(self, child: str, t: float) -> np.ndarray:
        series = self.samples[child]
        times = [s[0] for s in series]
        if self.static[child] or len(series) == 1 and abs(t - times[0]) <= 1e-9:
            _, trans, quat = series[-1]
        elif t < times[0] - EXTRAPOLATION_TOLERANCE or t > times[-1] + EXTRAPOLATION_TOLERANCE:
            raise MapError(f"{self.name}: no transform {self.parent[child]} -> {child} at "
                           f"t={t:.3f} s (tf covers {times[0]:.3f}..{times[-1]:.3f} s)")
        elif t <= times[0]:
            _, trans, quat = series[0]
        elif t >= times[-1]:
            _, trans, quat = series[-1]
        else:
            i = bisect_left(times, t)
            (t0, p0, q0), (t1, p1, q1) = series[i - 1], series[i]
            a = 0.0 if t1 == t0 else (t - t0) / (t1 - t0)
            slerp = Slerp([0.0, 1.0], Rotation.from_quat([q0, q1]))
            trans, quat = p0 + a * (p1 - p0), slerp([a]).as_quat()[0]
        out = np.eye(4)
        out[:3, :3] = Rotation.from_quat(quat).as_matrix()
        out[:3, 3] = trans
        return out


def _frame(frame_id: str) -> str:
    return str(frame_id).lstrip("/")


def _stamp(stamp) -> float:
    return float(stamp.sec) + float(stamp.nanosec) * 1e-9


def first_line(exc: BaseException) -> str:
    return (str(exc).splitlines() or [type(exc).__name__])[0][:100]
