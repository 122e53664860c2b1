"""Deterministic, seeded generators of the bundled example maps.

Every map is a point cloud of *sensor-like surface samples*: points on the visible surfaces
(floors, ceilings, walls, shelves, trunks, ...) as a laser scanner would return them, on a
jittered grid of about one point per ``spacing x spacing`` of surface, with 5 mm gaussian noise
on every coordinate.  Solids are never filled.  Units are metres, z is up.

The bundled files live in ``maps/`` at the repository root (``maps/<name>.ply`` binary little
endian float32 x, y, z, and a sidecar ``maps/<name>.json``); ``python maps/generate.py``
regenerates them byte for byte.

Sidecar keys: ``name``, ``description``, ``file`` (the PLY file name), ``units``, ``up``,
``seed``, ``n_points``, ``sample_spacing``, ``noise_sigma``, ``bounds``
(``[[xmin, ymin, zmin], [xmax, ymax, zmax]]``, the world box a planner must stay in; every point
lies inside it up to noise), ``robot_radius`` (suggested), ``cell_volume`` (suggested lattice cell
volume in m^3), ``clearance`` (the distance every default query keeps from every point:
``2 * robot_radius + 0.1``), ``queries`` (list of ``{"start", "goal", "note"}``) and, for some
maps, ``extra`` (map specific documented dimensions).

Every default query is checked when a map is built: both ends lie inside the bounds, at least
``clearance`` away from every point, and the straight segment between them passes closer than
``robot_radius`` to some point (so the query needs a real route).  A violation raises
:class:`planner.errors.MapError`.
"""

from __future__ import annotations

import json
import math
import os
import re
import tempfile
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from scipy.spatial import cKDTree

from planner.errors import MapError

__all__ = [
    "MAPS",
    "MAPS_DIR",
    "NOISE_SIGMA",
    "build",
    "forest",
    "generate",
    "generate_all",
    "load_map_info",
    "load_map_points",
    "map_path",
    "narrow_passage",
    "office",
    "two_storey",
    "warehouse",
]

MAPS_DIR = Path(__file__).resolve().parents[1] / "maps"
"""Directory of the bundled maps (``maps/`` at the repository root)."""

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


# --------------------------------------------------------------------------------------------
# office
# --------------------------------------------------------------------------------------------

_DOOR_W, _DOOR_H, _WALL_T = 0.9, 2.1, 0.12


