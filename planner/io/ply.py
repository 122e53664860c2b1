"""PLY point clouds: reading vertex ``x, y, z`` (ascii / binary) and the one PLY writer.

Files whose elements have only scalar properties (every point cloud) are read here with numpy,
checking that the data holds exactly what the header declares; files with list properties
(meshes with faces) go through ``plyfile``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from planner.errors import MapError
from planner.fsutil import atomic_path
from planner.io._files import header_lines, loadtxt, read_bytes
from planner.io.obstacles import Obstacles
from planner.io.validate import cloud

_TYPES = {"char": "i1", "int8": "i1", "uchar": "u1", "uint8": "u1", "short": "i2",
          "int16": "i2", "ushort": "u2", "uint16": "u2", "int": "i4", "int32": "i4",
          "uint": "u4", "uint32": "u4", "float": "f4", "float32": "f4", "double": "f8",
          "float64": "f8"}
_FORMATS = {"ascii": None, "binary_little_endian": "<", "binary_big_endian": ">"}


def read_ply(p: Path) -> Obstacles:
    """Vertex ``x, y, z`` of a PLY file as a cloud (see :func:`planner.io.load_obstacles`)."""
    data = read_bytes(p)
    if not data.startswith(b"ply"):
        raise MapError(f"{p.name}: corrupt PLY: not a PLY file (no 'ply' magic)")
    lines, pos = header_lines(data, p.name, "PLY", "end_header")
    fmt, elements = _parse_header(lines, p.name)
    if not any(name == "vertex" for name, _, _ in elements):
        raise MapError(f"{p.name}: PLY file has no 'vertex' element")
    if any(prop[0] == "list" for _, _, props in elements for prop in props):
        return _read_with_plyfile(p)
    names = [n for n, _, _ in elements]
    vi = names.index("vertex")
    _, n_vert, vprops = elements[vi]
    pnames = [prop[2] for prop in vprops]
    missing = [c for c in "xyz" if c not in pnames]
    if missing:
        raise MapError(f"{p.name}: PLY vertex element lacks properties {missing}")
    if fmt is None:
        pts = _ascii_vertices(data[pos:], p.name, elements, vi, [pnames.index(c) for c in "xyz"])
    else:
        dtypes = [np.dtype([(prop[2], fmt + _TYPES[prop[1]]) for prop in props])
                  for _, _, props in elements]
        sizes = [count * dt.itemsize for (_, count, _), dt in zip(elements, dtypes, strict=True)]
        body = len(data) - pos
        need = sum(sizes)
        if body < need:
            raise MapError(f"{p.name}: truncated PLY: header declares {need} bytes of data, "
                           f"file holds {body}")
        if body > need:
            raise MapError(f"{p.name}: PLY declares {n_vert} points, has more data "
                           f"({body - need} extra bytes)")
        vert = np.frombuffer(data, dtype=dtypes[vi], count=n_vert, offset=pos + sum(sizes[:vi]))
        pts = np.column_stack([vert[c].astype(np.float64) for c in "xyz"]) if n_vert else \
            np.zeros((0, 3))
    return cloud(pts, p.name)


def _parse_header(lines: list[str], name: str):
    """(byte-order char or None for ascii, [(element, count, [(kind, type, prop)])])."""
    if not lines or lines[0] != "ply":
        raise MapError(f"{name}: not a PLY file (first line must be 'ply')")
    fmt = ...
    elements: list[tuple[str, int, list]] = []
    for line in lines[1:-1]:
        tok = line.split()
        if not tok or tok[0] in ("comment", "obj_info"):
            continue
        if tok[0] == "format" and len(tok) == 3 and tok[1] in _FORMATS:
            fmt = _FORMATS[tok[1]]
        elif tok[0] == "element" and len(tok) == 3:
            try:
                count = int(tok[2])
            except ValueError:
                raise MapError(f"{name}: PLY element count {tok[2][:20]!r} is not an integer") \
                    from None
            if count < 0:
                raise MapError(f"{name}: PLY element {tok[1]!r} has a negative count")
            elements.append((tok[1], count, []))
        elif tok[0] == "property" and elements and len(tok) == 3 and tok[1] in _TYPES:
            elements[-1][2].append(("scalar", tok[1], tok[2]))
        elif (tok[0] == "property" and elements and len(tok) == 5 and tok[1] == "list"
              and tok[2] in _TYPES and tok[3] in _TYPES):
            elements[-1][2].append(("list", tok[3], tok[4]))
        else:
            raise MapError(f"{name}: bad PLY header line {line[:40]!r}")
    if fmt is ...:
        raise MapError(f"{name}: PLY header lacks a valid 'format' line")
    return fmt, elements


def _ascii_vertices(body: bytes, name: str, elements, vi: int, cols: list[int]) -> np.ndarray:
    rows = [ln for ln in body.decode("ascii", errors="replace").splitlines() if ln.strip()]
    declared = sum(count for _, count, _ in elements)
    n_vert = elements[vi][1]
    if len(rows) < declared:
        raise MapError(f"{name}: truncated PLY: header declares {declared} rows, file holds "
                       f"{len(rows)}")
    if len(rows) > declared:
        raise MapError(f"{name}: PLY declares {n_vert} points, has more data "
                       f"({len(rows) - declared} extra rows)")
    start = sum(count for _, count, _ in elements[:vi])
    text = "\n".join(rows[start:start + n_vert])
    nprops = len(elements[vi][2])
    table = loadtxt(text, name, ncols=nprops, exact=True) if n_vert else np.zeros((0, nprops))
    return table[:, cols]


def _read_with_plyfile(p: Path) -> Obstacles:
    from plyfile import PlyData

    try:
        ply = PlyData.read(str(p))
    except Exception as exc:  # plyfile raises many types (PlyParseError, ValueError, ...)
        msg = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise MapError(f"{p.name}: corrupt or truncated PLY ({msg})") from None
    vert = ply["vertex"].data
    names = vert.dtype.names or ()
    missing = [c for c in "xyz" if c not in names]
    if missing:
        raise MapError(f"{p.name}: PLY vertex element lacks properties {missing}")
    try:
        pts = np.column_stack([np.asarray(vert[c], dtype=np.float64) for c in "xyz"])
    except (TypeError, ValueError):
        raise MapError(f"{p.name}: PLY vertex x/y/z are not scalar numbers") from None
    return cloud(pts.reshape(-1, 3), p.name)


def write_ply(path: str | Path, points: np.ndarray, dtype=np.float32,
              comments: tuple[str, ...] = ()) -> None:
    """Write points atomically as a binary little-endian PLY (vertex ``x, y, z``).

    The bytes are those ``plyfile`` writes for the same data.

    Parameters
    ----------
    path : str or Path
        Target file.
    points : ndarray, shape (N, 3)
        Metres.
    dtype : float32 or float64
        Stored precision.
    comments : tuple of str
        Header ``comment`` lines (one line each).
    """
    dt = np.dtype(dtype).newbyteorder("<")
    name = {"f4": "float", "f8": "double"}[dt.str[1:]]
    pts = np.asarray(points, dtype=np.float64)
    vert = np.empty(len(pts), dtype=[("x", dt), ("y", dt), ("z", dt)])
    vert["x"], vert["y"], vert["z"] = pts[:, 0], pts[:, 1], pts[:, 2]
    if any("\n" in c for c in comments):
        raise MapError("PLY comments must be single lines")
    notes = "".join(f"comment {c}\n" for c in comments)
    header = (f"ply\nformat binary_little_endian 1.0\n{notes}element vertex {len(pts)}\n"
              f"property {name} x\nproperty {name} y\nproperty {name} z\nend_header\n")
    with atomic_path(path) as tmp, open(tmp, "wb") as f:
        f.write(header.encode("ascii"))
        f.write(vert.tobytes())
