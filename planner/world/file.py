"""Saved worlds (``planner world MAP --out world.npz``): a built world, loaded without rebuilding.

File format (numpy ``.npz``, uncompressed for a fast load; written atomically):

* ``format`` = ``"planner.World"``, ``version`` = 1;
* ``generator`` (3, 3) float64 (m) and ``lattice`` (its name, ``""`` for a custom one);
* ``blocked`` (M, 3) int16 or int32 (the smallest that holds them): the distinct in-bounds
  blocked cells (inflated for ``radius``; under the ``"blocked"`` policy unknown space too),
  and ``unknown`` (U,) int64: sorted packed keys (:func:`planner.occupancy.keys.pack`) of the
  in-bounds cells meeting unknown space. Free cells are the in-bounds cells in neither list (not
  stored: they are the bulk of the box). Cells out of bounds are never free, so a path
  touches none of them and leaving them out changes no plan and no count;
* ``bounds`` (2, 3) float64 (m), ``radius`` (m), ``unknown_policy``;
* ``source`` (the map file name) and ``source_sha256`` (hex digest of its bytes, ``""`` for
  in-memory data); ``dim`` (2 for a 2D map planned on a prism of its 2D lattice).
"""

from __future__ import annotations

import hashlib
import math
import os
import zipfile
from pathlib import Path

import numpy as np

from planner.errors import MapError
from planner.fsutil import atomic_path

__all__ = ["FORMAT", "VERSION", "check_options", "is_world_file", "load_world", "save_world",
           "sha256"]

FORMAT = "planner.World"
VERSION = 1
_REL = 1e-9


def sha256(path: str | os.PathLike) -> str:
    """Hex SHA-256 of a file's bytes."""
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def is_world_file(path) -> bool:
    """True for an ``.npz`` written by :func:`save_world`."""
    if not isinstance(path, str | os.PathLike):
        return False
    p = Path(path)
    if p.suffix.lower() != ".npz" or not p.is_file():
        return False
    try:
        with zipfile.ZipFile(p) as z:
            if "format.npy" not in z.namelist():
                return False
        with np.load(p, allow_pickle=False) as data:
            return str(data["format"]) == FORMAT
    except (OSError, ValueError, zipfile.BadZipFile):
        return False


def save_world(world, path: str | os.PathLike) -> None:
    """Write ``world`` (a :class:`planner.World`) to ``path`` (``.npz``) atomically."""
    from planner.occupancy.keys import pack, unique_keys

    src = world.source or ""
    digest = getattr(world, "source_sha256", "") or ""
    path_of_source = getattr(world, "source_file", "") or src
    if not digest and path_of_source and Path(path_of_source).is_file():
        digest = sha256(path_of_source)
    from planner.occupancy.keys import unpack

    blocked = unpack(unique_keys(pack(world.blocked)), 3)
    blocked = blocked[world.in_bounds(blocked)]
    small = np.int16 if not len(blocked) or np.abs(blocked).max() < 2**15 else np.int32
    blocked = blocked.astype(small)
    unknown = world.unknown
    unknown = pack(unknown[world.in_bounds(unknown)])
    arrays = {
        "format": np.array(FORMAT), "version": np.array(VERSION, dtype=np.int64),
        "generator": np.asarray(world.lattice.generator, dtype=np.float64),
        "lattice": np.array(world.lattice.name or ""),
        "blocked": blocked, "unknown": unknown,
        "bounds": world.bounds, "radius": np.array(world.radius),
        "unknown_policy": np.array(world.unknown_policy),
        "source": np.array(Path(src).name if src else ""),
        "source_sha256": np.array(digest), "dim": np.array(getattr(world, "dim", 3)),
    }
    with atomic_path(path) as tmp, open(tmp, "wb") as f:
        np.savez(f, **arrays)


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
    from planner.lattice import Lattice
    from planner.world.world import World

    p = Path(path)
    try:
        with np.load(p, allow_pickle=False) as data:
            if "format" not in data.files or str(data["format"]) != FORMAT:
                raise MapError(f"{p.name}: not a saved planner world")
            version = int(data["version"])
            if version != VERSION:
                raise MapError(f"{p.name}: saved world version {version}; this planner reads "
                               f"version {VERSION} (rebuild it with `planner world`)")
            d = {k: data[k] for k in data.files}
    except (OSError, ValueError, KeyError, zipfile.BadZipFile) as exc:
        raise MapError(f"{p.name}: cannot read saved world: {exc}") from None
    name = str(d["lattice"]) or None
    dim = int(d["dim"])
    g, bounds = d["generator"], d["bounds"]
    if dim == 2:  # the 2D lattice; World plans on its prism again
        g, bounds = g[:2, :2], bounds[:, :2]
    lat = Lattice(g, name=name)
    world = World(lat, np.zeros((0, dim), np.int64), bounds, source=str(d["source"]),
                  radius=float(d["radius"]), unknown_policy=str(d["unknown_policy"]),
                  dim=dim)
    # Written by save_world from a checked world: in range, distinct and sorted as stored.
    world._blocked = np.ascontiguousarray(d["blocked"], dtype=np.int64).reshape(-1, 3)
    world._unknown_keys = np.ascontiguousarray(d["unknown"], dtype=np.int64)
    world.source_sha256 = str(d["source_sha256"])
    world.saved_path = str(p)
    return world


def check_options(world, lattice=None, cell_volume=None, radius=None, unknown=None,
                  bounds=None) -> None:
    """One-line MapError when an option asked for differs from what the saved world holds
    (another lattice, cell volume, radius, unknown policy or bounds): rebuild from the map
    instead of silently using the saved one."""
    from planner.lattice import Lattice

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
        if b.shape != world.bounds.shape or not np.allclose(b, world.bounds, rtol=_REL,
                                                            atol=1e-9):
            raise bad("bounds", b.tolist(), world.bounds.tolist())
