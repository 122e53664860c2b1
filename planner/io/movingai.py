"""MovingAI 3D benchmark files: ``.3dmap`` voxel maps and ``.3dscen`` query lists."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from planner.errors import MapError
from planner.io._files import loadtxt, read_text
from planner.io.obstacles import Obstacles, Scenarios

# Largest grid side accepted: beyond it coordinates no longer fit int64 products, and no
# benchmark map comes near it.
_MAX_DIM = 1 << 31
# Integers above 2**53 are not exact in float64.
_MAX_COORD = float(1 << 53)


def read_3dmap(p: Path) -> Obstacles:
    """``voxel X Y Z`` then one blocked voxel ``x y z`` per line: unit cubes, grid bounds."""
    text = read_text(p)
    head, _, body = text.partition("\n")
    m = re.fullmatch(r"voxel\s+(\d+)\s+(\d+)\s+(\d+)", head.strip())
    if not m:
        raise MapError(f"{p.name}: bad .3dmap header {head.strip()[:40]!r} "
                       f"(expected 'voxel X Y Z')")
    dims_int = [int(g) for g in m.groups()]
    if min(dims_int) <= 0 or max(dims_int) > _MAX_DIM:
        raise MapError(f"{p.name}: .3dmap dimensions must be positive, at most {_MAX_DIM}, got "
                       f"{' '.join(g[:20] for g in m.groups())}")
    dims = np.array(dims_int, dtype=np.int64)
    vox = loadtxt(body, p.name, ncols=3, first_line=2, exact=True)
    if not len(vox):
        raise MapError(f"{p.name}: .3dmap has no blocked voxels")
    if not np.isfinite(vox).all() or not np.array_equal(vox, np.round(vox)):
        raise MapError(f"{p.name}: .3dmap voxel coordinates must be integers")
    if (vox < 0).any() or (vox >= dims).any():
        row = int(np.nonzero(((vox < 0) | (vox >= dims)).any(axis=1))[0][0])
        where = " ".join(f"{v:.0f}" for v in vox[row])
        raise MapError(f"{p.name}: voxel ({where}) on line {row + 2} "
                       f"lies outside the {dims.tolist()} grid")
    bounds = np.stack([np.full(3, -0.5), dims - 0.5])
    return Obstacles(points=np.zeros((0, 3)), boxes=vox, box_size=1.0, bounds=bounds,
                     resolution=1.0, source=p.name)


def load_scenarios(path: str | Path) -> Scenarios:
    """Read a MovingAI ``.3dscen`` file.

    The file is ``version 1``, the map name, then one
    ``sx sy sz gx gy gz optimal_cost heuristic_ratio`` line per query.

    Parameters
    ----------
    path : str or PathLike

    Returns
    -------
    Scenarios
        ``starts`` / ``goals`` (K, 3) int64 voxel coordinates, ``costs`` (K,) float64.

    Raises
    ------
    MapError
        Missing file, bad header, malformed or non-finite rows, no queries.
    """
    p = Path(path)
    lines = read_text(p).splitlines()
    if len(lines) < 2 or not re.fullmatch(r"version\s+\S+", lines[0].strip()):
        raise MapError(f"{p.name}: not a .3dscen file (first line must be 'version 1')")
    map_name = lines[1].strip()
    table = loadtxt("\n".join(lines[2:]), p.name, ncols=8, first_line=3, exact=True)
    if not len(table):
        raise MapError(f"{p.name}: contains no queries")
    if not np.isfinite(table).all():
        raise MapError(f"{p.name}: contains NaN or infinite values")
    coords = table[:, :6]
    if not np.array_equal(coords, np.round(coords)) or (np.abs(coords) > _MAX_COORD).any():
        raise MapError(f"{p.name}: start/goal coordinates must be integers below 2**53")
    return Scenarios(
        starts=coords[:, :3].astype(np.int64),
        goals=coords[:, 3:6].astype(np.int64),
        costs=table[:, 6].copy(),
        heuristic_ratios=table[:, 7].copy(),
        map_name=map_name,
        source=p.name,
    )
