"""Verification of saved worlds: every key's schema and a digest over the arrays.

A saved world (:mod:`planner.world.file`) is read member by member through the checked
``.npy`` reader (:mod:`planner.npyfile`: declared sizes against the memory budget and the
member, no pickles, no trailing bytes); then :func:`check_schema` checks every key (type,
shape, dtype, range, a lattice name against its generator) and :func:`digest`
(BLAKE2b over every array's name, dtype, shape and bytes) against the ``digest`` stored at
save. Any mismatch is one ``MapError``: ``corrupt or modified world file: <what>``.
``check_source`` compares the source map's name and SHA-256 with a map file.
"""

from __future__ import annotations

import hashlib
import math
import os
import zipfile
import zlib
from pathlib import Path

import numpy as np

from planner._numba import njit_cached
from planner.errors import MapError, PlannerError
from planner.fsutil import sha256
from planner.io.obstacles import UNKNOWN_POLICIES
from planner.lattice import NAMED_LATTICES, Lattice
from planner.lattice.paper import NAMED_LATTICES_2D
from planner.lattice.planar import planar_prism
from planner.npyfile import read_array
from planner.occupancy.bits import n_bytes
from planner.world.cells import index_box
from planner.world.world import _BOUNDS_TOL

__all__ = ["KEYS", "OPTIONAL_KEYS", "check_schema", "check_source", "corrupt", "digest",
           "read_members"]

# every key a saved world holds, besides the digest over them
KEYS = ("format", "version", "generator", "lattice", "box", "blocked", "unknown", "bounds",
        "radius", "unknown_policy", "source", "source_sha256", "dim")
# keys a saved world may hold: ``offset`` (3,) float64, its local frame's origin in the map's
# frame (m; written only when non-zero, :attr:`planner.World.offset`)
OPTIONAL_KEYS = ("offset",)
_REL = 1e-9


def corrupt(path: Path, what: str) -> MapError:
    """The one error of a world file that fails a check."""
    return MapError(f"{path.name}: corrupt or modified world file: {what}")


def digest(arrays: dict[str, np.ndarray]) -> str:
    """Hex BLAKE2b (32 bytes) of the arrays in key order: name, dtype, shape and bytes, so a
    change of any value, type or shape changes it."""
    h = hashlib.blake2b(digest_size=32)
    for key in sorted(arrays):
        if key == "digest":
            continue
        a = np.ascontiguousarray(arrays[key])
        h.update(f"{key}|{a.dtype.str}|{a.shape}|".encode())
        h.update(a.tobytes())
    return h.hexdigest()


def read_members(path: Path) -> dict[str, np.ndarray]:
    """Every member of the ``.npz`` at ``path``, each read through
    :func:`planner.npyfile.read_array` (exactly the keys :data:`KEYS` and ``digest``, and
    any of :data:`OPTIONAL_KEYS`)."""
    try:
        with open(path, "rb") as f:  # np.savez writes no archive comment: the end record
            f.seek(max(0, f.seek(0, os.SEEK_END) - 22))  # is the last 22 bytes
            end = f.read(22)
        if len(end) == 22 and (end[:4] != b"PK\x05\x06" or end[20:22] != b"\0\0"):
            raise corrupt(path, "data after the end of the zip archive (or no end record)")
        with zipfile.ZipFile(path) as z:
            infos = z.infolist()
            names = [i.filename for i in infos]
            want = {f"{k}.npy" for k in (*KEYS, "digest")}
            if len(set(names)) != len(names):
                raise corrupt(path, "duplicate members")
            missing = sorted(want - set(names))
            if missing:
                raise corrupt(path, f"missing key {missing[0][:-4]!r}")
            extra = sorted(set(names) - want - {f"{k}.npy" for k in OPTIONAL_KEYS})
            if extra:
                raise corrupt(path, f"unexpected member {extra[0]!r}")
            out = {}
            for info in infos:
                with z.open(info) as f:
                    out[info.filename[:-4]] = read_array(f, info.file_size,
                                                         f"{path.name}: {info.filename}")
            return out
    except (zipfile.BadZipFile, EOFError, NotImplementedError, ValueError) as exc:
        if isinstance(exc, PlannerError):
            raise
        raise corrupt(path, f"not a readable .npz ({str(exc).splitlines()[0]})") from None
    except OSError as exc:
        raise MapError(f"{path.name}: cannot read saved world: {exc.strerror or exc}") from None