def _office(seed: int) -> _Map:
    rng = np.random.default_rng([seed, 1])
    spacing = 0.1
    S = _Surfaces(rng, spacing)
    X, Y, H = 20.0, 12.0, 3.0
    h = _WALL_T / 2
    # shell, seen from inside
    S.rect("z", 0.0, (0, 0), (X, Y))
    S.rect("z", H, (0, 0), (X, Y))
    S.rect("x", 0.0, (0, 0), (Y, H))
    S.rect("x", X, (0, 0), (Y, H))
    S.rect("y", 0.0, (0, 0), (X, H))
    S.rect("y", Y, (0, 0), (X, H))
    # corridor walls (corridor y in [5, 7] between wall centres) with one door per room
    south_doors = [1.6, 7.0, 12.5, 17.8]  # left edges of the doors
    north_doors = [1.5, 5.5, 10.0, 14.0]
    S.wall("y", 5.0, _WALL_T, (0, 0), (X, H), [(d, d + _DOOR_W, _DOOR_H) for d in south_doors])
    S.wall("y", 7.0, _WALL_T, (0, 0), (X, H), [(d, d + _DOOR_W, _DOOR_H) for d in north_doors])
    # room partitions; the north-east corner room (x > 16.5) opens only into its neighbour
    for x in (5.0, 10.0, 15.0):
        S.wall("x", x, _WALL_T, (0.0, 0), (5.0 - h, H))
    for x in (4.0, 8.0, 13.0):
        S.wall("x", x, _WALL_T, (7.0 + h, 0), (Y, H))
    S.wall("x", 16.5, _WALL_T, (7.0 + h, 0), (Y, H), [(9.5, 9.5 + _DOOR_W, _DOOR_H)])

    queries = [
        ((2.5, 2.5, 1.2), (18.3, 10.5, 1.2),
         "south-west room to the north-east corner room: two corridor doors and an inner door"),
        ((12.5, 2.0, 1.0), (2.0, 9.5, 1.5), "across the corridor through two doors"),
        ((1.0, 6.0, 1.5), (17.5, 2.5, 1.2), "corridor west end into the south-east room"),
    ]
    # furniture: desks / cabinets as closed boxes against the outer walls, away from doors
    # and from the query points
    keep_out = [np.array(p[:2]) for q in queries for p in q[:2]]
    keep_out += [np.array([d + _DOOR_W / 2, 5.0]) for d in south_doors]
    keep_out += [np.array([d + _DOOR_W / 2, 7.0]) for d in north_doors]
    keep_out += [np.array([16.5, 9.95])]
    rooms = [  # (x0, x1, y0, y1, wall side: y of the outer wall the furniture stands against)
        (0.0, 5.0 - h, 0.0, 5.0 - h, 0.0), (5.0 + h, 10.0 - h, 0.0, 5.0 - h, 0.0),
        (10.0 + h, 15.0 - h, 0.0, 5.0 - h, 0.0), (15.0 + h, X, 0.0, 5.0 - h, 0.0),
        (0.0, 4.0 - h, 7.0 + h, Y, Y), (4.0 + h, 8.0 - h, 7.0 + h, Y, Y),
        (8.0 + h, 13.0 - h, 7.0 + h, Y, Y), (13.0 + h, 16.5 - h, 7.0 + h, Y, Y),
        (16.5 + h, X, 7.0 + h, Y, Y),
    ]
    doors = [[[d, 5.0 - h, 0.0], [d + _DOOR_W, 5.0 + h, _DOOR_H]] for d in south_doors]
    doors += [[[d, 7.0 - h, 0.0], [d + _DOOR_W, 7.0 + h, _DOOR_H]] for d in north_doors]
    doors += [[[16.5 - h, 9.5, 0.0], [16.5 + h, 9.5 + _DOOR_W, _DOOR_H]]]
    furniture = []
    for (x0, x1, y0, y1, wy) in rooms:
        for _ in range(int(rng.integers(1, 3))):
            for _attempt in range(50):
                w = float(rng.uniform(0.8, 1.6))
                d = float(rng.uniform(0.5, 0.8))
                ht = float(rng.choice([0.75, 0.75, 1.2, 1.9]))
                fx = float(rng.uniform(x0 + 0.05, x1 - w - 0.05))
                fy = y0 + 0.02 if wy == 0.0 else y1 - d - 0.02
                c = np.array([fx + w / 2, fy + d / 2])
                if all(np.linalg.norm(c - k) > 2.2 for k in keep_out) and all(
                    fx > b[1] + 0.3 or fx + w < b[0] - 0.3 or abs(fy - b[2]) > 0.1
                    for b in furniture
                ):
                    furniture.append((fx, fx + w, fy, d, ht))
                    S.box((fx, fy, 0.0), (fx + w, fy + d, ht))
                    break
    info = _info(
        "office",
        "One office floor 20 x 12 x 3 m: a 2 m corridor along x with four rooms on each side, "
        "0.9 x 2.1 m doors from every room to the corridor except the north-east corner room, "
        "which is reached through its neighbour; 0.12 m interior walls; a few desks and "
        "cabinets (closed boxes) against the outer walls.",
        seed, spacing, ((0, 0, 0), (X, Y, H)), 0.25, 0.002, queries,
        extra={"door_width": _DOOR_W, "door_height": _DOOR_H, "wall_thickness": _WALL_T,
               "doors": doors},
    )
    return _Map(S.points(), info)


