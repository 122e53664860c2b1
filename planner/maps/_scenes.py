"""The bundled scenes: office, two_storey, warehouse, forest, narrow_passage (seeded)."""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np

from planner.errors import MapError
from planner.maps._sampling import _info, _Map, _Surfaces, _validate

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
