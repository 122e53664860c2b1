"""Reading obstacle maps and point clouds; writing point clouds.

Readers (chosen by file extension, or by an explicit ``format`` name):

===========  ==============================  =============================================
format       extensions                      contents
===========  ==============================  =============================================
``ply``      ``.ply``                        vertex ``x, y, z`` (ascii or binary), metres
``pcd``      ``.pcd``                        PCD v0.7 ascii / binary / binary_compressed
``xyz``      ``.xyz .txt .dat`` (+``.gz``,   one ``x y z [extra ...]`` per line; ``#``
             ``.bz2``)                       comments; whitespace or comma separated
``npy``      ``.npy``                        (N, 3) numeric array
``bt``       ``.bt``                         OctoMap binary OcTree: occupied voxel centres
``3dmap``    ``.3dmap``                      MovingAI voxel map: unit cubes
===========  ==============================  =============================================

Every coordinate is returned as float64 metres.  Point clouds (PLY, PCD, text, npy) drop
*no-return* points: rows exactly equal to ``(0, 0, 0)`` in the file's (sensor) frame, which
scanners such as Velodyne drivers emit for beams that saw nothing.  A real return at exactly the
sensor origin is physically impossible, so nothing of value is lost.

Every bad input (missing file, unknown format, truncated or corrupt data, NaN / inf
coordinates, an empty cloud) raises :class:`planner.errors.MapError` whose one-line message
names the file and the problem.
"""

from __future__ import annotations

import bz2
import gzip
import io as _stdio
import math
import os
import re
import warnings
import zlib
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numba import njit

from planner.errors import MapError
from planner.fsutil import atomic_path

__all__ = [
    "Obstacles",
    "Scenarios",
    "load_obstacles",
    "load_points",
    "load_posed_scans",
    "load_scenarios",
    "merge_scans",
    "save_points",
]

PathLike = str | os.PathLike

# Extension -> canonical format name.  Text formats may carry a .gz / .bz2 suffix on top.
_EXTENSIONS = {
    ".ply": "ply",
    ".pcd": "pcd",
    ".xyz": "xyz",
    ".txt": "xyz",
    ".dat": "xyz",
    ".npy": "npy",
    ".bt": "bt",
    ".3dmap": "3dmap",
}
# Explicit format names accepted by ``format=`` (aliases included).
_FORMAT_ALIASES = {
    "ply": "ply",
    "pcd": "pcd",
    "xyz": "xyz",
    "txt": "xyz",
    "dat": "xyz",
    "text": "xyz",
    "npy": "npy",
    "bt": "bt",
    "octomap": "bt",
    "3dmap": "3dmap",
    "movingai": "3dmap",
}
_COMPRESSIONS = (".gz", ".bz2")

# A corrupt .bt whose occupied leaves are huge (e.g. one at depth 1) would otherwise expand to
# billions of voxels and exhaust memory; no real map comes near this.
_MAX_EXPANDED_VOXELS = 100_000_000


# --------------------------------------------------------------------------------------------
# Result types
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True, eq=False)  # eq=False: element-wise array equality is not a bool
class Obstacles:
    """Everything a map file says about obstacles.

    Attributes
    ----------
    points : ndarray, shape (N, 3), float64
        Sensed obstacle points, metres.  May be empty, shape (0, 3).
    boxes : ndarray, shape (M, 3), float64
        Centres of solid axis-aligned cubes of edge ``box_size``, metres.  May be empty.
    box_size : float
        Edge length of every box, metres; 0.0 when there are no boxes.
    bounds : ndarray, shape (2, 3), or None
        ``[min, max]`` corners of the map's world box, metres, or None when the format has no
        intrinsic bounds (point clouds, OctoMap).
    resolution : float or None
        Native cell size, metres (OctoMap ``res``, 1.0 for ``.3dmap``); None for raw clouds.
    source : str
        File name the obstacles came from (``"<array>"`` or similar for in-memory data).
    """

    points: np.ndarray
    boxes: np.ndarray
    box_size: float
    bounds: np.ndarray | None
    resolution: float | None
    source: str

    def __post_init__(self) -> None:
        # Coerce once here so every consumer can rely on float64 (N, 3) arrays.
        for name in ("points", "boxes"):
            arr = np.asarray(getattr(self, name), dtype=np.float64)
            if arr.size == 0:
                arr = arr.reshape(0, 3)
            if arr.ndim != 2 or arr.shape[1] != 3:
                raise MapError(f"{self.source}: Obstacles.{name} must have shape (N, 3), "
                               f"got {arr.shape}")
            object.__setattr__(self, name, arr)
        if self.bounds is not None:
            b = np.asarray(self.bounds, dtype=np.float64)
            if b.shape != (2, 3):
                raise MapError(f"{self.source}: Obstacles.bounds must have shape (2, 3), "
                               f"got {b.shape}")
            object.__setattr__(self, "bounds", b)
        object.__setattr__(self, "box_size", float(self.box_size))


