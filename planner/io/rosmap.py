"""ROS map_server occupancy maps: a ``.yaml`` description and its image (PGM read here).

The description is any YAML document (read with PyYAML, block or flow style) whose keys are
``image``, ``resolution`` (m per pixel), ``origin`` ``[x, y, yaw]`` (the
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

from planner.budget import require
from planner.errors import MapError
from planner.io._files import decode_text, read_bytes
from planner.io.obstacles import Obstacles

_MODES = ("trinary", "scale", "raw")


def read_rosmap(p: Path) -> Obstacles:
    """A map_server ``.yaml`` and its image as a 2D :class:`Obstacles` (see module doc)."""
    meta = load_map_yaml(decode_text(read_bytes(p), p.name), p.name)
    image = _get(meta, "image", "text", p.name)
    res = _get(meta, "resolution", "number", p.name)
    origin = _get(meta, "origin", "numbers", p.name)
    occ_t = _get(meta, "occupied_thresh", "number", p.name, 0.65)
    free_t = _get(meta, "free_thresh", "number", p.name, 0.196)
    negate = _get(meta, "negate", "flag", p.name, False)
    mode = _get(meta, "mode", "text", p.name, "trinary")
    if not (math.isfinite(res) and 1e-6 <= res <= 1e4):
        raise MapError(f"{p.name}: 'resolution' must be between 1e-6 and 1e4 m, got {res}")
    if len(origin) != 3 or not all(math.isfinite(v) for v in origin):
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


def load_map_yaml(text: str, name: str) -> dict:
    """The map description as a dict: any valid YAML (block or flow style) whose top level
    is a mapping.

    Raises
    ------
    MapError
        Not YAML, or not a mapping (one line, with the line number when YAML gives one).
    """
    import yaml

    try:
        _check_yaml_size(yaml, text, name)
        meta = yaml.safe_load(text)
    except RecursionError:
        raise MapError(f"{name}: not valid YAML (nested too deeply)") from None
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f"{name}:{mark.line + 1}" if mark is not None else name
        what = getattr(exc, "problem", None) or type(exc).__name__
        raise MapError(f"{where}: not valid YAML ({' '.join(str(what).split())})") from None
    if not isinstance(meta, dict):
        raise MapError(f"{name}: a map description is a YAML mapping of 'key: value', got "
                       f"{type(meta).__name__}")
    return meta


YAML_EVENTS = 10_000  # a map description has a dozen keys
YAML_ALIASES = 16  # k aliases expand a value at most ~e^(k/e) times: 16 -> ~360


def _check_yaml_size(yaml, text: str, name: str) -> None:
    """Refuse a description of more than :data:`YAML_EVENTS` parse events or
    :data:`YAML_ALIASES` aliases before anything is built from it: aliases share nodes, so
    a few lines can stand for billions of values (the "billion laughs")."""
    events = aliases = 0
    for ev in yaml.parse(text, Loader=yaml.SafeLoader):
        events += 1
        aliases += isinstance(ev, yaml.AliasEvent)
        if events > YAML_EVENTS or aliases > YAML_ALIASES:
            raise MapError(f"{name}: a map description of more than {YAML_EVENTS} values or "
                           f"{YAML_ALIASES} aliases (&anchor / *alias) is refused")


def _number(val) -> float | None:
    """A YAML number, or a scalar map_server reads as one (PyYAML's YAML 1.1 keeps ``1e-3``
    a string; yaml-cpp converts it); None otherwise."""
    if isinstance(val, bool):
        return None
    if isinstance(val, int | float):
        return float(val)
    if isinstance(val, str):
        try:
            return float(val)
        except ValueError:
            return None
    return None


def _get(meta: dict, key: str, kind: str, name: str, default=None):
    """``meta[key]`` as ``kind``: "text", "number", "numbers" (a list) or "flag" (an integer
    or true/false, as map_server's ``negate``)."""
    if key not in meta:
        if default is None:
            raise MapError(f"{name}: map description lacks '{key}'")
        return default
    val = meta[key]
    if kind == "text" and isinstance(val, str):
        return val
    if kind == "number" and (v := _number(val)) is not None:
        return v
    if kind == "numbers" and isinstance(val, list):
        nums = [_number(v) for v in val]
        if None not in nums:
            return nums
        raise MapError(f"{name}: '{key}' must be a list of numbers, got {val!r:.40}")
    if kind == "flag" and isinstance(val, int):  # bool is an int; non-zero negates
        return bool(val)
    wanted = {"text": "string", "number": "number", "numbers": "list of numbers",
              "flag": "integer or true/false"}[kind]
    raise MapError(f"{name}: '{key}' must be a {wanted}, got {val!r:.40}")


def read_image(p: Path) -> tuple[np.ndarray, int]:
    """Grey levels (H, W) int64 and the maximum value: PGM (P5, P2) here, others via Pillow."""
    data = read_bytes(p)
    if data[:2] in (b"P5", b"P2"):
        return read_pgm(data, p.name)
    try:
        from PIL import Image
    except ImportError:  # pragma: no cover - Pillow comes with matplotlib
        raise MapError(f"{p.name}: only PGM images can be read without Pillow") from None
    if data[:8] == b"\x89PNG\r\n\x1a\n":
        _check_png_end(data, p.name)
    try:
        with Image.open(p) as im:
            w, h = im.size
            require(_PIXEL_BYTES * float(w) * h, f"{p.name}: a {w}x{h} map image")
            grey = np.asarray(im.convert("L"), dtype=np.int64)
    except MapError:
        raise
    except Exception as exc:  # Pillow raises many types on corrupt images
        raise MapError(f"{p.name}: unreadable map image ({type(exc).__name__})") from None
    return grey, 255


# bytes per pixel while a map image becomes obstacles: grey levels, the masks, the (H, W)
# grids of cell centres and the boxes (int64 / float64)
_PIXEL_BYTES = 64


def _check_png_end(data: bytes, name: str) -> None:
    """Refuse bytes after a PNG's IEND chunk (data after a complete file, as elsewhere)."""
    end = data.rfind(b"IEND")
    if end >= 4 and len(data) > end + 8:  # type, then its 4-byte CRC: the file's end
        raise MapError(f"{name}: {len(data) - end - 8} bytes of data after the end of the "
                       f"PNG image")


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
    require(_PIXEL_BYTES * float(w) * h, f"{name}: a {w}x{h} map image")
    if data[:2] == b"P5":
        pos += 1  # exactly one whitespace byte before the raster
        dt = np.dtype(">u2") if maxval > 255 else np.dtype("u1")
        need = w * h * dt.itemsize
        if len(data) - pos < need:
            raise MapError(f"{name}: truncated PGM: needs {need} bytes of pixels, has "
                           f"{len(data) - pos}")
        if len(data) - pos > need:
            raise MapError(f"{name}: {len(data) - pos - need} bytes of data after the end of "
                           f"the PGM image")
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
