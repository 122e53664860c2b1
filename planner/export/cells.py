"""A world's cells as a PLY point set: the centres of the blocked and the unknown cells.

Binary little-endian PLY, one ``vertex`` per cell with ``x, y, z`` (float64, metres: the
cell centre), ``i, j, k`` (int32 lattice indices) and ``state`` (uint8): 1 blocked (an
obstacle or the robot radius around one, or around unknown space when unknown space is
blocked), 2 unknown (the cell meets unknown space). ``comment`` lines give the lattice
generator (rows, metres), the radius and the unknown-space policy. Read with ``plyfile``,
Open3D, CloudCompare or MeshLab (which show the extra properties as scalar fields).
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from planner.errors import MapError
from planner.export.octomap import write_cspace_octomap, write_octomap
from planner.fsutil import atomic_path

__all__ = ["BLOCKED", "UNKNOWN", "write_ply_cells", "write_world_cells"]

BLOCKED, UNKNOWN = 1, 2


def write_ply_cells(out: str | os.PathLike, world) -> tuple[int, int]:
    """Write the cells of ``world`` (module docstring) atomically; returns the numbers of
    blocked and unknown cells written."""
    from plyfile import PlyData, PlyElement

    unknown = world.unknown
    blocked = np.unique(np.asarray(world.blocked, dtype=np.int64), axis=0)
    if len(unknown) and len(blocked):
        blocked = blocked[~world.is_unknown(blocked)]
    cells = np.concatenate([blocked, unknown]).astype(np.int64)
    state = np.concatenate([np.full(len(blocked), BLOCKED), np.full(len(unknown), UNKNOWN)])
    # centres in the map's frame; i, j, k count from the world's local origin (its offset)
    xyz = world.to_map(world.lattice.to_world(cells)) if len(cells) else np.zeros((0, 3))
    v = np.empty(len(cells), dtype=[("x", "<f8"), ("y", "<f8"), ("z", "<f8"), ("i", "<i4"),
                                    ("j", "<i4"), ("k", "<i4"), ("state", "u1")])
    for n, name in enumerate("xyz"):
        v[name] = xyz[:, n]
    for n, name in enumerate("ijk"):
        v[name] = cells[:, n]
    v["state"] = state
    g = np.asarray(world.lattice.generator, dtype=float)
    comments = [f"lattice {world.lattice.name or 'custom'}",
                "generator " + "; ".join(" ".join(repr(float(x)) for x in row) for row in g),
                f"radius {world.radius!r}", f"unknown_policy {world.unknown_policy}",
                f"state {BLOCKED} blocked, {UNKNOWN} unknown"]
    if world.local_frame:  # x, y, z = generator @ (i, j, k) + offset
        comments.append("offset " + " ".join(repr(float(x)) for x in world.offset))
    with atomic_path(out) as tmp:
        PlyData([PlyElement.describe(v, "vertex")], byte_order="<",
                comments=comments).write(str(tmp))
    return len(blocked), len(unknown)


def write_world_cells(out: str | os.PathLike, world, cspace: bool = False) -> None:
    """Write ``world``'s cells by the suffix of ``out``: ``.ply``, or ``.bt`` (the map's
    obstacles as an OctoMap; ``cspace``: the world's blocked cells, cubic worlds only)."""
    suffix = Path(out).suffix.lower()
    if suffix == ".ply":
        write_ply_cells(out, world)
    elif suffix == ".bt":
        if world.local_frame:  # its keys count from the map's origin: they would not fit
            raise MapError(f"{out}: an OctoMap tree reaches +-32768 cells from its frame's "
                           f"origin; this map lies {np.abs(world.offset).max():.0f} m from "
                           "it (write .ply, or shift the map)")
        (write_cspace_octomap if cspace else write_octomap)(out, world)
    else:
        raise MapError(f"{out}: unknown cell file type {suffix!r}; use .ply or .bt")
