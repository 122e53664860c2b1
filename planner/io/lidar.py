"""Survey point formats (the ``robot`` extra): LAS / LAZ (laspy + lazrs), E57 (pye57)."""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np

from planner.budget import require as require_budget
from planner.errors import MapError
from planner.io.bag import first_line, require
from planner.io.obstacles import Obstacles
from planner.io.validate import cloud, finite_points


def read_las(p: Path) -> Obstacles:
    """LAS / LAZ points with each file's scale and offset applied (metres, world frame)."""
    laspy = require("laspy", ".las/.laz", p.name)
    if p.suffix.lower() == ".laz":
        require("lazrs", ".laz", p.name)
    check_las_header(p)
    try:
        las = laspy.read(str(p))
        # laspy's x/y/z are the stored integers times scale plus offset.
        xyz = np.column_stack([np.asarray(las.x, dtype=np.float64),
                               np.asarray(las.y, dtype=np.float64),
                               np.asarray(las.z, dtype=np.float64)])
    except MapError:
        raise
    except Exception as exc:  # laspy / lazrs raise their own error types on corrupt files
        raise MapError(f"{p.name}: unreadable LAS/LAZ ({first_line(exc)})") from None
    return cloud(xyz, p.name)


# A LAZ point takes at least this many bytes of compressed data on average (bounding the point
# count a file of a given size can honestly declare).
_MIN_LAZ_BYTES_PER_POINT = 0.05


def check_las_header(p: Path) -> None:
    """Refuse a LAS/LAZ header whose counts its file cannot hold, before laspy reads it
    (laspy trusts them: a flipped VLR count makes it read millions of empty records)."""
    size = p.stat().st_size
    with open(p, "rb") as f:
        head = f.read(375)
    if len(head) < 227 or head[:4] != b"LASF":
        raise MapError(f"{p.name}: not a LAS/LAZ file (no 'LASF' signature)")
    header_size, = np.frombuffer(head, "<u2", 1, 94)
    offset, n_vlrs = np.frombuffer(head, "<u4", 2, 96)
    record, = np.frombuffer(head, "<u2", 1, 105)
    count = int(np.frombuffer(head, "<u4", 1, 107)[0])
    if head[25] >= 4 and len(head) >= 255:  # LAS 1.4: the 64-bit count
        count = max(count, int(np.frombuffer(head, "<u8", 1, 247)[0]))
    if not (header_size <= offset <= size) or int(n_vlrs) * 54 > offset - header_size:
        raise MapError(f"{p.name}: corrupt LAS header ({int(n_vlrs)} VLRs and point data at "
                       f"byte {int(offset)} do not fit the {size}-byte file)")
    body = size - int(offset)
    compressed = (head[104] & 0x80) or p.suffix.lower() == ".laz"
    fits = count * _MIN_LAZ_BYTES_PER_POINT <= body if compressed else count * int(record) <= body
    if not fits:
        raise MapError(f"{p.name}: LAS header declares {count} points, the file holds "
                       f"{body} bytes of point data")
    if compressed:  # the chunk table fixes where the compressed points end
        end = _laz_end(p, head, int(offset), size)
    else:  # the header fixes the size: points, then LAS 1.4's extended VLRs
        end = _las_end(p, head, int(offset) + count * int(record), size)
    if end < size:
        raise MapError(f"{p.name}: {size - end} bytes of trailing data after the end of "
                       f"the LAS/LAZ data")


def _laz_end(p: Path, head: bytes, offset: int, size: int) -> int:
    """Byte offset where a LAZ file ends: after its chunk table, or after the extended VLRs
    that follow it (LAS 1.4). The table's length is found by encoding the decoded table
    again (LASzip's coding is deterministic, so the bytes must also agree); ``size`` when
    the file has no chunk table to check against (streamed LAZ, or no LASzip VLR)."""
    import laspy  # the robot extra: read_las required laspy
    try:
        import lazrs
    except ImportError:  # a compressed ".las" without lazrs: laspy refuses it
        return size

    with open(p, "rb") as f:
        f.seek(offset)
        start = int.from_bytes(f.read(8), "little", signed=True)
        if not offset + 8 <= start < size:
            return size  # table offset not written (-1) or unreadable: laspy decides
        try:
            with laspy.open(str(p)) as reader:
                vlrs = reader.header.vlrs
            raw = next(v.record_data for v in vlrs if v.record_id == 22204)
            vlr = lazrs.LazVlr(raw)
            f.seek(offset)
            table = lazrs.read_chunk_table(f, vlr)
            out = io.BytesIO()
            lazrs.write_chunk_table(out, table, vlr)
        except StopIteration:
            return size
        except Exception as exc:  # laspy / lazrs error types on corrupt headers or tables
            raise MapError(f"{p.name}: unreadable LAZ chunk table ({first_line(exc)})") from None
        encoded = out.getvalue()
        f.seek(start)
        if f.read(len(encoded)) != encoded:
            raise MapError(f"{p.name}: corrupt LAZ chunk table at byte {start}")
    return _las_end(p, head, start + len(encoded), size)