@dataclass(frozen=True, eq=False)
class Scenarios:
    """MovingAI ``.3dscen`` start/goal queries.

    Attributes
    ----------
    starts, goals : ndarray, shape (K, 3), int64
        Voxel coordinates (0-based; voxel (x, y, z) is the unit cube centred on that point).
    costs : ndarray, shape (K,), float64
        Optimal path cost (26-neighbour cubic lattice, no corner cutting), voxel units.
    heuristic_ratios : ndarray, shape (K,), float64
        Optimal cost divided by the octile heuristic, as listed in the file.
    map_name : str
        Map file named on the second line.
    source : str
        Scenario file name.
    """

    starts: np.ndarray
    goals: np.ndarray
    costs: np.ndarray
    heuristic_ratios: np.ndarray
    map_name: str
    source: str

    def __len__(self) -> int:
        return len(self.costs)


# --------------------------------------------------------------------------------------------
# Public readers
# --------------------------------------------------------------------------------------------


def load_obstacles(path: PathLike, format: str | None = None) -> Obstacles:
    """Read a map or point-cloud file into :class:`Obstacles`.

    Parameters
    ----------
    path : str or PathLike
        File to read.
    format : str, optional
        ``"ply"``, ``"pcd"``, ``"xyz"`` (aliases ``"txt"``, ``"dat"``), ``"npy"``, ``"bt"``
        (alias ``"octomap"``) or ``"3dmap"`` (alias ``"movingai"``).  Default: from the file
        extension (case-insensitive; text files may end in ``.gz`` / ``.bz2``).

    Returns
    -------
    Obstacles
        Point clouds fill ``points`` only.  ``.3dmap`` fills ``boxes`` (unit voxel centres),
        ``box_size=1``, ``bounds=[[-.5]*3, [X-.5, Y-.5, Z-.5]]``, ``resolution=1``.  ``.bt``
        fills both ``points`` and ``boxes`` with the occupied finest-voxel centres,
        ``box_size = resolution = res``, ``bounds=None``.

    Raises
    ------
    MapError
        Missing file, unknown format, truncated / corrupt content, NaN or infinite
        coordinates, or no obstacles at all.
    """
    p = Path(path)
    fmt, compression = _resolve_format(p, format)
    if not p.is_file():
        raise MapError(f"{p}: file not found" if not p.exists() else f"{p}: not a regular file")
    try:
        if fmt == "ply":
            obst = _read_ply(p)
        elif fmt == "pcd":
            obst = _read_pcd(p)
        elif fmt == "xyz":
            obst = _read_xyz(p, compression)
        elif fmt == "npy":
            obst = _read_npy(p)
        elif fmt == "bt":
            obst = _read_octomap(p)
        else:
            obst = _read_3dmap(p)
    except MapError:
        raise
    except OSError as exc:  # permission denied, I/O error, ...
        raise MapError(f"{p.name}: cannot read file: {exc.strerror or exc}") from exc
    except MemoryError as exc:
        raise MapError(f"{p.name}: file too large to load") from exc
    except (ValueError, IndexError, TypeError, KeyError, EOFError) as exc:
        # Safety net: every known corruption is reported specifically above; anything that
        # slips through still surfaces as a MapError naming the file.
        msg = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise MapError(f"{p.name}: corrupt {fmt} file ({msg})") from exc
    return obst


def load_points(path: PathLike, format: str | None = None) -> np.ndarray:
    """Read obstacle points from any supported file.

    Parameters
    ----------
    path, format
        As for :func:`load_obstacles`.

    Returns
    -------
    ndarray, shape (N, 3), float64
        Metres.  The sensed points of a cloud (no-return ``(0, 0, 0)`` rows dropped), or, for
        voxel maps without sensed points (``.3dmap``), the voxel centres.

    Raises
    ------
    MapError
        As for :func:`load_obstacles`.
    """
    obst = load_obstacles(path, format)
    return obst.points if len(obst.points) else obst.boxes


def load_scenarios(path: PathLike) -> Scenarios:
    """Read a MovingAI ``.3dscen`` file.

    The file is ``version 1``, the map name, then one
    ``sx sy sz gx gy gz optimal_cost heuristic_ratio`` line per query.

    Parameters
    ----------
    path : str or PathLike

    Returns
    -------
    Scenarios
        ``starts`` / ``goals`` (K, 3) int64 voxel coordinates, ``costs`` (K,) float64.

    Raises
    ------
    MapError
        Missing file, bad header, malformed or non-finite rows, no queries.
    """
    p = Path(path)
    text = _read_text(p)
    lines = text.splitlines()
    if len(lines) < 2 or not re.fullmatch(r"version\s+\S+", lines[0].strip()):
        raise MapError(f"{p.name}: not a .3dscen file (first line must be 'version 1')")
    map_name = lines[1].strip()
    body = "\n".join(lines[2:])
    table = _loadtxt(body, p.name, ncols=8, first_line=3, exact=True)
    if not len(table):
        raise MapError(f"{p.name}: contains no queries")
    if not np.isfinite(table).all():
        raise MapError(f"{p.name}: contains NaN or infinite values")
    coords = table[:, :6]
    if not np.array_equal(coords, np.round(coords)):
        raise MapError(f"{p.name}: start/goal coordinates must be integers")
    return Scenarios(
        starts=coords[:, :3].astype(np.int64),
        goals=coords[:, 3:6].astype(np.int64),
        costs=table[:, 6].copy(),
        heuristic_ratios=table[:, 7].copy(),
        map_name=map_name,
        source=p.name,
    )


