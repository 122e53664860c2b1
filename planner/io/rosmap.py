"""ROS map_server occupancy maps: a ``.yaml`` description and its image (PGM read here).

The YAML keys are ``image``, ``resolution`` (m per pixel), ``origin`` ``[x, y, yaw]`` (the
lower-left pixel's corner, m and rad), ``occupied_thresh``, ``free_thresh``, ``negate`` and
``mode`` (``trinary``, ``scale`` or ``raw``).  As in map_server, a pixel's occupancy is
``(255 - v) / 255`` (``v / 255`` when negated); above ``occupied_thresh`` it is occupied,
below ``free_thresh`` free, otherwise unknown.  ``raw`` mode takes ``v`` as a percentage
(over 100: unknown).  The result is 2D: occupied and free pixels as square boxes of edge
``resolution``; unknown pixels stay unknown.
"""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np

from planner.errors import MapError
from planner.io._files import decode_text, read_bytes
from planner.io.obstacles import Obstacles

_MODES = ("trinary", "scale", "raw")


def read_rosmap(p: Path) -> Obstacles:
    """A map_server ``.yaml`` and its image as a 2D :class:`Obstacles` (see module doc)."""
    meta = parse_flat_yaml(decode_text(read_bytes(p), p.name), p.name)
    image = _get(meta, "image", str, p.name)
    res = _get(meta, "resolution", float, p.name)
    origin = _get(meta, "origin", list, p.name)
    occ_t = _get(meta, "occupied_thresh", float, p.name, 0.65)
    free_t = _get(meta, "free_thresh", float, p.name, 0.196)
    negate = _get(meta, "negate", int, p.name, 0)
    mode = _get(meta, "mode", str, p.name, "trinary")
    if not (math.isfinite(res) and 1e-6 <= res <= 1e4):
        raise MapError(f"{p.name}: 'resolution' must be between 1e-6 and 1e4 m, got {res}")
    if len(origin) != 3 or not all(isinstance(v, float) and math.isfinite(v) for v in origin):
        raise MapError(f"{p.name}: 'origin' must be three finite numbers [x, y, yaw]")
    if abs(origin[2]) > 1e-9:
        raise MapError(f"{p.name}: rotated maps (origin yaw {origin[2]:g}) are not supported")
    if not (0 <= free_t <= occ_t <= 1):
        raise MapError(f"{p.name}: need 0 <= free_thresh <= occupied_thresh <= 1, got "
                       f"{free_t} and {occ_t}")
    if mode not in _MODES:
        raise MapError(f"{p.name}: 'mode' must be one of {', '.join(_MODES)}, got {mode!r}")
    img_path = Path(image) if Path(image).is_absolute() else p.parent / image
    pix, maxval = read_image(img_path)
    if mode == "raw":
        occ = np.where(pix <= 100, pix / 100.0, np.nan)
    else:
        v = pix / float(maxval)
        occ = v if negate else 1.0 - v
    occupied = occ > occ_t
    free = occ < free_t  # NaN (raw unknown) compares False both ways: unknown
    h, w = pix.shape
    # Image row 0 is the top of the map (largest y).
    jj, ii = np.meshgrid(np.arange(w), np.arange(h))
    centres = np.stack([origin[0] + (jj + 0.5) * res, origin[1] + (h - 1 - ii + 0.5) * res],
                       axis=-1)
    bounds = np.array([[origin[0], origin[1]], [origin[0] + w * res, origin[1] + h * res]])
    return Obstacles(points=np.zeros((0, 2)), boxes=centres[occupied], box_size=res,
                     free_boxes=centres[free], free_box_sizes=np.full(int(free.sum()), res),
                     bounds=bounds, resolution=res, source=p.name, unknown_default="blocked",
                     dim=2)