def _las_end(p: Path, head: bytes, points_end: int, size: int) -> int:
    """Byte offset where a LAS/LAZ file ends: at ``points_end`` (after its point records, or a
    LAZ's chunk table), or after the last extended VLR (LAS 1.4), each a 60-byte header
    and its declared payload."""
    if head[25] < 4 or len(head) < 247:
        return points_end
    start = int(np.frombuffer(head, "<u8", 1, 235)[0])
    n = int(np.frombuffer(head, "<u4", 1, 243)[0])
    if not n:
        return points_end
    if not points_end <= start <= size:
        raise MapError(f"{p.name}: corrupt LAS header (extended VLRs at byte {start})")
    end = start
    with open(p, "rb") as f:
        for _ in range(n):
            f.seek(end)
            rec = f.read(60)
            if len(rec) < 60:
                raise MapError(f"{p.name}: truncated LAS extended VLR")
            end += 60 + int(np.frombuffer(rec, "<u8", 1, 20)[0])
            if end > size:
                raise MapError(f"{p.name}: truncated LAS extended VLR")
    return end


_E57_POINT_BYTES = 160  # per declared point: pye57's arrays, ours, and the world's


def read_e57(p: Path) -> Obstacles:
    """Every scan of an E57 file, each moved into the file's frame by its pose.

    Points flagged invalid (``cartesianInvalidState``) are dropped by ``pye57``; spherical
    scans are converted to Cartesian by it; each scan's position is kept as its sensor origin.
    """
    pye57 = require("pye57", ".e57", p.name)
    pts_all, owner, origins, dropped = [], [], [], 0
    try:
        e57 = pye57.E57(str(p))
        try:
            declared = 0
            for i in range(e57.scan_count):
                header = e57.get_header(i)
                # before reading: the declared points of every scan so far against the
                # budget (the scan's arrays, the copies made from them and the world's)
                declared += int(getattr(header, "point_count", 0) or 0)
                require_budget(_E57_POINT_BYTES * float(declared),
                               f"{p.name}: {declared} E57 points")
                rot = getattr(header, "rotation", None)
                if header.has_pose() and rot is not None and not np.isfinite(
                        np.asarray(rot, dtype=np.float64)).all():
                    raise MapError(f"{p.name}: E57 scan {i} rotation is not finite")
                scan = e57.read_scan(i, transform=True, ignore_missing_fields=True)
                xyz = np.column_stack([np.asarray(scan[f"cartesian{c}"], dtype=np.float64)
                                       for c in "XYZ"])
                origin = (np.asarray(header.translation, dtype=np.float64).reshape(3)
                          if header.has_pose() else np.zeros(3))
                pts, keep = finite_points(xyz, p.name)
                dropped += len(keep) - len(pts)
                pts_all.append(pts)
                owner.append(np.full(len(pts), i, dtype=np.int64))
                origins.append(origin)
        finally:
            e57.close()
    except MapError:
        raise
    except Exception as exc:  # libE57Format raises its own error types on corrupt files
        raise MapError(f"{p.name}: unreadable E57 ({first_line(exc)})") from None
    points = np.concatenate(pts_all) if pts_all else np.zeros((0, 3))
    if not len(points):
        raise MapError(f"{p.name}: E57 file holds no finite points")
    if not np.isfinite(np.array(origins)).all():
        raise MapError(f"{p.name}: E57 scan pose is not finite")
    return Obstacles(points=points, boxes=np.zeros((0, 3)), box_size=0.0, bounds=None,
                     resolution=None, source=p.name, origins=np.array(origins),
                     point_origin=np.concatenate(owner), dropped_nonfinite=dropped)