# --------------------------------------------------------------------------------------------
# two storey
# --------------------------------------------------------------------------------------------


def _two_storey(seed: int) -> _Map:
    rng = np.random.default_rng([seed, 2])
    spacing = 0.08
    S = _Surfaces(rng, spacing)
    X, Y = 12.0, 8.0
    ceil0, slab, top = 3.0, 3.2, 6.2  # ground-floor ceiling, upper floor level, upper ceiling
    n_steps, rise, run, stair_w, stair_x0 = 16, 0.2, 0.3, 1.2, 1.0
    stair_x1 = stair_x0 + (n_steps - 1) * run  # 5.5: the last riser leads onto the slab
    well = ((0.0, 0.0), (stair_x1, 2.2))  # opening in the slab above the stairs
    # shell
    S.rect("z", 0.0, (0, 0), (X, Y))
    S.rect("z", top, (0, 0), (X, Y))
    for z0, z1 in ((0.0, ceil0), (slab, top)):
        S.rect("x", 0.0, (0, z0), (Y, z1))
        S.rect("x", X, (0, z0), (Y, z1))
        S.rect("y", 0.0, (0, z0), (X, z1))
        S.rect("y", Y, (0, z0), (X, z1))
    # outer wall strips at slab level visible inside the stair well
    S.rect("x", 0.0, (well[0][1], ceil0), (well[1][1], slab))
    S.rect("y", 0.0, (well[0][0], ceil0), (well[1][0], slab))
    # slab: underside, top, edges of the well
    S.rect("z", ceil0, (0, 0), (X, Y), [well])
    S.rect("z", slab, (0, 0), (X, Y), [well])
    S.rect("x", well[1][0], (well[0][1], ceil0), (well[1][1], slab))
    S.rect("y", well[1][1], (well[0][0], ceil0), (well[1][0], slab))
    # stairs along +x against the south wall: risers, treads, open side face (step profile)
    for i in range(n_steps):
        x = stair_x0 + i * run
        S.rect("x", x, (0.0, i * rise), (stair_w, (i + 1) * rise))
        if i < n_steps - 1:
            S.rect("z", (i + 1) * rise, (x, 0.0), (x + run, stair_w))
            S.rect("y", stair_w, (x, 0.0), (x + run, (i + 1) * rise))
    # railing panel (1 m) along the long side of the well on the upper floor
    S.rect("y", well[1][1], (0.0, slab), (stair_x1 - 1.0, slab + 1.0))
    # partitions with doors
    S.wall("x", 8.0, _WALL_T, (0.0, 0.0), (Y, ceil0), [(4.0, 4.0 + _DOOR_W, _DOOR_H)])
    S.wall("x", 8.5, _WALL_T, (0.0, slab), (Y, top), [(6.0, 6.0 + _DOOR_W, slab + _DOOR_H)])
    queries = [
        ((10.5, 2.0, 1.2), (10.5, 2.0, 4.4),
         "straight up is blocked by the slab: out through the ground-floor door, up the stairs, "
         "back through the upper door"),
        ((6.5, 6.5, 1.0), (2.0, 6.0, 4.7),
         "ground floor middle to the west end of the upper floor"),
        ((10.0, 6.5, 4.5), (2.5, 5.0, 1.5), "upper east room down to the ground floor"),
    ]
    info = _info(
        "two_storey",
        "Two floors of 12 x 8 m, 3 m high (ground floor z 0..3, 0.2 m slab, upper floor "
        "z 3.2..6.2) joined by a straight 16-step stair (rise 0.2 m, run 0.3 m, 1.2 m wide) "
        "along the south wall under a 5.5 x 2.2 m opening in the slab, with a 1 m railing "
        "panel along part of the opening; each floor is split by a partition with a door.",
        seed, spacing, ((0, 0, 0), (X, Y, top)), 0.25, 0.002, queries,
        extra={"slab_opening": [[0.0, 0.0, ceil0], [stair_x1, 2.2, slab]],
               "stairs": {"steps": n_steps, "rise": rise, "run": run, "width": stair_w}},
    )
    return _Map(S.points(), info)


