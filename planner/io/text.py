"""Text XYZ clouds (optionally ``.gz`` / ``.bz2`` / ``.xz``) and ``.npy`` arrays."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from planner.errors import MapError
from planner.io._files import check_file, loadtxt, read_text
from planner.io.obstacles import Obstacles
from planner.io.validate import cloud
from planner.npyfile import read_npy_file


def read_xyz(p: Path, compression: str | None = None, budget: int | None = None) -> Obstacles:
    """One ``x y z [extra ...]`` per line; ``#`` comments; whitespace or comma separated.

    A compressed file is inflated in chunks and refused past ``budget`` bytes."""
    text = read_text(p, compression, budget)
    return cloud(loadtxt(text, p.name, ncols=3), p.name)


def read_npy(p: Path) -> Obstacles:
    """An (N, 3) numeric ``.npy`` array (no pickles); (N, 3 + k) too, its first three
    columns x, y, z (a scan saved with intensity, ring, time, ... after them)."""
    check_file(p)
    # header first: declared size against the budget and the file, no pickles, no trailer
    arr = read_npy_file(p, p.name)
    if not isinstance(arr, np.ndarray) or arr.ndim != 2 or arr.shape[1] < 3:
        raise MapError(f"{p.name}: .npy array must have shape (N, 3) (or (N, 3 + k): x, y, z "
                       f"first), got {getattr(arr, 'shape', None)}")
    if arr.dtype.kind not in "fiu":
        raise MapError(f"{p.name}: .npy array must be numeric, got dtype {arr.dtype}")
    return cloud(arr[:, :3], p.name)
