"""The bundled 2D map ``floorplan``: a ROS map_server occupancy grid (PGM + YAML) of a floor.

A 16 x 10 m floor at 0.05 m per pixel: outer walls, four rooms off a corridor with 1 m doors,
a diagonal wall (no axis favours it), round pillars, and one room never observed (unknown,
grey 205). Written by :func:`generate_floorplan` (``python -m planner.maps`` also writes it)
as ``floorplan.pgm``, ``floorplan.yaml`` and a sidecar ``floorplan.json`` with its bounds,
robot radius, cell area (``cell_volume``, m^2) and queries. Deterministic: no randomness.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from planner.fsutil import atomic_path, write_text_atomic
from planner.maps.bundled import _write_json

__all__ = ["FLOORPLAN", "floorplan_image", "generate_floorplan"]

FLOORPLAN = "floorplan"
_RES = 0.05
_W, _H = 16.0, 10.0
_FREE, _OCC, _UNKNOWN = 254, 0, 205


def floorplan_image() -> np.ndarray:
    """(200, 320) uint8 image, row 0 at the top (largest y) as map_server reads it."""
    h, w = int(round(_H / _RES)), int(round(_W / _RES))
    ys, xs = np.meshgrid((np.arange(h)[::-1] + 0.5) * _RES, (np.arange(w) + 0.5) * _RES,
                         indexing="ij")
    img = np.full((h, w), _FREE, dtype=np.uint8)
    t = 0.1  # wall half thickness (m)

    def wall(x0, y0, x1, y1):
        # every pixel centre within t of the segment (x0, y0)-(x1, y1)
        d = np.array([x1 - x0, y1 - y0])
        s = np.clip(((xs - x0) * d[0] + (ys - y0) * d[1]) / (d @ d), 0, 1)
        img[np.hypot(xs - x0 - s * d[0], ys - y0 - s * d[1]) <= t] = _OCC

    for seg in [(0, 0, 16, 0), (0, 10, 16, 10), (0, 0, 0, 10), (16, 0, 16, 10)]:
        wall(*seg)
    # corridor 4 m < y < 6 m; rooms below and above, 1 m doors
    for x0, x1 in [(0, 3.5), (4.5, 11.5), (12.5, 16)]:
        wall(x0, 4, x1, 4)
    for x0, x1 in [(0, 2.0), (3.0, 9.0), (10.0, 16)]:
        wall(x0, 6, x1, 6)
    wall(8, 0, 8, 4)
    wall(6, 6, 6, 10)
    wall(11, 6, 11, 10)
    wall(9.5, 1.0, 13.5, 3.0)  # diagonal wall in the lower right room
    for cx, cy in [(2, 2), (5, 2), (13, 8.5), (8.5, 8.0)]:
        img[np.hypot(xs - cx, ys - cy) <= 0.3] = _OCC
    # the upper right room was never observed
    img[(xs > 11.1) & (xs < 15.9) & (ys > 6.1) & (ys < 9.9)] = _UNKNOWN
    return img


def generate_floorplan(out_dir: str | os.PathLike[str]) -> tuple[Path, Path, Path]:
    """Write ``floorplan.pgm``, ``floorplan.yaml`` and ``floorplan.json`` into ``out_dir``."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    img = floorplan_image()
    pgm, yaml, js = (out / f"{FLOORPLAN}{s}" for s in (".pgm", ".yaml", ".json"))
    with atomic_path(pgm) as tmp:
        tmp.write_bytes(f"P5\n{img.shape[1]} {img.shape[0]}\n255\n".encode() + img.tobytes())
    write_text_atomic(yaml, f"image: {pgm.name}\nresolution: {_RES}\norigin: [0.0, 0.0, 0.0]\n"
                            "negate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n")
    _write_json(js, {
        "name": FLOORPLAN,
        "description": "2D floor plan (ROS map_server PGM + YAML): corridor, four rooms, a "
                       "diagonal wall, pillars, one unobserved room",
        "file": yaml.name, "units": "m", "resolution": _RES,
        "bounds": [[0.0, 0.0], [_W, _H]], "robot_radius": 0.2, "cell_volume": 0.0025,
        "queries": [
            {"start": [1.0, 1.0], "goal": [14.5, 1.0], "note": "lower left room to lower "
             "right room, around the diagonal wall"},
            {"start": [1.0, 8.5], "goal": [14.5, 2.5], "note": "upper left room to lower "
             "right room through the corridor"},
            {"start": [3.0, 5.0], "goal": [9.0, 8.5], "note": "corridor into the upper middle "
             "room"},
        ],
    })
    return pgm, yaml, js