def parse_flat_yaml(text: str, name: str) -> dict:
    """The flat ``key: value`` YAML map_server writes: numbers, strings, ``[a, b]`` lists."""
    out: dict = {}
    for lineno, raw in enumerate(text.splitlines(), start=1):
        line = raw.split("#", 1)[0].strip()
        if not line:
            continue
        key, sep, val = line.partition(":")
        if not sep or not key.strip():
            raise MapError(f"{name}:{lineno}: expected 'key: value', got {line[:40]!r}")
        val = val.strip()
        if val.startswith("["):
            if not val.endswith("]"):
                raise MapError(f"{name}:{lineno}: unterminated list")
            out[key.strip()] = [_scalar(t.strip()) for t in val[1:-1].split(",") if t.strip()]
        else:
            out[key.strip()] = _scalar(val)
    return out


def _scalar(tok: str):
    if len(tok) >= 2 and tok[0] == tok[-1] and tok[0] in "'\"":
        return tok[1:-1]
    if tok.lower() in ("true", "false"):
        return int(tok.lower() == "true")
    try:
        return float(tok)
    except ValueError:
        return tok


def _get(meta: dict, key: str, kind: type, name: str, default=None):
    if key not in meta:
        if default is None:
            raise MapError(f"{name}: map description lacks '{key}'")
        return default
    val = meta[key]
    if kind is int and isinstance(val, float) and val in (0.0, 1.0):
        return int(val)
    if kind is float and isinstance(val, float):
        return val
    if not isinstance(val, kind):
        raise MapError(f"{name}: '{key}' must be a {kind.__name__}, got {val!r:.40}")
    return val


def read_image(p: Path) -> tuple[np.ndarray, int]:
    """Grey levels (H, W) int64 and the maximum value: PGM (P5, P2) here, others via Pillow."""
    data = read_bytes(p)
    if data[:2] in (b"P5", b"P2"):
        return read_pgm(data, p.name)
    try:
        from PIL import Image
    except ImportError:  # pragma: no cover - Pillow comes with matplotlib
        raise MapError(f"{p.name}: only PGM images can be read without Pillow") from None
    try:
        with Image.open(p) as im:
            grey = np.asarray(im.convert("L"), dtype=np.int64)
    except Exception as exc:  # Pillow raises many types on corrupt images
        raise MapError(f"{p.name}: unreadable map image ({type(exc).__name__})") from None
    return grey, 255


_PGM_TOKEN = re.compile(rb"(?:\s|#[^\n]*\n?)*(\S+)")


def read_pgm(data: bytes, name: str) -> tuple[np.ndarray, int]:
    """Decode a binary (P5) or ASCII (P2) PGM image: (H, W) int64 grey levels, maxval."""
    pos = 2
    vals = []
    for _ in range(3):  # width, height, maxval (comments allowed between them)
        m = _PGM_TOKEN.match(data, pos)
        if not m or not m.group(1).isdigit():
            raise MapError(f"{name}: bad PGM header")
        vals.append(int(m.group(1)))
        pos = m.end()
    w, h, maxval = vals
    if not (w > 0 and h > 0 and 0 < maxval < 65536):
        raise MapError(f"{name}: bad PGM size {w}x{h} or maxval {maxval}")
    if w * h > 1 << 30:
        raise MapError(f"{name}: PGM of {w}x{h} pixels is too large")
    if data[:2] == b"P5":
        pos += 1  # exactly one whitespace byte before the raster
        dt = np.dtype(">u2") if maxval > 255 else np.dtype("u1")
        need = w * h * dt.itemsize
        if len(data) - pos < need:
            raise MapError(f"{name}: truncated PGM: needs {need} bytes of pixels, has "
                           f"{len(data) - pos}")
        pix = np.frombuffer(data, dtype=dt, count=w * h, offset=pos).astype(np.int64)
    else:
        tokens = re.sub(rb"#[^\n]*", b" ", data[pos:]).split()
        if len(tokens) != w * h:
            raise MapError(f"{name}: PGM declares {w}x{h} pixels, holds {len(tokens)} values")
        try:
            pix = np.array([int(t) for t in tokens], dtype=np.int64)
        except ValueError:
            raise MapError(f"{name}: PGM pixel values must be integers") from None
    if pix.max(initial=0) > maxval:
        raise MapError(f"{name}: PGM pixel value above maxval {maxval}")
    return pix.reshape(h, w), maxval