# --------------------------------------------------------------------------------------------
# warehouse
# --------------------------------------------------------------------------------------------


def _warehouse(seed: int) -> _Map:
    rng = np.random.default_rng([seed, 3])
    spacing = 0.17
    S = _Surfaces(rng, spacing)
    X, Y, H = 30.0, 20.0, 6.0
    rx0, rx1, depth, rack_h = 4.0, 26.0, 1.0, 4.5
    levels = [0.15, 1.6, 3.05, rack_h]
    n_bays = 8
    bay = (rx1 - rx0) / n_bays
    racks = [2.0 + 3.0 * k for k in range(6)]  # y of the front face; aisles are 2 m wide
    post = 0.08
    S.rect("z", 0.0, (0, 0), (X, Y))
    S.rect("z", H, (0, 0), (X, Y))
    S.rect("x", 0.0, (0, 0), (Y, H))
    S.rect("x", X, (0, 0), (Y, H))
    S.rect("y", 0.0, (0, 0), (X, H))
    S.rect("y", Y, (0, 0), (X, H))
    for y0 in racks:
        y1 = y0 + depth
        for z in levels:  # boards (thin: one sampled plane each)
            S.rect("z", z, (rx0, y0), (rx1, y1))
        S.rect("y", y0 + depth / 2, (rx0, 0.0), (rx1, rack_h))  # back mesh
        for yf in (y0, y1):  # kick plates under the bottom board
            S.rect("y", yf, (rx0, 0.0), (rx1, levels[0]))
        for j in range(n_bays + 1):  # uprights
            x = rx0 + j * bay
            xa = min(max(x - post / 2, rx0), rx1 - post)
            xb = xa + post
            for yp in (y0, y1 - post):
                S.box((xa, yp, 0.0), (xb, yp + post, rack_h))
        for j in range(n_bays):  # goods on the boards, front and back half
            for z0, z1 in zip(levels[:-1], levels[1:], strict=True):
                for half in (0, 1):
                    if rng.uniform() < 0.35:
                        continue
                    w = float(rng.uniform(0.8, bay - 0.3))
                    d = float(rng.uniform(0.3, depth / 2 - 0.05))
                    ht = float(rng.uniform(0.3, z1 - z0 - 0.15))
                    gx = rx0 + j * bay + post + float(rng.uniform(0.0, bay - 2 * post - w))
                    gy = y0 + 0.02 if half == 0 else y1 - d - 0.02
                    S.box((gx, gy, z0), (gx + w, gy + d, z0 + ht))
    queries = [
        ((6.0, 4.0, 1.5), (20.0, 13.0, 1.5),
         "from the first inner aisle to the fourth one: via a cross aisle (or over the racks)"),
        ((2.0, 16.0, 1.0), (24.0, 7.0, 3.5), "west cross aisle to high up in a far aisle"),
        ((15.0, 1.0, 1.0), (15.0, 19.0, 1.0), "south wall aisle to north wall aisle"),
    ]
    info = _info(
        "warehouse",
        "Warehouse hall 30 x 20 x 6 m with six parallel 22 m shelf racks along x (1 m deep, "
        "4.5 m high, boards at 0.15/1.6/3.05/4.5 m, uprights every 2.75 m, a back mesh and "
        "random goods boxes), 2 m aisles between racks and walls, 4 m cross aisles at both "
        "ends; 1.5 m free above the racks.",
        seed, spacing, ((0, 0, 0), (X, Y, H)), 0.3, 0.008, queries,
        extra={"racks_y": [[y, y + depth] for y in racks], "racks_x": [rx0, rx1],
               "rack_height": rack_h, "aisle_width": 2.0},
    )
    return _Map(S.points(), info)


# --------------------------------------------------------------------------------------------
# forest
# --------------------------------------------------------------------------------------------


