"""What a saved world's checks prove, and re-verifying its cells against its source map.

A saved world's digest (:func:`planner.world.check.digest`) is a checksum: it catches a
damaged file and an edit by a tool that does not know the format, not an edit by someone
who recomputes it (it is no signature, and there is no key). What makes a saved world's
blocked cells trustworthy is that they are the cells its source map gives:
:func:`verify_cells` rebuilds the world from the source (same generator, bounds, radius and
unknown policy, all read from the file) and compares both bit sets, cell for cell. Edited
cells, a changed radius or a changed policy are then found; a world consistent with its
source in every cell is, by construction, the world ``planner world`` would build.

The command line runs it with ``--check-source`` (the source must be found and unchanged),
and by default whenever the source map is found beside the world file, in the current
folder or among the bundled maps with the SHA-256 recorded at save (``--trust-world``
skips it: the world is then trusted by its digest alone).
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from planner.errors import MapError, PlannerError
from planner.fsutil import sha256

__all__ = ["find_source", "verify_cells", "verify_world", "Unbuildable"]


class Unbuildable(MapError):
    """The source map of a saved world cannot be rebuilt from its name and the file."""

# sources the reader cannot rebuild from the file name alone (options not recorded)
_NEEDS_OPTIONS = (".bag", ".db3", ".mcap")


def find_source(world, map_path: str | os.PathLike | None = None) -> Path | None:
    """The source map file of a saved ``world``: ``map_path``, else its recorded name beside
    the world file, in the current folder, or a bundled map of that name; None if absent."""
    if map_path is not None:
        return Path(map_path)
    src = Path(world.source or "").name
    if not src:
        return None
    saved = Path(getattr(world, "saved_path", "") or "world.npz")
    for p in (saved.parent / src, Path(src)):
        if p.is_file():
            return p
    from planner.maps import resolve  # lazy: scipy

    for name in (Path(src).stem, src):  # "floorplan" -> floorplan.yaml, "office.ply"
        p = resolve(name)
        if p.name == src and p.is_file():
            return p
    return None


def verify_cells(world, source: str | os.PathLike, *, format: str | None = None) -> None:
    """Rebuild ``world`` from ``source`` with its own settings and compare every cell.

    Raises
    ------
    MapError
        One line: how many cells differ (blocked or unknown) from what the source gives.
    """
    from planner.lattice import Lattice  # lazy: numba
    from planner.world.build import build_world  # lazy: numba, scipy

    saved = Path(getattr(world, "saved_path", "") or "world.npz")
    g, bounds = world.lattice.generator, np.asarray(world.bounds, dtype=float)
    if world.dim == 2:  # built on the 2D lattice (the world plans on its prism)
        g, bounds = g[:2, :2], bounds[:, :2]
    lat = Lattice(g, name=world.lattice.name)
    try:
        rebuilt = build_world(str(source), lat, radius=world.radius, bounds=bounds,
                              format=format, unknown=world.unknown_policy)
    except PlannerError as exc:
        raise Unbuildable(f"{saved.name}: cannot rebuild it from its source "
                          f"{Path(source).name} to check it: {exc}") from None
    for what, mine, theirs in (("blocked", world.free_bits, rebuilt.free_bits),
                               ("unknown", world.unknown_bits, rebuilt.unknown_bits)):
        a, b = mine.bits, theirs.bits
        if a.shape != b.shape:
            raise MapError(f"{saved.name}: its cell box differs from the one its source "
                           f"{Path(source).name} gives: the file was edited; rebuild it "
                           f"with `planner world`")
        diff = int(np.unpackbits(np.bitwise_xor(a, b)).sum())
        if diff:
            raise MapError(f"{saved.name}: {diff} {what} cells differ from those its source "
                           f"map {Path(source).name} gives with the saved settings (radius "
                           f"{world.radius:g} m, unknown {world.unknown_policy}): the file "
                           f"was edited; rebuild it with `planner world`")


def verify_world(world, *, required: bool, format: str | None = None) -> bool:
    """Check a loaded saved world against its source map: the SHA-256 recorded at save,
    then every cell (:func:`verify_cells`).

    ``required`` (``--check-source``): a source that is absent, changed or not rebuildable
    from its name alone (a bag: its topic and frames are not recorded) is an error; else
    such a world is left to its digest and False is returned.

    Raises
    ------
    MapError
        The cells differ, or (``required``) the source cannot be checked.
    """
    from planner.world.check import check_source  # lazy: numba

    src = find_source(world)
    if not required:
        if (src is None or not world.source_sha256 or src.suffix.lower() in _NEEDS_OPTIONS
                or src.is_dir() or sha256(src) != world.source_sha256):
            return False
    check_source(world, src)
    if src is not None and (src.suffix.lower() in _NEEDS_OPTIONS or src.is_dir()):
        raise MapError(f"{src.name}: a bag's topic, frames and clouds are not recorded in "
                       f"the saved world, so its cells cannot be re-verified; rebuild it")
    try:
        verify_cells(world, src, format=format)
    except Unbuildable:  # not from its name alone (e.g. built with --format poses)
        if required:
            raise
        return False
    return True