# --------------------------------------------------------------------------------------------
# Posed scans
# --------------------------------------------------------------------------------------------


def merge_scans(scans: list[np.ndarray], poses) -> np.ndarray:
    """Transform sensor-frame scans into the world frame and concatenate them.

    Parameters
    ----------
    scans : list of ndarray, each shape (N_i, 3)
        Points in each scan's sensor frame, metres.  Rows exactly ``(0, 0, 0)`` are no-returns
        and are dropped before transforming (after it they would be the sensor position).
    poses : sequence of ndarray shape (4, 4), or ndarray shape (K, 4, 4)
        Sensor-to-world homogeneous transforms, one per scan (``p_world = R @ p + t``).

    Returns
    -------
    ndarray, shape (sum N_i, 3), float64
        World-frame points, metres, in scan order.

    Raises
    ------
    MapError
        Count mismatch, a pose that is not a finite rigid transform, bad scan shapes, or no
        points at all.
    """
    poses_arr = np.asarray(poses, dtype=np.float64)
    if poses_arr.ndim != 3 or poses_arr.shape[1:] != (4, 4):
        raise MapError(f"merge_scans: poses must be 4x4 matrices, got shape {poses_arr.shape}")
    if len(scans) != len(poses_arr):
        raise MapError(f"merge_scans: {len(scans)} scans but {len(poses_arr)} poses")
    out = []
    for i, (scan, pose) in enumerate(zip(scans, poses_arr, strict=True)):
        _check_pose(pose, f"merge_scans: pose {i}")
        pts = np.asarray(scan, dtype=np.float64)
        if pts.ndim != 2 or pts.shape[1] != 3:
            raise MapError(f"merge_scans: scan {i} must have shape (N, 3), got {pts.shape}")
        if not np.isfinite(pts).all():
            raise MapError(f"merge_scans: scan {i} contains NaN or infinite coordinates")
        pts = _drop_no_returns(pts)
        out.append(pts @ pose[:3, :3].T + pose[:3, 3])
    merged = np.concatenate(out) if out else np.zeros((0, 3))
    if not len(merged):
        raise MapError("merge_scans: no points to merge")
    return merged