def _scalar(d: dict, key: str, kind: str):
    a = d[key]
    if a.shape != () or a.dtype.kind not in kind:
        raise ValueError(f"{key!r} must be a scalar of kind {kind!r}, got {a.dtype} {a.shape}")
    return a[()]


def check_schema(d: dict[str, np.ndarray], path: Path) -> None:
    """Every key of a saved world read by :func:`read_members` (version already checked).

    Raises
    ------
    MapError
        ``corrupt or modified world file: <what>`` for the first key that fails.
    """
    try:
        dim = int(_scalar(d, "dim", "iu"))
        if dim not in (2, 3):
            raise ValueError(f"'dim' must be 2 or 3, got {dim}")
        g, bounds = d["generator"], d["bounds"]
        if g.shape != (3, 3) or g.dtype != np.float64 or not np.isfinite(g).all():
            raise ValueError(f"'generator' must be a finite (3, 3) float64, got {g.dtype} "
                             f"{g.shape}")
        if (bounds.shape != (2, 3) or bounds.dtype != np.float64
                or not np.isfinite(bounds).all() or (bounds[1] < bounds[0]).any()):
            raise ValueError("'bounds' must be a finite (2, 3) float64 [min, max] box")
        off = d.get("offset")
        if off is not None and (off.shape != (3,) or off.dtype != np.float64
                                or not np.isfinite(off).all()):
            raise ValueError("'offset' must be a finite (3,) float64")
        radius = float(_scalar(d, "radius", "fiu"))
        if not (math.isfinite(radius) and radius >= 0):
            raise ValueError(f"'radius' must be a finite number >= 0, got {radius}")
        policy = str(_scalar(d, "unknown_policy", "U"))
        if policy not in UNKNOWN_POLICIES:
            raise ValueError(f"'unknown_policy' must be one of {UNKNOWN_POLICIES}, got "
                             f"{policy!r}")
        for key in ("source", "source_sha256"):
            _scalar(d, key, "U")
        sha = str(d["source_sha256"][()])
        if sha and (len(sha) != 64 or any(c not in "0123456789abcdef" for c in sha)):
            raise ValueError("'source_sha256' must be empty or 64 hex digits")
        name = str(_scalar(d, "lattice", "U"))
        gd = g[:2, :2] if dim == 2 else g
        lat = Lattice(gd, name=name or None)
        if name in NAMED_LATTICES + NAMED_LATTICES_2D:
            ref = Lattice.named(name, lat.cell_volume).generator
            if ref.shape != gd.shape or not np.allclose(ref, gd, rtol=_REL, atol=0):
                raise ValueError(f"'lattice' says {name!r}, the generator is another lattice")
        lo, hi = _tol_bounds(bounds, lat)
        box = d["box"]
        want = np.stack(index_box(g, lo, hi))
        if box.shape != (2, 3) or box.dtype != np.int64 or not np.array_equal(box, want):
            raise ValueError("'box' is not the index box of the generator and bounds")
        size = n_bytes(box[1])
        same = str(_scalar(d, "digest", "U")) == digest(d)
        bits = {key: _inflate(d[key], size, key) for key in ("blocked", "unknown")}
        code = _bits_check(bits["blocked"], bits["unknown"], box[0], box[1],
                           np.ascontiguousarray(g, dtype=np.float64), lo, hi, dim == 2)
        if code:
            raise ValueError(_CELL_PROBLEMS[code])
        # last: a well-formed file whose values were edited (cells removed, radius changed)
        if not same:
            raise ValueError("the arrays do not match the digest written at save")
        d["blocked_bits"], d["unknown_bits"] = bits["blocked"], bits["unknown"]
    except ValueError as exc:  # PlannerError is a ValueError: a bad lattice too
        raise corrupt(path, str(exc)) from None