def _height_field(rng: np.random.Generator, size: float) -> Callable[[np.ndarray, np.ndarray],
                                                                      np.ndarray]:
    """Smooth ground height field over [0, size]^2 scaled to the range [-1, 1] m."""
    waves = [(rng.uniform(0.5, 1.0), rng.uniform(-1, 1, 2), rng.uniform(9, 25),
              rng.uniform(0, 2 * math.pi)) for _ in range(4)]
    bumps = [(rng.uniform(-1, 1), rng.uniform(0, size, 2), rng.uniform(2.5, 5.0))
             for _ in range(5)]

    def raw(x, y):
        z = np.zeros(np.broadcast(x, y).shape)
        for amp, direc, wl, ph in waves:
            u = (direc[0] * x + direc[1] * y) / np.hypot(*direc)
            z += amp * np.sin(2 * math.pi * u / wl + ph)
        for amp, c, sig in bumps:
            z += amp * np.exp(-((x - c[0]) ** 2 + (y - c[1]) ** 2) / (2 * sig * sig))
        return z

    g = np.linspace(0.0, size, 301)
    gz = raw(*np.meshgrid(g, g, indexing="ij"))
    mid, half = (gz.max() + gz.min()) / 2, (gz.max() - gz.min()) / 2

    def height(x, y):
        return (raw(np.asarray(x, float), np.asarray(y, float)) - mid) / half

    return height


def _forest(seed: int) -> _Map:
    rng = np.random.default_rng([seed, 4])
    spacing = 0.12
    S = _Surfaces(rng, spacing)
    L = 30.0
    radius = 0.3
    height = _height_field(rng, L)
    ends = [((2.0, 2.0), (28.0, 28.0)), ((2.0, 28.0), (28.0, 2.0)), ((15.0, 1.5), (15.0, 28.5))]
    notes = ["diagonal through the forest", "other diagonal", "south edge to north edge"]
    q_xy = np.array([p for e in ends for p in e])
    # trunks: (x, y, r, h), rejection sampled with a clear gap of >= 1 m between trunks
    trees: list[tuple[float, float, float, float]] = []
    target = int(rng.integers(70, 91))
    for _ in range(20000):
        if len(trees) >= target:
            break
        x, y = rng.uniform(0.8, L - 0.8, 2)
        r = float(rng.uniform(0.15, 0.4))
        hgt = float(rng.uniform(4.0, 8.0))
        if np.min(np.hypot(q_xy[:, 0] - x, q_xy[:, 1] - y)) < 1.5 + r:
            continue
        if all(math.hypot(x - tx, y - ty) >= r + tr + 1.0 for tx, ty, tr, _ in trees):
            trees.append((float(x), float(y), r, hgt))

    def blocked(a, b) -> bool:
        a, b = np.array(a), np.array(b)
        d = b - a
        for tx, ty, tr, _ in trees:
            t = np.clip(np.dot(np.array([tx, ty]) - a, d) / np.dot(d, d), 0, 1)
            if np.linalg.norm(a + t * d - (tx, ty)) < tr + radius:
                return True
        return False

    for a, b in ends:  # make sure no query is a straight shot between the trunks
        if not blocked(a, b):
            mx, my = (np.array(a) + np.array(b)) / 2
            trees.append((float(mx), float(my), 0.3, 6.0))
    # ground, without the footprints of the trunks
    gx, gy = S._grid(L, L)
    keep = np.ones(gx.shape, dtype=bool)
    for tx, ty, tr, _ in trees:
        keep &= np.hypot(gx - tx, gy - ty) > tr
    S.add(np.column_stack([gx[keep], gy[keep], height(gx[keep], gy[keep])]))
    # trunks and a few crowns
    for tx, ty, tr, hgt in trees:
        base = float(height(tx, ty))
        crown = None
        if hgt >= 5.5 and rng.uniform() < 0.3:
            rc = min(float(rng.uniform(1.0, 1.8)), (hgt - 3.0) / 2,
                     tx - 0.05, ty - 0.05, L - 0.05 - tx, L - 0.05 - ty)  # inside the square
            if rc >= 0.5:
                crown = (np.array([tx, ty, base + hgt - rc]), rc)
        before = len(S.parts)
        S.cylinder(tx, ty, tr, base - 0.5, base + hgt)
        trunk = S.parts.pop(before)
        ok = trunk[:, 2] >= height(trunk[:, 0], trunk[:, 1])
        if crown is not None:
            ok &= np.linalg.norm(trunk - crown[0], axis=1) > crown[1]
        S.add(trunk[ok])
        if crown is not None:
            S.sphere(crown[0], crown[1])
            ball = S.parts.pop()
            S.add(ball[ball[:, 2] > height(ball[:, 0], ball[:, 1])])
    pts = S.points()
    zmin = math.floor((pts[:, 2].min() - 0.02) * 10) / 10
    zmax = math.ceil((pts[:, 2].max() + 0.02) * 10) / 10
    queries = [
        ((a[0], a[1], float(height(*a)) + 1.5), (b[0], b[1], float(height(*b)) + 1.5), note)
        for (a, b), note in zip(ends, notes, strict=True)
    ]
    gh = height(*np.meshgrid(np.linspace(0, L, 61), np.linspace(0, L, 61)))
    info = _info(
        "forest",
        f"Forest patch 30 x 30 m without ceiling: smooth uneven ground (height field of "
        f"sinusoids and gaussian bumps, -1..+1 m), {len(trees)} vertical tree trunks "
        f"(radius 0.15-0.4 m, 4-8 m tall, clear gaps >= 1 m) and a few spherical crowns at "
        f">= 3 m above their trunk base. Queries are 1.5 m above the ground.",
        seed, spacing, ((0, 0, zmin), (L, L, zmax)), radius, 0.008, queries,
        extra={"n_trees": len(trees), "ground_height_range": [round(float(gh.min()), 3),
                                                               round(float(gh.max()), 3)]},
    )
    return _Map(pts, info)


