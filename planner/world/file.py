"""Saved worlds (``planner world MAP --out world.npz``): a built world, loaded without rebuilding.

File format (numpy ``.npz``, members stored uncompressed; written atomically):

* ``format`` = ``"planner.World"``, ``version`` = 3;
* ``generator`` (3, 3) float64 (m) and ``lattice`` (its name, ``""`` for a custom one);
* ``box`` (2, 3) int64: ``[lo, dims]`` of the world's index box (the one
  :class:`planner.World` derives from ``generator`` and ``bounds``);
* ``blocked`` and ``unknown``: zlib streams (uint8) of bit sets over that box
  (:mod:`planner.occupancy.bits`: ``ceil(prod(dims) / 8)`` bytes, C order, little bit
  order; decompressed to exactly that size, never more): the in-bounds blocked cells
  (inflated for ``radius``; under the ``"blocked"`` policy unknown space too) and the
  in-bounds cells meeting unknown space. Free cells are the in-bounds cells not blocked.
  Cells out of bounds are never free, so a path touches none of them and leaving them out
  changes no plan and no count. One bit a cell of the box before compression, and mostly
  long runs after it;
* ``bounds`` (2, 3) float64 (m), ``radius`` (m), ``unknown_policy``;
* ``offset`` (3,) float64 (m), only in a world built in a local frame (a map far from its
  origin, :mod:`planner.world.frame`): a map point is the local point plus ``offset``;
  ``bounds`` and the cells are local;
* ``source`` (the map file name) and ``source_sha256`` (hex digest of its bytes, ``""`` for
  in-memory data); ``dim`` (2 for a 2D map planned on a prism of its 2D lattice);
* ``digest``: hex BLAKE2b over every other array (:func:`planner.world.check.digest`).

Loading verifies the file (:mod:`planner.world.check`): each member's declared size
against the memory budget and the member, every key's type, shape, dtype, range and
order, the lattice name against the generator, and the digest. Any mismatch is a one-line
``MapError`` "corrupt or modified world file: <what>". The digest catches damage, not an
edit by someone who recomputes it: :mod:`planner.world.trust` rebuilds the cells from the
source map and compares them (``planner plan/compare WORLD``: by default when the unchanged
source is found, required with ``--check-source``).
"""

from __future__ import annotations

import math
import os
import zipfile
import zlib
from pathlib import Path

import numpy as np

from planner.errors import MapError
from planner.fsutil import atomic_path, sha256
from planner.lattice import Lattice
from planner.npyfile import read_array
from planner.world.check import check_schema, corrupt, read_members
from planner.world.check import digest as array_digest
from planner.world.world import DENSE_BUDGET, World

__all__ = ["FORMAT", "VERSION", "check_options", "is_world_file", "load_world", "save_world",
           "sha256"]

FORMAT = "planner.World"
VERSION = 3  # 2: every key checked and a digest over the arrays; 3: bit sets over the box
_REL = 1e-9



def is_world_file(path) -> bool:
    """True for an ``.npz`` that is not known to be another format: a world written by
    :func:`save_world`, or a damaged ``.npz`` (which :func:`load_world` then reports as a
    corrupt world file rather than as a map of no known format)."""
    if not isinstance(path, str | os.PathLike):
        return False
    p = Path(path)
    if p.suffix.lower() != ".npz" or not p.is_file():
        return False
    try:
        with zipfile.ZipFile(p) as z:
            info = z.getinfo("format.npy")
            with z.open(info) as f:
                fmt = read_array(f, info.file_size, p.name)
    except (OSError, ValueError, KeyError, EOFError, zipfile.BadZipFile,
            NotImplementedError):
        return True  # unreadable: corrupt, reported by load_world
    return not (fmt.shape == () and fmt.dtype.kind == "U" and str(fmt[()]) != FORMAT)


def save_world(world, path: str | os.PathLike) -> None:
    """Write ``world`` (a :class:`planner.World`, dense storage) to ``path`` (``.npz``)
    atomically.

    Raises
    ------
    MapError
        The world uses hash storage (its box is too large for bit sets).
    """
    src = world.source or ""
    digest = getattr(world, "source_sha256", "") or ""
    path_of_source = getattr(world, "source_file", "") or src
    if not digest and path_of_source and Path(path_of_source).is_file():
        digest = sha256(path_of_source)
    free, unknown = world.free_bits, world.unknown_bits
    if free is None:
        raise MapError("this world's box is too large for a saved world (hash storage); "
                       "give smaller bounds or larger cells")
    arrays = {
        "format": np.array(FORMAT), "version": np.array(VERSION, dtype=np.int64),
        "generator": np.asarray(world.lattice.generator, dtype=np.float64),
        "lattice": np.array(world.lattice.name or ""),
        "box": np.stack([free.lo, free.dims]).astype(np.int64),
        "blocked": _deflate(world.blocked_bits().bits), "unknown": _deflate(unknown.bits),
        "bounds": world.bounds, "radius": np.array(world.radius),
        "unknown_policy": np.array(world.unknown_policy),
        "source": np.array(Path(src).name if src else ""),
        "source_sha256": np.array(digest), "dim": np.array(getattr(world, "dim", 3)),
    }
    if world.local_frame:
        arrays["offset"] = world.offset
    arrays["digest"] = np.array(array_digest(arrays))
    with atomic_path(path) as tmp, open(tmp, "wb") as f:
        np.savez(f, **arrays)