def load_posed_scans(path: PathLike) -> np.ndarray:
    """Read a pose list and merge its scans into one world-frame cloud.

    Each non-comment line is ``scan_path`` followed by either 16 numbers (the 4x4
    sensor-to-world matrix, row-major) or 7 numbers ``x y z qx qy qz qw`` (translation in
    metres and a rotation quaternion, normalised here).  Separators are whitespace and / or
    commas; ``#`` starts a comment.  Relative scan paths are relative to the pose file's folder.

    Parameters
    ----------
    path : str or PathLike
        Pose list file.

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
    p = Path(path)
    text = _read_text(p)
    scans, poses = [], []
    for lineno, raw in enumerate(text.splitlines(), start=1):
        line = raw.split("#", 1)[0].strip()
        if not line:
            continue
        tokens = [t for t in re.split(r"[\s,]+", line) if t]
        where = f"{p.name}:{lineno}"
        try:
            nums = [float(t) for t in tokens[1:]]
        except ValueError:
            raise MapError(f"{where}: pose values must be numbers") from None
        if len(nums) == 16:
            pose = np.array(nums).reshape(4, 4)
        elif len(nums) == 7:
            pose = _pose_from_quaternion(nums, where)
        else:
            raise MapError(f"{where}: expected a scan path then 16 (4x4) or 7 (x y z qx qy qz "
                           f"qw) numbers, got {len(nums)}")
        _check_pose(pose, where)
        scan_path = Path(tokens[0])
        if not scan_path.is_absolute():
            scan_path = p.parent / scan_path
        scans.append(load_points(scan_path))
        poses.append(pose)
    if not scans:
        raise MapError(f"{p.name}: lists no scans")
    return merge_scans(scans, poses)


def _pose_from_quaternion(nums: list[float], where: str) -> np.ndarray:
    x, y, z, qx, qy, qz, qw = nums
    n = math.sqrt(qx * qx + qy * qy + qz * qz + qw * qw)
    if not math.isfinite(n) or n < 1e-12:
        raise MapError(f"{where}: quaternion has zero or non-finite norm")
    qx, qy, qz, qw = qx / n, qy / n, qz / n, qw / n
    pose = np.eye(4)
    pose[:3, :3] = [
        [1 - 2 * (qy * qy + qz * qz), 2 * (qx * qy - qz * qw), 2 * (qx * qz + qy * qw)],
        [2 * (qx * qy + qz * qw), 1 - 2 * (qx * qx + qz * qz), 2 * (qy * qz - qx * qw)],
        [2 * (qx * qz - qy * qw), 2 * (qy * qz + qx * qw), 1 - 2 * (qx * qx + qy * qy)],
    ]
    pose[:3, 3] = (x, y, z)
    return pose


def _check_pose(pose: np.ndarray, where: str) -> None:
    if not np.isfinite(pose).all():
        raise MapError(f"{where}: pose contains NaN or infinite values")
    if not np.allclose(pose[3], (0.0, 0.0, 0.0, 1.0), atol=1e-9):
        raise MapError(f"{where}: pose last row must be 0 0 0 1")
    r = pose[:3, :3]
    # Loose tolerance: poses saved with 6 significant digits are still accepted.
    if not np.allclose(r @ r.T, np.eye(3), atol=1e-3) or np.linalg.det(r) < 0:
        raise MapError(f"{where}: pose rotation is not a proper rotation matrix")


# --------------------------------------------------------------------------------------------
# Writer
# --------------------------------------------------------------------------------------------


def save_points(path: PathLike, points: np.ndarray, *, dtype=np.float64) -> None:
    """Write points atomically (temporary file in the same folder, then rename).

    Parameters
    ----------
    path : str or PathLike
        Target; the extension picks the format: ``.ply`` (binary little endian vertex
        ``x, y, z``), ``.npy``, or ``.xyz`` / ``.txt`` / ``.dat`` (optionally ``.gz`` / ``.bz2``;
        one ``x y z`` line per point, 17 significant digits so float64 round-trips exactly).
    points : ndarray, shape (N, 3)
        Metres; finite, at least one point.
    dtype : numpy dtype, default float64
        Stored precision for ``.ply`` and ``.npy`` (float32 or float64).

    Raises
    ------
    MapError
        Unknown extension, bad shape, NaN / inf, no points, or unsupported ``dtype``.
    """
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
    with atomic_path(p) as tmp:
        if fmt == "ply":
            from plyfile import PlyData, PlyElement

            le = dt.newbyteorder("<")
            vert = np.empty(len(pts), dtype=[("x", le), ("y", le), ("z", le)])
            vert["x"], vert["y"], vert["z"] = pts[:, 0], pts[:, 1], pts[:, 2]
            ply = PlyData([PlyElement.describe(vert, "vertex")], text=False, byte_order="<")
            with open(tmp, "wb") as f:
                ply.write(f)
        elif fmt == "npy":
            with open(tmp, "wb") as f:  # a file object: np.save(path) would append ".npy"
                np.save(f, pts.astype(dt))
        else:
            opener = {None: open, ".gz": gzip.open, ".bz2": bz2.open}[compression]
            with opener(tmp, "wt") as f:
                np.savetxt(f, pts, fmt="%.17g")


# --------------------------------------------------------------------------------------------
# Helpers shared by readers
# --------------------------------------------------------------------------------------------


def _resolve_format(p: Path, format: str | None) -> tuple[str, str | None]:
    """(canonical format, compression suffix or None) from ``format`` or the file name."""
    suffixes = [s.lower() for s in p.suffixes]
    compression = suffixes[-1] if suffixes and suffixes[-1] in _COMPRESSIONS else None
    if format is not None:
        fmt = _FORMAT_ALIASES.get(str(format).lower().lstrip("."))
        if fmt is None:
            raise MapError(f"{p.name}: unknown format '{format}' (known: "
                           f"{', '.join(sorted(_FORMAT_ALIASES))})")
    else:
        ext = suffixes[-2] if compression and len(suffixes) >= 2 else (
            suffixes[-1] if suffixes and not compression else "")
        fmt = _EXTENSIONS.get(ext)
        if fmt is None:
            raise MapError(f"{p.name}: unknown file extension '{''.join(p.suffixes)}' (known: "
                           f"{', '.join(sorted(_EXTENSIONS))}, text also with .gz/.bz2)")
    if compression and fmt != "xyz":
        raise MapError(f"{p.name}: {compression} compression is only supported for text XYZ")
    return fmt, compression


def _read_bytes(p: Path) -> bytes:
    if not p.is_file():
        raise MapError(f"{p}: file not found" if not p.exists() else f"{p}: not a regular file")
    try:
        return p.read_bytes()
    except OSError as exc:
        raise MapError(f"{p.name}: cannot read file: {exc.strerror or exc}") from exc


def _read_text(p: Path, compression: str | None = None) -> str:
    data = _read_bytes(p)
    try:
        if compression == ".gz":
            data = gzip.decompress(data)
        elif compression == ".bz2":
            data = bz2.decompress(data)
    except (OSError, EOFError, ValueError, zlib.error) as exc:
        raise MapError(f"{p.name}: corrupt or truncated {compression} data ({exc})") from exc
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError:
        raise MapError(f"{p.name}: not a text file (invalid UTF-8)") from None


def _loadtxt(text: str, name: str, ncols: int, first_line: int = 1, exact: bool = False,
             usecols: tuple[int, ...] | None = None) -> np.ndarray:
    """Parse whitespace/comma separated numbers, '#' comments, as float64 (rows, ncols).

    ``exact`` requires exactly ``ncols`` columns per row; otherwise each row needs the
    ``usecols`` columns (default the first ``ncols``) and any other columns are ignored.
    ``first_line`` is the file line number of ``text``'s first line, for messages.
    """
    if "," in text:
        text = text.replace(",", " ")
    cols = usecols if usecols is not None else tuple(range(ncols))
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", UserWarning)  # "input contained no data": fine
            if exact:
                arr = np.loadtxt(_stdio.StringIO(text), dtype=np.float64, comments="#",
                                 ndmin=2)
            else:
                arr = np.loadtxt(_stdio.StringIO(text), dtype=np.float64, comments="#",
                                 ndmin=2, usecols=cols)
        ok = arr.size == 0 or arr.shape[1] == ncols
    except ValueError:
        ok = False
    if not ok:
        # numpy's row numbers skip comments and differ between its messages, so find the
        # offending line ourselves (error path only, speed irrelevant).
        raise MapError(f"{name}: {_describe_bad_line(text, ncols, exact, cols, first_line)}")
    return arr if arr.size else np.zeros((0, ncols))


def _describe_bad_line(text: str, ncols: int, exact: bool, cols: tuple[int, ...],
                       first_line: int) -> str:
    for i, raw in enumerate(text.splitlines()):
        tokens = raw.split("#", 1)[0].split()
        if not tokens:
            continue
        if exact and len(tokens) != ncols:
            bad = f"expected {ncols} numbers, got {len(tokens)}"
        elif len(tokens) <= max(cols):
            bad = f"expected at least {max(cols) + 1} numbers, got {len(tokens)}"
        else:
            try:
                [float(tokens[c]) for c in (range(ncols) if exact else cols)]
                continue
            except ValueError:
                bad = "not a number"
        return f"malformed line {i + first_line} ({bad}): {raw.strip()[:60]!r}"
    return "malformed numeric text"


def _drop_no_returns(pts: np.ndarray) -> np.ndarray:
    """Remove rows exactly (0, 0, 0): scanners' encoding of 'no return' (see module doc)."""
    zero = (pts[:, 0] == 0.0) & (pts[:, 1] == 0.0) & (pts[:, 2] == 0.0)
    return pts[~zero] if zero.any() else pts


