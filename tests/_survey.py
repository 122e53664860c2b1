"""A LAS 1.4 survey in UTM coordinates, written with laspy from a known scene (tests)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

#: UTM zone easting / northing and height of the scene's south-west ground corner (m)
CORNER = np.array([455_000.0, 5_410_000.0, 323.3])
SIZE = 150.0  # square site (m)
TOP = 4.0  # walls and the building rise this far above the ground (m)


def _grid(a: np.ndarray, b: np.ndarray, step: float) -> np.ndarray:
    """Points every ``step`` (m) over the 1D ranges ``a`` x ``b`` as (N, 2)."""
    u, v = np.meshgrid(np.arange(a[0], a[1] + 1e-9, step), np.arange(b[0], b[1] + 1e-9, step),
                       indexing="ij")
    return np.column_stack([u.ravel(), v.ravel()])


def survey_points() -> np.ndarray:
    """(N, 3) the scene in UTM (m): ground every 0.5 m, two walls across the site with a
    gap at opposite ends (so a path from the south-west to the north-east corner winds
    between them) and a box building, surfaces sampled every 0.25 m, all as tall as the
    box."""
    g = _grid(np.array([0.0, SIZE]), np.array([0.0, SIZE]), 0.5)
    parts = [np.column_stack([g, np.zeros(len(g))])]
    for x, (y0, y1) in ((50.0, (0.0, 90.0)), (100.0, (60.0, SIZE))):
        w = _grid(np.array([y0, y1]), np.array([0.0, TOP]), 0.25)
        parts.append(np.column_stack([np.full(len(w), x), w[:, 0], w[:, 1]]))
    # a building 15 x 20 m between the walls
    x0, x1, y0, y1 = 68.0, 83.0, 40.0, 60.0
    for x in (x0, x1):
        w = _grid(np.array([y0, y1]), np.array([0.0, TOP]), 0.25)
        parts.append(np.column_stack([np.full(len(w), x), w[:, 0], w[:, 1]]))
    for y in (y0, y1):
        w = _grid(np.array([x0, x1]), np.array([0.0, TOP]), 0.25)
        parts.append(np.column_stack([w[:, 0], np.full(len(w), y), w[:, 1]]))
    roof = _grid(np.array([x0, x1]), np.array([y0, y1]), 0.25)
    parts.append(np.column_stack([roof, np.full(len(roof), TOP)]))
    return np.concatenate(parts) + CORNER


def write_survey(path: str | Path) -> np.ndarray:
    """Write :func:`survey_points` as LAS 1.4 (point format 6, 1 mm scale, the corner as the
    header offset, as survey software does); returns the points as stored (m)."""
    import laspy

    pts = survey_points()
    header = laspy.LasHeader(point_format=6, version="1.4")
    header.offsets = CORNER.copy()
    header.scales = [0.001, 0.001, 0.001]
    las = laspy.LasData(header)
    las.x, las.y, las.z = pts[:, 0], pts[:, 1], pts[:, 2]
    las.write(str(path))
    back = laspy.read(str(path))
    return np.column_stack([back.x, back.y, back.z]).astype(float)