_CELL_PROBLEMS = {1: "bits set past the last cell of the box",
                  3: "'blocked' holds cells outside the bounds",
                  4: "'unknown' holds cells outside the bounds",
                  6: "a 2D world holds cells off the plane z = 0"}


def _inflate(a: np.ndarray, size: int, key: str) -> np.ndarray:
    """The ``size`` bytes of bits the zlib stream ``a`` (uint8) holds, read no further."""
    if a.ndim != 1 or a.dtype != np.uint8:
        raise ValueError(f"{key!r} must be a (K,) uint8 zlib stream, got {a.dtype} {a.shape}")
    z = zlib.decompressobj()
    try:
        out = z.decompress(a.tobytes(), size + 1)
    except zlib.error as exc:
        raise ValueError(f"{key!r} is not a readable zlib stream ({exc})") from None
    if len(out) != size or not z.eof or z.unused_data:
        raise ValueError(f"{key!r} must hold {size} bytes of bits over the box")
    return np.frombuffer(out, dtype=np.uint8).copy()


def _tol_bounds(bounds: np.ndarray, lat) -> tuple[np.ndarray, np.ndarray]:
    """The box a saved cell centre must lie in: :meth:`planner.World.in_bounds`'s."""
    size = 2.0 * (planar_prism(lat) if lat.dim == 2 else lat).packing_radius
    tol = _BOUNDS_TOL * max(float(np.abs(bounds).max()), size)
    return bounds[0] - tol, bounds[1] + tol


@njit_cached
def _bits_check(blocked, unknown, blo, dims, g, lo, hi, planar):  # pragma: no cover
    """0, or the first problem (:data:`_CELL_PROBLEMS`) of the saved bit sets over the box
    ``blo`` (3,), ``dims`` (3,): no bit past the last cell, every set cell's centre
    ``g @ cell`` in ``[lo, hi]`` (m), and ``z == 0`` when ``planar``. One pass over the
    set bits, no temporaries."""
    n = dims[0] * dims[1] * dims[2]
    plane = dims[1] * dims[2]
    for q in range(blocked.shape[0]):
        for which in range(2):
            v = blocked[q] if which == 0 else unknown[q]
            if v == 0:
                continue
            for t in range(8):
                if not (v >> t) & 1:
                    continue
                f = q * 8 + t
                if f >= n:
                    return 1
                i = blo[0] + f // plane
                j = blo[1] + (f // dims[2]) % dims[1]
                k = blo[2] + f % dims[2]
                if planar and k != 0:
                    return 6
                for r in range(3):
                    x = g[r, 0] * i + g[r, 1] * j + g[r, 2] * k
                    if not (lo[r] <= x <= hi[r]):
                        return 3 + which
    return 0


def check_source(world, map_path: str | os.PathLike | None = None) -> None:
    """The map a saved world was built from is unchanged: same name and SHA-256.

    ``map_path`` is the map file (None: the world's source name beside the world file, or
    in the current folder).

    Raises
    ------
    MapError
        The world names no source, the source is not found, or its bytes changed.
    """
    saved = Path(getattr(world, "saved_path", "") or "world.npz")
    src = Path(world.source or "").name
    if not src or not world.source_sha256:
        raise MapError(f"{saved.name}: records no source map file to check")
    if map_path is None:
        found = [p for p in (saved.parent / src, Path(src)) if p.is_file()]
        if not found:
            raise MapError(f"{saved.name}: source map {src} not found beside it or here "
                           "(--check-source)")
        map_path = found[0]
    p = Path(map_path)
    if p.name != src:
        raise MapError(f"{saved.name}: built from {src}, not {p.name}")
    if sha256(p) != world.source_sha256:
        raise MapError(f"{saved.name}: source map {p} has changed since the world was saved "
                       f"(SHA-256 differs); rebuild it with `planner world`")