def _cloud(pts: np.ndarray, p: Path) -> Obstacles:
    """Validate a raw sensor cloud and wrap it (drops no-returns)."""
    pts = np.ascontiguousarray(pts, dtype=np.float64)
    if not np.isfinite(pts).all():
        bad = int((~np.isfinite(pts).all(axis=1)).sum())
        raise MapError(f"{p.name}: {bad} points have NaN or infinite coordinates")
    n_raw = len(pts)
    pts = _drop_no_returns(pts)
    if not len(pts):
        what = "no points" if n_raw == 0 else f"only no-return (0,0,0) points ({n_raw})"
        raise MapError(f"{p.name}: point cloud is empty ({what})")
    return Obstacles(points=pts, boxes=np.zeros((0, 3)), box_size=0.0, bounds=None,
                     resolution=None, source=p.name)


# --------------------------------------------------------------------------------------------
# PLY, text, npy
# --------------------------------------------------------------------------------------------


def _read_ply(p: Path) -> Obstacles:
    from plyfile import PlyData

    try:
        ply = PlyData.read(str(p))
    except Exception as exc:  # plyfile raises many types (PlyParseError, ValueError, ...)
        msg = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise MapError(f"{p.name}: corrupt or truncated PLY ({msg})") from None
    if "vertex" not in ply:
        raise MapError(f"{p.name}: PLY file has no 'vertex' element")
    vert = ply["vertex"].data
    names = vert.dtype.names or ()
    missing = [c for c in "xyz" if c not in names]
    if missing:
        raise MapError(f"{p.name}: PLY vertex element lacks properties {missing}")
    try:
        pts = np.column_stack([np.asarray(vert[c], dtype=np.float64) for c in "xyz"])
    except (TypeError, ValueError):
        raise MapError(f"{p.name}: PLY vertex x/y/z are not scalar numbers") from None
    return _cloud(pts.reshape(-1, 3), p)


def _read_xyz(p: Path, compression: str | None) -> Obstacles:
    text = _read_text(p, compression)
    pts = _loadtxt(text, p.name, ncols=3)
    return _cloud(pts, p)


def _read_npy(p: Path) -> Obstacles:
    try:
        arr = np.load(p, allow_pickle=False)
    except (ValueError, EOFError) as exc:  # bad magic, truncated data, pickled object array
        msg = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise MapError(f"{p.name}: not a valid .npy array ({msg})") from None
    if not isinstance(arr, np.ndarray) or arr.ndim != 2 or arr.shape[1] != 3:
        raise MapError(f"{p.name}: .npy array must have shape (N, 3), got "
                       f"{getattr(arr, 'shape', None)}")
    if arr.dtype.kind not in "fiu":
        raise MapError(f"{p.name}: .npy array must be numeric, got dtype {arr.dtype}")
    return _cloud(arr, p)


# --------------------------------------------------------------------------------------------
# PCD
# --------------------------------------------------------------------------------------------

_PCD_TYPES = {("F", 4): "f4", ("F", 8): "f8", ("I", 1): "i1", ("I", 2): "i2", ("I", 4): "i4",
              ("I", 8): "i8", ("U", 1): "u1", ("U", 2): "u2", ("U", 4): "u4", ("U", 8): "u8"}