# --------------------------------------------------------------------------------------------
# narrow passage
# --------------------------------------------------------------------------------------------

PASSAGE_WIDTH = 0.7
PASSAGE_HEIGHT = 1.0
PASSAGE_LENGTH = 3.0


def _narrow_passage(seed: int) -> _Map:
    rng = np.random.default_rng([seed, 5])
    spacing = 0.05
    S = _Surfaces(rng, spacing)
    C, H = 6.0, 3.0  # chambers are C x C x H
    W, PH, PL = PASSAGE_WIDTH, PASSAGE_HEIGHT, PASSAGE_LENGTH
    yc = C / 2
    p0, p1 = yc - W / 2, yc + W / 2
    xa, xb = C, C + PL  # passage between the two chamber walls
    X = 2 * C + PL
    hole = [((p0, 0.0 - 1.0), (p1, PH))]
    for x0, x1 in ((0.0, xa), (xb, X)):  # the two closed chambers, seen from inside
        S.rect("z", 0.0, (x0, 0.0), (x1, C))
        S.rect("z", H, (x0, 0.0), (x1, C))
        S.rect("y", 0.0, (x0, 0.0), (x1, H))
        S.rect("y", C, (x0, 0.0), (x1, H))
        S.rect("x", x0, (0.0, 0.0), (C, H), hole if x0 == xb else ())
        S.rect("x", x1, (0.0, 0.0), (C, H), hole if x1 == xa else ())
    # the passage: floor, ceiling, side walls
    S.rect("z", 0.0, (xa, p0), (xb, p1))
    S.rect("z", PH, (xa, p0), (xb, p1))
    S.rect("y", p0, (xa, 0.0), (xb, PH))
    S.rect("y", p1, (xa, 0.0), (xb, PH))
    queries = [
        ((3.0, 3.0, 1.5), (12.0, 3.0, 1.5), "chamber to chamber, must drop into the passage"),
        ((1.5, 1.5, 2.0), (13.5, 4.5, 0.8), "far corners of the two chambers"),
        ((3.0, 3.0, 0.75), (12.0, 3.0, 0.75),
         "in line with the passage but too high for its 1 m ceiling"),
    ]
    info = _info(
        "narrow_passage",
        f"Two closed 6 x 6 x 3 m chambers (x 0..6 and 9..15) joined by a single straight "
        f"passage {PL} m long along x, centred at y = 3, with clear width W = {W} m and "
        f"clear height {PH} m (floor at z = 0); with the suggested robot radius 0.3 m the "
        f"robot centre must stay in a band 0.1 m wide (y 2.95..3.05) and 0.4 m high "
        f"(z 0.3..0.7) along the passage. The space between the "
        f"chambers outside the passage is enclosed and unreachable.",
        seed, spacing, ((0, 0, 0), (X, C, H)), 0.3, 0.001, queries,
        extra={"passage_width": W, "passage_height": PH, "passage_length": PL,
               "passage_box": [[xa, p0, 0.0], [xb, p1, PH]],
               "robot_centre_band": [[xa, round(p0 + 0.3, 3), 0.3],
                                     [xb, round(p1 - 0.3, 3), round(PH - 0.3, 3)]]},
    )
    return _Map(S.points(), info)


