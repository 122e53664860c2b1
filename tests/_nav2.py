"""A Nav2 ``map_saver`` map (PGM + YAML) of the bundled office floor (tests)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from planner.io import load_points
from planner.maps import map_path

RES = 0.05  # m per pixel, map_saver's default
ORIGIN = (-1.0, -1.0)  # the image's lower-left corner (m), as map_saver writes it
SHIFT = np.array([0.5, 0.5])  # the office's corner in the map frame (m)


def write_office_map(folder: str | Path) -> Path:
    """Slice the office (20 x 12 m, its corner at :data:`SHIFT` in the map frame) between
    0.1 and 1.9 m height into ``office_map.pgm`` (occupied 0, free 254 inside the floor's
    outline, unknown 205 outside it) with its ``office_map.yaml``; returns the YAML's
    path."""
    folder = Path(folder)
    pts = load_points(map_path("office"))
    pts = pts[(pts[:, 2] > 0.1) & (pts[:, 2] < 1.9)]
    pts[:, :2] += SHIFT
    w, h = int(round(22 / RES)), int(round(14 / RES))
    img = np.full((h, w), 205, np.uint8)
    lo = np.rint((SHIFT - ORIGIN) / RES).astype(int)  # the outline's pixels
    hi = lo + np.rint(np.array([20.0, 12.0]) / RES).astype(int)
    img[h - hi[1]:h - lo[1], lo[0]:hi[0]] = 254
    col = np.floor((pts[:, 0] - ORIGIN[0]) / RES).astype(int)
    row = h - 1 - np.floor((pts[:, 1] - ORIGIN[1]) / RES).astype(int)
    img[row, col] = 0
    (folder / "office_map.pgm").write_bytes(f"P5\n{w} {h}\n255\n".encode() + img.tobytes())
    yaml = folder / "office_map.yaml"
    yaml.write_text(f"image: office_map.pgm\nmode: trinary\nresolution: {RES}\n"
                    f"origin: [{ORIGIN[0]}, {ORIGIN[1]}, 0.0]\nnegate: 0\n"
                    "occupied_thresh: 0.65\nfree_thresh: 0.25\n")
    return yaml