def _read_pcd(p: Path) -> Obstacles:
    data = _read_bytes(p)
    hdr: dict[str, list[str]] = {}
    pos = 0
    # The header is ASCII lines ending with the DATA line; binary follows right after it.
    for _ in range(64):
        nl = data.find(b"\n", pos)
        if nl < 0:
            raise MapError(f"{p.name}: PCD header has no DATA line")
        line = data[pos:nl].decode("ascii", errors="replace").strip()
        pos = nl + 1
        if not line or line.startswith("#"):
            continue
        key, *vals = line.split()
        hdr[key.upper()] = vals
        if key.upper() == "DATA":
            break
    else:
        raise MapError(f"{p.name}: PCD header has no DATA line")

    def need(key: str) -> list[str]:
        if key not in hdr or not hdr[key]:
            raise MapError(f"{p.name}: PCD header lacks {key}")
        return hdr[key]

    fields = need("FIELDS")
    try:
        sizes = [int(s) for s in need("SIZE")]
        counts = [int(c) for c in hdr.get("COUNT", ["1"] * len(fields))]
        width, height = int(need("WIDTH")[0]), int(hdr.get("HEIGHT", ["1"])[0])
        npts = int(hdr["POINTS"][0]) if "POINTS" in hdr else width * height
    except ValueError:
        raise MapError(f"{p.name}: PCD header has a non-integer SIZE/COUNT/WIDTH/HEIGHT/POINTS") \
            from None
    types = [t.upper() for t in need("TYPE")]
    if not (len(fields) == len(sizes) == len(types) == len(counts)):
        raise MapError(f"{p.name}: PCD header FIELDS/SIZE/TYPE/COUNT lengths differ")
    if npts != width * height or npts < 0 or min(counts) < 1:
        raise MapError(f"{p.name}: PCD header POINTS {npts} != WIDTH*HEIGHT {width * height}")
    dtypes = []
    for f, s, t in zip(fields, sizes, types, strict=True):
        dt = _PCD_TYPES.get((t, s))
        if dt is None:
            raise MapError(f"{p.name}: PCD field {f!r} has unsupported TYPE {t} SIZE {s}")
        dtypes.append(np.dtype("<" + dt))
    idx = {}
    for c in "xyz":
        if c not in fields:
            raise MapError(f"{p.name}: PCD has no '{c}' field (FIELDS {' '.join(fields)})")
        idx[c] = fields.index(c)
    kind = need("DATA")[0].lower()
    point_step = sum(s * c for s, c in zip(sizes, counts, strict=True))
    # Byte offset of each field within one point (binary) / column index (ascii).
    byte_off = np.concatenate([[0], np.cumsum([s * c for s, c in zip(sizes, counts,
                                                                     strict=True)])])
    col_off = np.concatenate([[0], np.cumsum(counts)])

    if kind == "ascii":
        text = data[pos:].decode("ascii", errors="replace")
        cols = tuple(int(col_off[idx[c]]) for c in "xyz")
        if not text.strip():
            pts = np.zeros((0, 3))
        else:
            pts = _loadtxt(text, p.name, ncols=3, usecols=cols)
        if len(pts) != npts:
            raise MapError(f"{p.name}: PCD header promises {npts} points, file holds {len(pts)}")
    elif kind == "binary":
        body = data[pos:]
        if len(body) < npts * point_step:
            raise MapError(f"{p.name}: truncated PCD: header promises {npts} points "
                           f"({npts * point_step} bytes), file holds {len(body)} bytes")
        rec = np.dtype({"names": list("xyz"),
                        "formats": [dtypes[idx[c]] for c in "xyz"],
                        "offsets": [int(byte_off[idx[c]]) for c in "xyz"],
                        "itemsize": point_step})
        arr = np.frombuffer(body, dtype=rec, count=npts)
        pts = np.column_stack([arr[c] for c in "xyz"]).astype(np.float64)
    elif kind == "binary_compressed":
        raw = _pcd_decompress(data[pos:], npts, point_step, p.name)
        cols = []
        for c in "xyz":
            i = idx[c]
            # Column-major after decompression: field i's block starts after all points of
            # the fields before it; with COUNT > 1 keep the first element.
            start = npts * int(byte_off[i])
            col = np.frombuffer(raw, dtype=dtypes[i], count=npts * counts[i], offset=start)
            cols.append(col[:: counts[i]])
        pts = np.column_stack(cols).astype(np.float64)
    else:
        raise MapError(f"{p.name}: unknown PCD DATA kind {kind!r}")
    return _cloud(pts.reshape(-1, 3), p)