# --------------------------------------------------------------------------------------------
# public API
# --------------------------------------------------------------------------------------------

_BUILDERS: dict[str, Callable[[int], _Map]] = {
    "office": _office,
    "two_storey": _two_storey,
    "warehouse": _warehouse,
    "forest": _forest,
    "narrow_passage": _narrow_passage,
}


def build(name: str, seed: int = 0) -> tuple[np.ndarray, dict[str, Any]]:
    """Build map ``name``: ``(points (N, 3) float64, sidecar info dict)``, validated."""
    if name not in _BUILDERS:
        raise MapError(f"unknown map {name!r}; known: {sorted(_BUILDERS)}")
    m = _validate(_BUILDERS[name](int(seed)))
    return m.points, m.info


def office(seed: int = 0) -> np.ndarray:
    """Office floor 20 x 12 x 3 m: corridor, eight rooms, 0.9 x 2.1 m doors. (N, 3) points."""
    return build("office", seed)[0]


def two_storey(seed: int = 0) -> np.ndarray:
    """Two 12 x 8 x 3 m floors joined by a stairwell. (N, 3) points."""
    return build("two_storey", seed)[0]


def warehouse(seed: int = 0) -> np.ndarray:
    """Warehouse 30 x 20 x 6 m with six shelf racks and 2 m aisles. (N, 3) points."""
    return build("warehouse", seed)[0]


def forest(seed: int = 0) -> np.ndarray:
    """Forest 30 x 30 m: uneven ground, 70-90 trunks, a few crowns. (N, 3) points."""
    return build("forest", seed)[0]


def narrow_passage(seed: int = 0) -> np.ndarray:
    """Two 6 x 6 x 3 m chambers joined by a 3 m passage 0.7 m wide, 1 m high. (N, 3) points."""
    return build("narrow_passage", seed)[0]


MAPS: dict[str, Callable[..., np.ndarray]] = {
    "office": office,
    "two_storey": two_storey,
    "warehouse": warehouse,
    "forest": forest,
    "narrow_passage": narrow_passage,
}
"""Registry: map name -> generator ``f(seed=0) -> np.ndarray (N, 3)``."""


def _atomic_write(path: Path, write: Callable[[str], None]) -> None:
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    os.close(fd)
    try:
        write(tmp)
        os.chmod(tmp, 0o644)  # mkstemp makes 0600 files
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise


def _write_ply(path: Path, points: np.ndarray, comment: str) -> None:
    from plyfile import PlyData, PlyElement

    vertex = np.empty(len(points), dtype=[("x", "<f4"), ("y", "<f4"), ("z", "<f4")])
    for i, k in enumerate("xyz"):
        vertex[k] = points[:, i]
    data = PlyData([PlyElement.describe(vertex, "vertex")], text=False, byte_order="<",
                   comments=[comment])
    _atomic_write(path, lambda tmp: data.write(tmp))


def _write_json(path: Path, info: dict[str, Any]) -> None:
    text = json.dumps(info, indent=2) + "\n"
    # one line per innermost list of numbers: "start": [2.0, 2.0, 1.178]
    text = re.sub(r"\[\s+([-+0-9.eE,\s]+?)\s+\]",
                  lambda m: "[" + ", ".join(v.strip() for v in m.group(1).split(",")) + "]", text)

    def write(tmp: str) -> None:
        with open(tmp, "w", encoding="utf-8", newline="\n") as f:
            f.write(text)

    _atomic_write(path, write)


def generate(name: str, out_dir: str | os.PathLike[str], seed: int = 0) -> tuple[Path, Path]:
    """Write ``<name>.ply`` and ``<name>.json`` into ``out_dir``; return both paths."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    points, info = build(name, seed)
    ply, js = out / f"{name}.ply", out / f"{name}.json"
    _write_ply(ply, points, f"lattice-planner map {name} seed {int(seed)} units m z-up")
    _write_json(js, info)
    return ply, js


def generate_all(out_dir: str | os.PathLike[str] = MAPS_DIR, seed: int = 0
                 ) -> dict[str, tuple[Path, Path]]:
    """Generate every map in :data:`MAPS` into ``out_dir``: name -> (ply path, json path)."""
    return {name: generate(name, out_dir, seed) for name in MAPS}


def map_path(name: str) -> Path:
    """Path of the bundled point cloud ``maps/<name>.ply``; MapError if unknown or missing."""
    if name not in MAPS:
        raise MapError(f"unknown map {name!r}; known: {sorted(MAPS)}")
    path = MAPS_DIR / f"{name}.ply"
    if not path.is_file():
        raise MapError(f"bundled map file {path} is missing; run `python maps/generate.py`")
    return path


def load_map_info(name_or_path: str | os.PathLike[str]) -> dict[str, Any]:
    """Sidecar info of a bundled map name, a ``.json`` sidecar path or a ``.ply`` path.

    The returned dict is the JSON content plus ``"ply_path"``: the absolute path of the
    point-cloud file next to the sidecar.
    """
    if isinstance(name_or_path, str) and name_or_path in MAPS:
        js = MAPS_DIR / f"{name_or_path}.json"
    else:
        p = Path(name_or_path)
        js = p if p.suffix.lower() == ".json" else p.with_suffix(".json")
    try:
        info = json.loads(js.read_text(encoding="utf-8"))
    except FileNotFoundError as e:
        raise MapError(f"map info {js} not found") from e
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as e:
        raise MapError(f"map info {js} is unreadable: {e}") from e
    if not isinstance(info, dict) or "bounds" not in info or "queries" not in info:
        raise MapError(f"map info {js} lacks 'bounds' or 'queries'")
    info["ply_path"] = str((js.parent / info.get("file", js.with_suffix(".ply").name)).resolve())
    return info


def load_map_points(name_or_path: str | os.PathLike[str]) -> np.ndarray:
    """Points (N, 3) float64 of a bundled map name or of a PLY file written by this module."""
    from plyfile import PlyData

    if isinstance(name_or_path, str) and name_or_path in MAPS:
        path = map_path(name_or_path)
    else:
        path = Path(name_or_path)
    try:
        v = PlyData.read(str(path))["vertex"]
        return np.column_stack([v["x"], v["y"], v["z"]]).astype(np.float64)
    except FileNotFoundError as e:
        raise MapError(f"point cloud {path} not found") from e
    except Exception as e:  # plyfile raises assorted errors on corrupt input
        raise MapError(f"point cloud {path} is unreadable: {e}") from e