def _deflate(bits: np.ndarray) -> np.ndarray:
    """A bit set as a zlib stream (uint8): mostly long runs, so kilobytes per megabyte."""
    return np.frombuffer(zlib.compress(bits.tobytes(), 6), dtype=np.uint8)


def load_world(path: str | os.PathLike):
    """Read a world written by :func:`save_world`.

    Returns
    -------
    World

    Raises
    ------
    MapError
        Not a saved world, another format version, or a damaged file.
    """
    p = Path(path)
    if not p.is_file():
        raise MapError(f"{p}: file not found" if not p.exists() else f"{p}: not a regular file")
    _check_version(p)
    d = read_members(p)
    check_schema(d, p)
    if str(d["format"][()]) != FORMAT:
        raise corrupt(p, f"format {str(d['format'][()])!r}")
    name = str(d["lattice"]) or None
    dim = int(d["dim"])
    g, bounds = d["generator"], d["bounds"]
    if dim == 2:  # the 2D lattice; World plans on its prism again
        g, bounds = g[:2, :2], bounds[:, :2]
    lat = Lattice(g, name=name)
    world = World(lat, np.zeros((0, dim), np.int64), bounds, source=str(d["source"]),
                  radius=float(d["radius"]), unknown_policy=str(d["unknown_policy"]),
                  dim=dim, dense_budget=max(DENSE_BUDGET, d["blocked"].nbytes),
                  offset=d.get("offset"))
    # check_schema found the box the world's own and the bits in bounds, as saved.
    free, unknown = world.free_bits, world.unknown_bits
    np.bitwise_and(free.bits, np.invert(d["blocked_bits"]), out=free.bits)
    unknown.bits[:] = d["unknown_bits"]
    free.changed()
    unknown.changed()
    world.source_sha256 = str(d["source_sha256"])
    world.saved_path = str(p)
    return world


def _check_version(p: Path) -> None:
    """MapError unless ``p`` is a saved world of this :data:`VERSION` (read from the small
    ``format`` and ``version`` members only, through the checked reader)."""
    try:
        with zipfile.ZipFile(p) as z:
            names = z.namelist()
            if "format.npy" not in names or "version.npy" not in names:
                raise corrupt(p, "no 'format' and 'version' keys (not a saved planner world)")
            head = {}
            for key in ("format", "version"):
                info = z.getinfo(f"{key}.npy")
                with z.open(info) as f:
                    head[key] = read_array(f, info.file_size, f"{p.name}: {key}.npy")
    except (zipfile.BadZipFile, EOFError, NotImplementedError) as exc:
        raise corrupt(p, f"not a readable .npz ({str(exc).splitlines()[0]})") from None
    except OSError as exc:
        raise MapError(f"{p.name}: cannot read saved world: {exc.strerror or exc}") from None
    fmt, ver = head["format"], head["version"]
    if fmt.shape != () or fmt.dtype.kind != "U" or str(fmt[()]) != FORMAT:
        raise corrupt(p, "'format' is not \"planner.World\"")
    if ver.shape != () or ver.dtype.kind not in "iu":
        raise corrupt(p, "'version' is not an integer")
    if int(ver[()]) != VERSION:
        raise MapError(f"{p.name}: saved world version {int(ver[()])}; this planner reads "
                       f"version {VERSION} (rebuild it with `planner world`)")


def check_options(world, lattice=None, cell_volume=None, radius=None, unknown=None,
                  bounds=None) -> None:
    """One-line MapError when an option asked for differs from what the saved world holds
    (another lattice, cell volume, radius, unknown policy or bounds): rebuild from the map
    instead of silently using the saved one."""
    name = os.path.basename(getattr(world, "saved_path", "") or "saved world")
    lat = world.lattice

    def bad(what, asked, has):
        return MapError(f"{name}: saved with {what} {has}, asked for {asked}; rebuild it with "
                        f"`planner world` or drop the option")

    if isinstance(lattice, Lattice):
        if not np.allclose(lattice.generator, lat.generator, rtol=_REL, atol=0):
            raise bad("another lattice generator; lattice", lattice.name or "custom",
                      lat.name or "custom")
    elif lattice is not None and lattice != (lat.name or "custom"):
        raise bad("lattice", lattice, lat.name or "custom")
    if cell_volume is not None and not math.isclose(cell_volume, lat.cell_volume,
                                                    rel_tol=1e-6):
        raise bad("cell volume", f"{cell_volume:g} m^3", f"{lat.cell_volume:g} m^3")
    if radius is not None and not math.isclose(float(radius), world.radius, rel_tol=_REL,
                                               abs_tol=1e-12):
        raise bad("radius", f"{radius:g} m", f"{world.radius:g} m")
    if unknown is not None and unknown != world.unknown_policy:
        raise bad("unknown policy", unknown, world.unknown_policy)
    if bounds is not None:
        b = np.asarray(bounds, dtype=float)
        has = world.to_map(world.bounds)  # asked in the map's frame
        if b.shape != has.shape or not np.allclose(b, has, rtol=_REL, atol=1e-9):
            raise bad("bounds", b.tolist(), has.tolist())