def _pcd_decompress(body: bytes, npts: int, point_step: int, name: str) -> bytes:
    """Decompress a binary_compressed PCD body (after the DATA line) to npts*point_step bytes."""
    expected = npts * point_step
    if len(body) < 8:
        raise MapError(f"{name}: truncated PCD: binary_compressed size fields missing")
    csize, usize = np.frombuffer(body, dtype="<u4", count=2)
    csize, usize = int(csize), int(usize)
    if usize != expected:
        raise MapError(f"{name}: PCD header promises {npts} points ({expected} bytes), "
                       f"compressed block holds {usize} bytes")
    if len(body) - 8 < csize:
        raise MapError(f"{name}: truncated PCD: compressed block needs {csize} bytes, file "
                       f"holds {len(body) - 8}")
    if usize == 0:
        return b""
    src = np.frombuffer(body, dtype=np.uint8, count=csize, offset=8)
    out, n = _lzf_decompress(src, usize)
    if n != usize:
        raise MapError(f"{name}: corrupt LZF data in binary_compressed PCD")
    return out.tobytes()


@njit(cache=True)
def _lzf_decompress(src, out_len):  # pragma: no cover - compiled
    """LZF (liblzf) decompression of uint8 ``src`` into ``out_len`` bytes.

    Returns (out, n): ``n`` is the number of bytes produced, or -1 on corrupt input.
    """
    out = np.empty(out_len, np.uint8)
    ip = 0
    op = 0
    n = src.shape[0]
    while ip < n:
        ctrl = np.int64(src[ip])
        ip += 1
        if ctrl < 32:  # literal run of ctrl + 1 bytes
            length = ctrl + 1
            if ip + length > n or op + length > out_len:
                return out, -1
            for k in range(length):
                out[op + k] = src[ip + k]
            ip += length
            op += length
        else:  # back reference: length in the top 3 bits (7 = extended), 13-bit offset
            length = ctrl >> 5
            if length == 7:
                if ip >= n:
                    return out, -1
                length += np.int64(src[ip])
                ip += 1
            if ip >= n:
                return out, -1
            ref = op - ((ctrl & 0x1F) << 8) - np.int64(src[ip]) - 1
            ip += 1
            length += 2
            if ref < 0 or op + length > out_len:
                return out, -1
            for k in range(length):  # byte by byte: source and target may overlap
                out[op + k] = out[ref + k]
            op += length
    return out, op


# --------------------------------------------------------------------------------------------
# OctoMap .bt
# --------------------------------------------------------------------------------------------

_BT_MAGIC = "# Octomap OcTree binary file"
_BT_DEPTH = 16
_BT_CENTER = 32768


def _read_octomap(p: Path) -> Obstacles:
    data = _read_bytes(p)
    pos = 0
    first = True
    tree_id = size = res = None
    for _ in range(1000):
        nl = data.find(b"\n", pos)
        if nl < 0:
            raise MapError(f"{p.name}: OctoMap header has no 'data' line")
        line = data[pos:nl].decode("ascii", errors="replace").strip()
        pos = nl + 1
        if first:
            if not line.startswith(_BT_MAGIC):
                raise MapError(f"{p.name}: not an OctoMap .bt file (first line must be "
                               f"'{_BT_MAGIC}')")
            first = False
            continue
        if not line or line.startswith("#"):
            continue
        key, _, val = line.partition(" ")
        val = val.strip()
        try:
            if key == "id":
                tree_id = val
            elif key == "size":
                size = int(val)
            elif key == "res":
                res = float(val)
            elif key == "data":
                break
            else:
                raise MapError(f"{p.name}: unknown OctoMap header line {line[:40]!r}")
        except ValueError:
            raise MapError(f"{p.name}: bad OctoMap header value {line[:40]!r}") from None
    else:
        raise MapError(f"{p.name}: OctoMap header has no 'data' line")
    if tree_id != "OcTree":
        raise MapError(f"{p.name}: unsupported OctoMap tree id {tree_id!r} (need 'OcTree')")
    if size is None or res is None:
        raise MapError(f"{p.name}: OctoMap header lacks 'size' or 'res'")
    if not (math.isfinite(res) and res > 0):
        raise MapError(f"{p.name}: OctoMap resolution must be positive, got {res}")
    if size <= 0:
        raise MapError(f"{p.name}: OctoMap tree is empty (size {size})")

    stream = np.frombuffer(data, dtype=np.uint8, offset=pos)
    keys, depths, n_nodes, err = _bt_walk(stream)
    if err == 1:
        raise MapError(f"{p.name}: truncated OctoMap: bit stream ends inside the tree")
    if err == 2:
        raise MapError(f"{p.name}: corrupt OctoMap: tree deeper than {_BT_DEPTH} levels")
    if n_nodes != size:
        # OctoMap's own reader rejects this too ("Tree size mismatch").
        raise MapError(f"{p.name}: corrupt OctoMap: header says {size} nodes, stream has "
                       f"{n_nodes}")
    side = (1 << (_BT_DEPTH - depths)).astype(np.int64)
    total = int((side**3).sum())
    if total == 0:
        raise MapError(f"{p.name}: OctoMap has no occupied voxels")
    if total > _MAX_EXPANDED_VOXELS:
        raise MapError(f"{p.name}: OctoMap expands to {total} finest voxels (limit "
                       f"{_MAX_EXPANDED_VOXELS}); corrupt or too coarse")
    fine = _bt_expand(keys, side, total)
    centres = (fine - _BT_CENTER + 0.5) * res  # finest voxel key k -> centre (k-32768+.5)*res
    return Obstacles(points=centres, boxes=centres, box_size=res, bounds=None, resolution=res,
                     source=p.name)


