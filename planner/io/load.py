"""The reader chosen by file extension or format name (:func:`load_obstacles`,
:func:`load_points`, :func:`load_posed_scans`) and the point writer (:func:`save_points`).

Readers (chosen by file extension, or by an explicit ``format`` name):

===========  ===============================  ============================================
format       extensions                       contents
===========  ===============================  ============================================
``ply``      ``.ply``                         vertex ``x, y, z`` (ascii or binary), metres
``pcd``      ``.pcd``                         PCD v0.7 ascii / binary / binary_compressed
``xyz``      ``.xyz .txt .dat`` (+ ``.gz``,   one ``x y z [extra ...]`` per line; ``#``
             ``.bz2``, ``.xz``)               comments; whitespace or comma separated
``npy``      ``.npy``                         (N, 3) numeric array; (N, 3 + k): x, y, z
                                              first (intensity, ... dropped)
``kitti``    ``.bin``                         KITTI velodyne scan: float32 x, y, z,
                                              reflectance records
``bt``       ``.bt``                          OctoMap binary OcTree: occupied + free leaves
``3dmap``    ``.3dmap``                       MovingAI voxel map: unit cubes
``poses``    (``format="poses"`` only)        pose list of scans (:func:`load_posed_scans`)
``rosmap``   ``.yaml .yml``                   ROS map_server map (PGM / PNG image), 2D
``bag``      ``.bag``, a rosbag2 folder,      ``sensor_msgs/PointCloud2`` + ``/tf``
             ``.db3 .mcap``                   (``robot`` extra)
``las``      ``.las .laz``                    LAS / LAZ points (``robot`` extra)
``e57``      ``.e57``                         E57 scans with poses (``robot`` extra)
===========  ===============================  ============================================

Every coordinate is returned as float64 metres.  Point clouds drop *no-return* points (rows
exactly ``(0, 0, 0)`` in the sensor frame) and points with a NaN or infinite coordinate
(organized clouds' missing returns; counted in ``Obstacles.dropped_nonfinite``).

What a map says about space (occupied / free / unknown) is described on :class:`Obstacles`.

Every bad input (missing file, unknown format, truncated or corrupt data, a header that
disagrees with its data, a cloud with no finite point) raises :class:`planner.errors.MapError`
whose one-line message names the file and the problem.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from planner.errors import MapError
from planner.fsutil import atomic_path
from planner.io._files import DECOMPRESSED_BUDGET, check_file
from planner.io.bag import read_bag
from planner.io.kitti import read_kitti
from planner.io.lidar import read_e57, read_las
from planner.io.movingai import load_scenarios, read_3dmap
from planner.io.obstacles import Obstacles, Scenarios
from planner.io.ply import read_ply, write_ply
from planner.io.rosmap import read_rosmap
from planner.io.scans import read_pose_list
from planner.io.sidecar import load_sidecar
from planner.io.text import read_npy, read_xyz
from planner.io.validate import cloud, robust_extent

__all__ = [
    "DECOMPRESSED_BUDGET",
    "Obstacles",
    "Scenarios",
    "load_obstacles",
    "load_points",
    "load_posed_scans",
    "load_scenarios",
    "load_sidecar",
    "map_format",
    "obstacles_from_points",
    "robust_extent",
    "save_points",
]

PathLike = str | os.PathLike

# Extension -> canonical format name.  Text formats may carry a compression suffix on top.
_EXTENSIONS = {
    ".ply": "ply", ".pcd": "pcd", ".xyz": "xyz", ".txt": "xyz", ".dat": "xyz", ".npy": "npy",
    ".bt": "bt", ".3dmap": "3dmap", ".yaml": "rosmap", ".yml": "rosmap", ".bag": "bag",
    ".db3": "bag", ".mcap": "bag", ".las": "las", ".laz": "las", ".e57": "e57",
    ".bin": "kitti",
}
# Explicit format names accepted by ``format=`` (aliases included).
_FORMAT_ALIASES = {
    "ply": "ply", "pcd": "pcd", "xyz": "xyz", "txt": "xyz", "dat": "xyz", "text": "xyz",
    "npy": "npy", "bt": "bt", "octomap": "bt", "3dmap": "3dmap", "movingai": "3dmap",
    "poses": "poses", "rosmap": "rosmap", "yaml": "rosmap", "bag": "bag", "rosbag": "bag",
    "las": "las", "laz": "las", "e57": "e57", "kitti": "kitti", "bin": "kitti",
}
_COMPRESSIONS = (".gz", ".bz2", ".xz")


def load_obstacles(path: PathLike, format: str | None = None, *,
                   max_decompressed: int | None = None, **options) -> Obstacles:
    """Read a map or point-cloud file into :class:`Obstacles`.

    Parameters
    ----------
    path : str or PathLike
        File to read (a rosbag2 folder for ROS 2 bags).
    format : str, optional
        A format name of the module table (aliases ``txt``, ``dat``, ``text``, ``octomap``,
        ``movingai``, ``yaml``, ``rosbag``, ``laz``).  Default: from the file extension
        (case-insensitive; text files may end in ``.gz`` / ``.bz2`` / ``.xz``).
    max_decompressed : int, optional
        Byte budget for inflating a compressed text file (default: a quarter of the memory
        budget of :mod:`planner.budget`); inflation stops and fails once past it.
    **options
        Format options: for bags ``topic``, ``fixed_frame``, ``max_clouds``.

    Returns
    -------
    Obstacles
        Point clouds fill ``points``; posed scans and bags also ``origins``.  ``.3dmap``
        fills ``boxes`` (unit voxel centres) and ``bounds``.  ``.bt`` fills ``boxes`` /
        ``box_sizes`` with the occupied leaves and ``free_boxes`` with the free ones.
        ROS maps are 2D (``dim == 2``).

    Raises
    ------
    MapError
        Missing file, unknown format, truncated / corrupt content, a missing ``robot`` extra,
        or no obstacles at all.
    """
    p = Path(path)
    fmt, compression = _resolve_format(p, format)
    if fmt == "bag" and p.is_dir():
        pass  # a rosbag2 folder
    else:
        check_file(p)
    if options and fmt != "bag":
        raise MapError(f"{p.name}: options {sorted(options)} apply to bags only")
    try:
        # Corrupt bytes can hold signalling NaNs or huge values whose casts set FP flags; the
        # readers check every result for finiteness, so numpy's warnings would only be noise
        # printed ahead of the one error line.
        with np.errstate(all="ignore"):
            return _read(p, fmt, compression, max_decompressed, options)
    except MapError:
        raise
    except OSError as exc:  # permission denied, I/O error, ...
        raise MapError(f"{p.name}: cannot read file: {exc.strerror or exc}") from exc
    except MemoryError as exc:
        raise MapError(f"{p.name}: file too large to load") from exc
    except (ValueError, IndexError, TypeError, KeyError, EOFError, OverflowError) as exc:
        # Safety net: every known corruption is reported specifically by the readers; anything
        # that slips through still surfaces as a MapError naming the file.
        msg = str(exc).splitlines()[0][:100] if str(exc) else type(exc).__name__
        raise MapError(f"{p.name}: corrupt {fmt} file ({msg})") from exc


def _read(p: Path, fmt: str, compression: str | None, budget: int | None,
          options: dict) -> Obstacles:
    if fmt == "ply":
        return read_ply(p)
    if fmt == "pcd":
        from planner.io.pcd import read_pcd  # lazy: numba
        return read_pcd(p)
    if fmt == "xyz":
        return read_xyz(p, compression, budget)
    if fmt == "npy":
        return read_npy(p)
    if fmt == "bt":
        from planner.io.octomap import read_octomap  # lazy: numba
        return read_octomap(p)
    if fmt == "3dmap":
        return read_3dmap(p)
    if fmt == "poses":
        return read_pose_list(p, load_obstacles)
    if fmt == "rosmap":
        return read_rosmap(p)
    if fmt == "bag":
        return read_bag(p, **options)
    if fmt == "las":
        return read_las(p)
    if fmt == "kitti":
        return read_kitti(p)
    return read_e57(p)


def obstacles_from_points(points, source: str = "<array>") -> Obstacles:
    """World-frame obstacle points (an in-memory array) as :class:`Obstacles`.

    Validated like every cloud a reader returns: rows with NaN / inf are dropped and counted;
    ``(0, 0, 0)`` is kept (it is a place, not a no-return, in the world frame).

    Parameters
    ----------
    points : array_like, shape (N, 3)
        Metres.
    source : str
        Name for messages.

    Raises
    ------
    MapError
        Bad shape or dtype, no finite point, or absurd coordinates.
    """
    return cloud(points, source, sensor_frame=False)


def load_points(path: PathLike, format: str | None = None, **kwargs) -> np.ndarray:
    """Read obstacle points from any supported file.

    Parameters
    ----------
    path, format, kwargs
        As for :func:`load_obstacles`.

    Returns
    -------
    ndarray, shape (N, d), float64
        Metres.  The sensed points of a cloud, or, for maps of boxes without sensed points,
        the box centres; an OctoMap's leaves are filled with their finest-voxel centres (a
        leaf of 2^k voxels per side gives 8^k points).

    Raises
    ------
    MapError
        As for :func:`load_obstacles`.
    """
    obst = load_obstacles(path, format, **kwargs)
    if len(obst.points):
        return obst.points
    try:
        return obst.box_centre_points()
    except MapError as exc:
        raise MapError(f"{obst.source}: {exc}") from None


def load_posed_scans(path: str | Path) -> np.ndarray:
    """Read a pose list and merge its scans into one world-frame cloud.

    Each non-comment line is ``scan_path`` followed by either 16 numbers (the 4x4
    sensor-to-world matrix, row-major) or 7 numbers ``x y z qx qy qz qw`` (translation in
    metres and a rotation quaternion, normalised here).  Separators are whitespace and / or
    commas; ``#`` starts a comment.  Relative scan paths are relative to the pose file's folder.

    Returns
    -------
    ndarray, shape (N, 3), float64
        World-frame points, metres (no-returns dropped), scans in file order.

    Raises
    ------
    MapError
        Missing or malformed pose file (message gives the line number), a bad pose, or any
        error reading a scan.
    """
    return read_pose_list(Path(path), load_obstacles).points


def save_points(path: PathLike, points: np.ndarray, *, dtype=np.float64) -> None:
    """Write points atomically (temporary file in the same folder, then rename).

    Parameters
    ----------
    path : str or PathLike
        Target; the extension picks the format: ``.ply`` (binary little endian vertex
        ``x, y, z``), ``.npy``, or ``.xyz`` / ``.txt`` / ``.dat`` (optionally ``.gz`` / ``.bz2``
        / ``.xz``; one ``x y z`` line per point, 17 significant digits so float64 round-trips).
    points : ndarray, shape (N, 3)
        Metres; finite, at least one point.
    dtype : numpy dtype, default float64
        Stored precision for ``.ply`` and ``.npy`` (float32 or float64).

    Raises
    ------
    MapError
        Unknown extension, bad shape, NaN / inf, no points, or unsupported ``dtype``.
    """
    import bz2
    import gzip
    import lzma

    p = Path(path)
    fmt, compression = _resolve_format(p, None)
    pts = np.asarray(points, dtype=np.float64)
    if pts.ndim != 2 or pts.shape[1] != 3:
        raise MapError(f"{p.name}: points to save must have shape (N, 3), got {pts.shape}")
    if not len(pts):
        raise MapError(f"{p.name}: refusing to save an empty point cloud")
    if not np.isfinite(pts).all():
        raise MapError(f"{p.name}: points to save contain NaN or infinite coordinates")
    dt = np.dtype(dtype)
    if dt not in (np.dtype(np.float32), np.dtype(np.float64)):
        raise MapError(f"{p.name}: dtype must be float32 or float64, got {dt}")
    if fmt not in ("ply", "npy", "xyz"):
        raise MapError(f"{p.name}: cannot write format '{fmt}' (use .ply, .npy or .xyz)")
    if fmt == "ply":
        write_ply(p, pts, dt)
        return
    with atomic_path(p) as tmp:
        if fmt == "npy":
            with open(tmp, "wb") as f:  # a file object: np.save(path) would append ".npy"
                np.save(f, pts.astype(dt))
        else:
            opener = {None: open, ".gz": gzip.open, ".bz2": bz2.open,
                      ".xz": lzma.open}[compression]
            with opener(tmp, "wt") as f:
                np.savetxt(f, pts, fmt="%.17g")


def _resolve_format(p: Path, format: str | None) -> tuple[str, str | None]:
    """(canonical format, compression suffix or None) from ``format`` or the file name."""
    suffixes = [s.lower() for s in p.suffixes]
    compression = suffixes[-1] if suffixes and suffixes[-1] in _COMPRESSIONS else None
    if format is not None:
        fmt = _FORMAT_ALIASES.get(str(format).lower().lstrip("."))
        if fmt is None:
            raise MapError(f"{p.name}: unknown format '{format}' (known: "
                           f"{', '.join(sorted(_FORMAT_ALIASES))})")
    elif (p.is_dir() and (p / "metadata.yaml").is_file()) or p.name == "metadata.yaml":
        fmt = "bag"  # a rosbag2 folder, or its metadata file
    else:
        ext = suffixes[-2] if compression and len(suffixes) >= 2 else (
            suffixes[-1] if suffixes and not compression else "")
        fmt = _EXTENSIONS.get(ext)
        if fmt is None:
            raise MapError(f"{p.name}: unknown file extension '{''.join(p.suffixes)}' (known: "
                           f"{', '.join(sorted(_EXTENSIONS))}, text also with "
                           f"{'/'.join(_COMPRESSIONS)})")
    if compression and fmt != "xyz":
        raise MapError(f"{p.name}: {compression} compression is only supported for text XYZ")
    return fmt, compression


def map_format(path: PathLike, format: str | None = None) -> str | None:
    """The reader :func:`load_obstacles` would choose for ``path`` (a name of the module
    table), or None when it would refuse the name (the read then says why)."""
    try:
        return _resolve_format(Path(path), format)[0]
    except MapError:
        return None
