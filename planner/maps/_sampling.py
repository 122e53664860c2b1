"""Surface sampling and validation shared by the bundled scene generators.

Points are sensor-like surface samples on a jittered grid with gaussian noise (metres, z up).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from scipy.spatial import cKDTree

from planner.errors import MapError

NOISE_SIGMA = 0.005
"""Standard deviation (m) of the gaussian noise added to every coordinate."""

_JITTER = 0.35  # in-plane jitter of the sampling grid, as a fraction of the spacing


# --------------------------------------------------------------------------------------------
# surface sampling
# --------------------------------------------------------------------------------------------

_AXES = {"x": 0, "y": 1, "z": 2}


class _Surfaces:
    """Accumulates jittered-grid samples of axis-aligned rectangles, boxes, cylinders, spheres."""

    def __init__(self, rng: np.random.Generator, spacing: float) -> None:
        self.rng = rng
        self.s = float(spacing)
        self.parts: list[np.ndarray] = []

    def _grid(self, len_a: float, len_b: float) -> tuple[np.ndarray, np.ndarray]:
        """Jittered grid parameters in [0, len_a] x [0, len_b] (one sample per grid cell)."""
        na = max(1, math.ceil(len_a / self.s - 1e-9))
        nb = max(1, math.ceil(len_b / self.s - 1e-9))
        ia, ib = np.meshgrid(np.arange(na), np.arange(nb), indexing="ij")
        ja = self.rng.uniform(-_JITTER, _JITTER, ia.shape)
        jb = self.rng.uniform(-_JITTER, _JITTER, ib.shape)
        a = (ia + 0.5 + ja).ravel() * (len_a / na)
        b = (ib + 0.5 + jb).ravel() * (len_b / nb)
        return a, b

    def rect(self, normal: str, c: float, lo, hi, holes=()) -> None:
        """Rectangle perpendicular to axis ``normal`` at coordinate ``c``.

        ``lo``/``hi`` are the corners in the two remaining axes, in xyz order (for ``normal="y"``
        they are (x, z)).  ``holes`` is a list of ``(lo, hi)`` rectangles in the same coordinates
        where no points are kept (door openings, stair wells, ...).
        """
        k = _AXES[normal]
        others = [i for i in range(3) if i != k]
        a, b = self._grid(hi[0] - lo[0], hi[1] - lo[1])
        a = a + lo[0]
        b = b + lo[1]
        keep = np.ones(a.shape, dtype=bool)
        for (h0, h1) in holes:
            keep &= ~((a > h0[0]) & (a < h1[0]) & (b > h0[1]) & (b < h1[1]))
        pts = np.empty((int(keep.sum()), 3))
        pts[:, k] = c
        pts[:, others[0]] = a[keep]
        pts[:, others[1]] = b[keep]
        self.parts.append(pts)

    def box(self, lo, hi, bottom: bool = False) -> None:
        """Outer surface of an axis-aligned box (the bottom face only if ``bottom``)."""
        (x0, y0, z0), (x1, y1, z1) = lo, hi
        self.rect("z", z1, (x0, y0), (x1, y1))
        if bottom:
            self.rect("z", z0, (x0, y0), (x1, y1))
        self.rect("x", x0, (y0, z0), (y1, z1))
        self.rect("x", x1, (y0, z0), (y1, z1))
        self.rect("y", y0, (x0, z0), (x1, z1))
        self.rect("y", y1, (x0, z0), (x1, z1))

    def wall(self, normal: str, centre: float, thickness: float, lo, hi, doors=()) -> None:
        """Both faces of a thick interior wall, with door openings (jambs and lintels sampled).

        The wall is perpendicular to ``normal`` ("x" or "y"), centred at ``centre``; ``lo``/``hi``
        give its extent (along-wall coordinate, z).  ``doors`` is a list of ``(a0, a1, top)``:
        openings from the floor ``lo[1]`` up to ``top`` between along-wall coordinates a0, a1.
        """
        f0, f1 = centre - thickness / 2, centre + thickness / 2
        holes = [((a0, lo[1] - 1.0), (a1, top)) for (a0, a1, top) in doors]
        self.rect(normal, f0, lo, hi, holes)
        self.rect(normal, f1, lo, hi, holes)
        along = "y" if normal == "x" else "x"
        for (a0, a1, top) in doors:
            for a in (a0, a1):  # jambs
                self.rect(along, a, (f0, lo[1]), (f1, top))
            if normal == "x":  # lintel underside
                self.rect("z", top, (f0, a0), (f1, a1))
            else:
                self.rect("z", top, (a0, f0), (a1, f1))

    def cylinder(self, cx: float, cy: float, r: float, z0: float, z1: float) -> None:
        """Lateral surface of a vertical cylinder."""
        t, z = self._grid(2 * math.pi * r, z1 - z0)
        t = t / r
        self.parts.append(np.column_stack([cx + r * np.cos(t), cy + r * np.sin(t), z + z0]))

    def sphere(self, centre, r: float) -> None:
        """Surface of a sphere (Fibonacci lattice with a random twist)."""
        n = max(8, math.ceil(4 * math.pi * r * r / (self.s * self.s)))
        i = np.arange(n) + 0.5
        cz = 1.0 - 2.0 * i / n
        rho = np.sqrt(1.0 - cz * cz)
        phi = i * math.pi * (3.0 - math.sqrt(5.0)) + self.rng.uniform(0.0, 2 * math.pi)
        unit = np.column_stack([rho * np.cos(phi), rho * np.sin(phi), cz])
        self.parts.append(np.asarray(centre, dtype=float) + r * unit)

    def add(self, pts: np.ndarray) -> None:
        self.parts.append(np.asarray(pts, dtype=float).reshape(-1, 3))

    def points(self) -> np.ndarray:
        """All samples plus gaussian noise, rounded to float32 precision (returned as float64)."""
        pts = np.concatenate(self.parts, axis=0)
        pts = pts + self.rng.normal(0.0, NOISE_SIGMA, pts.shape)
        return pts.astype(np.float32).astype(np.float64)


# --------------------------------------------------------------------------------------------
# map data and validation
# --------------------------------------------------------------------------------------------


@dataclass
class _Map:
    points: np.ndarray
    info: dict[str, Any] = field(default_factory=dict)


def _r3(v) -> list[float]:
    return [round(float(c), 3) for c in v]


def _info(name, description, seed, spacing, bounds, radius, cell_volume, queries, extra=None):
    info: dict[str, Any] = {
        "name": name,
        "description": description,
        "file": f"{name}.ply",
        "units": "m",
        "up": "z",
        "seed": int(seed),
        "n_points": 0,
        "sample_spacing": spacing,
        "noise_sigma": NOISE_SIGMA,
        "bounds": [_r3(bounds[0]), _r3(bounds[1])],
        "robot_radius": radius,
        "cell_volume": cell_volume,
        "clearance": round(2 * radius + 0.1, 3),
        "queries": [
            {"start": _r3(s), "goal": _r3(g), "note": note} for (s, g, note) in queries
        ],
    }
    if extra:
        info["extra"] = _tidy(extra)
    return info


def _tidy(obj):
    """Round floats (recursively) so the sidecar JSON reads cleanly: 2.65, not 2.6500000000004."""
    if isinstance(obj, float):
        return round(obj, 6)
    if isinstance(obj, dict):
        return {k: _tidy(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [_tidy(v) for v in obj]
    return obj


def _segment_min_distance(tree: cKDTree, a, b, step: float = 0.02) -> float:
    a, b = np.asarray(a, float), np.asarray(b, float)
    n = max(2, math.ceil(np.linalg.norm(b - a) / step) + 1)
    samples = a + np.linspace(0.0, 1.0, n)[:, None] * (b - a)
    return float(tree.query(samples)[0].min())


def _validate(m: _Map) -> _Map:
    """Check the cloud and the default queries; raise MapError on any violation."""
    pts, info = m.points, m.info
    if pts.ndim != 2 or pts.shape[1] != 3 or len(pts) == 0 or not np.isfinite(pts).all():
        raise MapError(f"map {info['name']!r}: bad point array {pts.shape}")
    lo, hi = np.array(info["bounds"][0]), np.array(info["bounds"][1])
    tol = 10 * NOISE_SIGMA
    if (pts < lo - tol).any() or (pts > hi + tol).any():
        raise MapError(
            f"map {info['name']!r}: points outside the bounds "
            f"(min {pts.min(0)}, max {pts.max(0)}, bounds {info['bounds']})"
        )
    tree = cKDTree(pts)
    radius, clearance = info["robot_radius"], info["clearance"]
    for i, q in enumerate(info["queries"]):
        for key in ("start", "goal"):
            p = np.array(q[key])
            if (p < lo + clearance).any() or (p > hi - clearance).any():
                raise MapError(
                    f"map {info['name']!r} query {i} {key} {q[key]} is not inside the bounds "
                    f"by the clearance {clearance}"
                )
            d = float(tree.query(p)[0])
            if d < clearance:
                raise MapError(
                    f"map {info['name']!r} query {i} {key} {q[key]} is {d:.3f} m from the cloud, "
                    f"needs >= {clearance}"
                )
        d = _segment_min_distance(tree, q["start"], q["goal"])
        if d >= radius:
            raise MapError(
                f"map {info['name']!r} query {i}: the straight segment is free "
                f"({d:.3f} m >= robot radius {radius}); the query would be trivial"
            )
    info["n_points"] = int(len(pts))
    return m