@njit(cache=True)
def _bt_walk(stream):  # pragma: no cover - compiled
    """Depth-first walk of an OctoMap binary stream with an explicit stack.

    Returns (keys (L, 3) int64 min-corner keys of occupied leaves, depths (L,) int64,
    number of tree nodes incl. the root, error: 0 ok, 1 stream ended early, 2 too deep).
    """
    n = stream.shape[0]
    # Each 2-byte node holds at most 8 leaves, so 4 per byte bounds the leaf count.
    cap = max(8, 4 * n)
    keys = np.empty((cap, 3), np.int64)
    depths = np.empty(cap, np.int64)
    n_leaves = 0
    # Stack frame: node min-corner key, depth, 16 child-state bits, next child to visit.
    st_key = np.empty((_BT_DEPTH + 1, 3), np.int64)
    st_depth = np.empty(_BT_DEPTH + 1, np.int64)
    st_bits = np.empty(_BT_DEPTH + 1, np.int64)
    st_child = np.empty(_BT_DEPTH + 1, np.int64)
    if n < 2:
        return keys[:0], depths[:0], 0, 1
    top = 0
    st_key[0, 0] = 0
    st_key[0, 1] = 0
    st_key[0, 2] = 0
    st_depth[0] = 0
    st_bits[0] = np.int64(stream[0]) | (np.int64(stream[1]) << 8)
    st_child[0] = 0
    pos = 2
    n_nodes = 1
    while top >= 0:
        i = st_child[top]
        if i == 8:
            top -= 1
            continue
        st_child[top] = i + 1
        state = (st_bits[top] >> (2 * i)) & 3
        if state == 0:  # unknown: no node stored
            continue
        n_nodes += 1
        d = st_depth[top] + 1
        half = np.int64(1) << (_BT_DEPTH - d)
        kx = st_key[top, 0] + (i & 1) * half
        ky = st_key[top, 1] + ((i >> 1) & 1) * half
        kz = st_key[top, 2] + ((i >> 2) & 1) * half
        if state == 2:  # occupied leaf
            keys[n_leaves, 0] = kx
            keys[n_leaves, 1] = ky
            keys[n_leaves, 2] = kz
            depths[n_leaves] = d
            n_leaves += 1
        elif state == 3:  # inner node: its 2 bytes come next in the stream
            if d >= _BT_DEPTH:
                return keys[:0], depths[:0], n_nodes, 2
            if pos + 2 > n:
                return keys[:0], depths[:0], n_nodes, 1
            top += 1
            st_key[top, 0] = kx
            st_key[top, 1] = ky
            st_key[top, 2] = kz
            st_depth[top] = d
            st_bits[top] = np.int64(stream[pos]) | (np.int64(stream[pos + 1]) << 8)
            st_child[top] = 0
            pos += 2
    return keys[:n_leaves], depths[:n_leaves], n_nodes, 0


@njit(cache=True)
def _bt_expand(keys, side, total):  # pragma: no cover - compiled
    """Every finest-level key inside each leaf cube: (total, 3) float64."""
    out = np.empty((total, 3), np.float64)
    j = 0
    for leaf in range(keys.shape[0]):
        s = side[leaf]
        for dz in range(s):
            for dy in range(s):
                for dx in range(s):
                    out[j, 0] = keys[leaf, 0] + dx
                    out[j, 1] = keys[leaf, 1] + dy
                    out[j, 2] = keys[leaf, 2] + dz
                    j += 1
    return out


# --------------------------------------------------------------------------------------------
# MovingAI .3dmap
# --------------------------------------------------------------------------------------------


def _read_3dmap(p: Path) -> Obstacles:
    text = _read_text(p)
    head, _, body = text.partition("\n")
    m = re.fullmatch(r"voxel\s+(\d+)\s+(\d+)\s+(\d+)", head.strip())
    if not m:
        raise MapError(f"{p.name}: bad .3dmap header {head.strip()[:40]!r} "
                       f"(expected 'voxel X Y Z')")
    dims = np.array([int(g) for g in m.groups()], dtype=np.int64)
    if (dims <= 0).any():
        raise MapError(f"{p.name}: .3dmap dimensions must be positive, got {dims.tolist()}")
    vox = _loadtxt(body, p.name, ncols=3, first_line=2, exact=True)
    if not len(vox):
        raise MapError(f"{p.name}: .3dmap has no blocked voxels")
    if not np.array_equal(vox, np.round(vox)):
        raise MapError(f"{p.name}: .3dmap voxel coordinates must be integers")
    if (vox < 0).any() or (vox >= dims).any():
        row = int(np.nonzero(((vox < 0) | (vox >= dims)).any(axis=1))[0][0])
        raise MapError(f"{p.name}: voxel {vox[row].astype(int).tolist()} on line {row + 2} "
                       f"lies outside the {dims.tolist()} grid")
    bounds = np.stack([np.full(3, -0.5), dims - 0.5])
    return Obstacles(points=np.zeros((0, 3)), boxes=vox, box_size=1.0, bounds=bounds,
                     resolution=1.0, source=p.name)
