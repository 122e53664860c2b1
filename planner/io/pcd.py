"""PCD point clouds (v0.7): ascii, binary and binary_compressed (LZF), organized or not.

Organized clouds (HEIGHT > 1, from RGB-D cameras and organized lidars) mark missing returns
with NaN; those points are dropped and counted, not an error.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from planner._numba import njit_cached
from planner.budget import require
from planner.errors import MapError
from planner.io._files import header_lines, loadtxt, read_bytes
from planner.io.obstacles import Obstacles
from planner.io.scans import with_origin
from planner.io.validate import cloud

_PCD_TYPES = {("F", 4): "f4", ("F", 8): "f8", ("I", 1): "i1", ("I", 2): "i2", ("I", 4): "i4",
              ("I", 8): "i8", ("U", 1): "u1", ("U", 2): "u2", ("U", 4): "u4", ("U", 8): "u8"}


def read_pcd(p: Path) -> Obstacles:
    """``x, y, z`` of a PCD file as a cloud (see :func:`planner.io.load_obstacles`)."""
    data = read_bytes(p)
    lines, pos = header_lines(data, p.name, "PCD", "DATA")
    hdr: dict[str, list[str]] = {}
    for line in lines:  # any number of header and comment lines
        if not line or line.startswith("#"):
            continue
        key, *vals = line.split()
        hdr[key.upper()] = vals

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
    if npts != width * height or min(npts, width, height) < 0 or min(counts) < 1:
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
            pts = loadtxt(text, p.name, ncols=3, usecols=cols)
        if len(pts) != npts:
            what = "has more data" if len(pts) > npts else "file holds fewer"
            raise MapError(f"{p.name}: PCD declares {npts} points, {what} ({len(pts)} rows)")
    elif kind == "binary":
        body = data[pos:]
        if len(body) < npts * point_step:
            raise MapError(f"{p.name}: truncated PCD: header promises {npts} points "
                           f"({npts * point_step} bytes), file holds {len(body)} bytes")
        if body[npts * point_step:].strip(b"\r\n\0 "):  # a trailing newline is harmless
            raise MapError(f"{p.name}: PCD declares {npts} points, has more data "
                           f"({len(body) - npts * point_step} extra bytes)")
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
    obst = cloud(pts.reshape(-1, 3), p.name)
    origin = _viewpoint(hdr.get("VIEWPOINT"), p.name)
    return obst if origin is None else with_origin(obst, origin)


_DEFAULT_VIEWPOINT = (0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0)


def _viewpoint(vals: list[str] | None, name: str) -> np.ndarray | None:
    """The sensor origin (3,) of a PCD's ``VIEWPOINT tx ty tz qw qx qy qz`` (m, in the
    cloud's frame), or None when it is absent or PCL's default ``0 0 0 1 0 0 0``: PCL writes
    that default for every cloud, a merged map too, so it says nothing about a sensor
    (``--origin 0,0,0`` says it for a scan saved in its sensor frame)."""
    if not vals:
        return None
    try:
        v = tuple(float(x) for x in vals)
    except ValueError:
        raise MapError(f"{name}: PCD VIEWPOINT must be 7 numbers, got {' '.join(vals)[:60]!r}")\
            from None
    if len(v) != 7 or not np.isfinite(v).all():
        raise MapError(f"{name}: PCD VIEWPOINT must be 7 finite numbers tx ty tz qw qx qy qz")
    return None if v == _DEFAULT_VIEWPOINT else np.array(v[:3])


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
    # NUL padding after the block is PCL's own output (its writer sizes the file ahead)
    if body[8 + csize:].strip(b"\r\n\0 "):
        raise MapError(f"{name}: {len(body) - 8 - csize} bytes of trailing data after the "
                       f"PCD's compressed block")
    if usize == 0:
        return b""
    if usize > 88 * csize + 32:  # an LZF back reference (3 bytes) yields at most 264 bytes
        raise MapError(f"{name}: corrupt PCD: {csize} compressed bytes cannot hold {usize}")
    require(float(usize), f"{name}: its {npts}-point compressed block")
    src = np.frombuffer(body, dtype=np.uint8, count=csize, offset=8)
    out, n = _lzf_decompress(src, usize)
    if n != usize:
        raise MapError(f"{name}: corrupt LZF data in binary_compressed PCD")
    return out.tobytes()


@njit_cached
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
