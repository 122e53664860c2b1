"""Tri-state worlds: what is occupied, observed free or unknown, saved worlds and 2D maps."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import planner
from planner.errors import MapError, PlanError
from planner.io import Obstacles
from planner.lattice import NAMED_LATTICES, Lattice
from planner.voxels import exact_box_inflation

GEB = Path("../shared/data/octomap/geb079.bt")


def _box_dist(p: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """(P, B) exact distances from points (P, d) to axis-aligned boxes [lo, hi] (B, d)."""
    gap = np.maximum(lo[None] - p[:, None], 0) + np.maximum(p[:, None] - hi[None], 0)
    return np.linalg.norm(gap, axis=2)


def _room(res: float = 0.1) -> Obstacles:
    """A 2 x 2 x 1 m grid map: a wall at x = 1, free space observed only for y < 1.4."""
    ax = [np.arange(0, 2, res) + res / 2, np.arange(0, 2, res) + res / 2,
          np.arange(0, 1, res) + res / 2]
    c = np.stack(np.meshgrid(*ax, indexing="ij"), -1).reshape(-1, 3)
    wall = np.abs(c[:, 0] - 1.05) < res / 2 + 1e-9
    wall &= c[:, 1] < 1.2  # a gap at 1.2 <= y < 1.4, then unknown beyond
    free = ~wall & (c[:, 1] < 1.4)
    return Obstacles(points=np.zeros((0, 3)), boxes=c[wall], box_size=res, free_boxes=c[free],
                     free_box_sizes=np.full(int(free.sum()), res), bounds=[[0, 0, 0], [2, 2, 1]],
                     resolution=res, source="room")


def _unknown_voxels(obst: Obstacles, res: float, pad: float):
    """Unknown space of a grid map over its bounds padded by ``pad``: a lookup of the unknown
    voxels and the boundary ones (a known voxel among their 26 neighbours) as boxes."""
    lo = obst.bounds[0] - pad
    n = np.ceil((obst.bounds[1] + pad - lo) / res).astype(int)
    known = np.zeros(n, dtype=bool)
    for c in np.concatenate([obst.boxes, obst.free_boxes]):
        known[tuple(np.floor((c - lo) / res).astype(int))] = True
    p = np.pad(known, 1)
    near = np.zeros_like(known)
    for o in np.ndindex(3, 3, 3):
        near |= p[o[0]: o[0] + n[0], o[1]: o[1] + n[1], o[2]: o[2] + n[2]]
    edge = lo + np.argwhere(~known & near) * res

    def inside(pts: np.ndarray) -> np.ndarray:
        v = np.floor((pts - lo) / res).astype(int)
        ok = np.all((v >= 0) & (v < n), axis=1)
        out = ~ok  # beyond the padded grid: unknown
        out[ok] = ~known[tuple(v[ok].T)]
        return out

    return inside, edge, edge + res


def test_octomap_leaves_are_inflated_once_exactly():
    # Leaves of two sizes (as a pruned OctoMap): the world blocks exactly the exact set (in
    # bounds: the cells out of bounds are never free and a world does not list them).
    rng = np.random.default_rng(3)
    fine = np.round(rng.uniform(0, 2, (40, 3)) / 0.1) * 0.1 + 0.05
    coarse = np.round(rng.uniform(0, 2, (5, 3)) / 0.2) * 0.2 + 0.1
    boxes = np.concatenate([fine, coarse])
    sizes = np.r_[np.full(40, 0.1), np.full(5, 0.2)]
    obst = Obstacles(points=np.zeros((0, 3)), boxes=boxes, box_size=0.2, box_sizes=sizes,
                     bounds=[[0, 0, 0], [2, 2, 2]], resolution=0.1, source="leaves")
    for name in NAMED_LATTICES:
        w = planner.build_world(obst, name, cell_volume=0.1**3, radius=0.15)
        exact = exact_box_inflation(boxes - sizes[:, None] / 2, boxes + sizes[:, None] / 2,
                                    w.lattice, 0.15)
        inside = exact.keys[w.in_bounds(exact.indices)]
        assert w.n_blocked == len(inside), name
        assert np.array_equal(planner.occupancy.keys.pack(w.blocked), inside), name


@pytest.mark.skipif(not GEB.is_file(), reason="geb079.bt not present")
def test_geb079_blocked_counts_equal_the_exact_set_on_every_lattice():
    obst = planner.io.load_obstacles(GEB)
    h = obst.box_sizes[:, None] / 2
    for name in NAMED_LATTICES:
        w = planner.build_world(obst, name, cell_volume=0.2**3, radius=0.2, unknown="free")
        exact = exact_box_inflation(obst.boxes - h, obst.boxes + h, w.lattice, 0.2)
        assert w.n_blocked == int(w.in_bounds(exact.indices).sum()), name


@pytest.mark.parametrize("name", ["cubic", "fcc", "bcc"])
def test_no_usable_cell_comes_closer_than_the_radius_to_unknown_space(name):
    obst, r = _room(), 0.15
    w = planner.build_world(obst, name, cell_volume=0.08**3, radius=r)
    assert w.unknown_policy == "blocked" and w.n_unknown > 0
    inside, lo, hi = _unknown_voxels(obst, 0.1, 0.6)
    cells = w.lattice.quantize(np.stack(np.meshgrid(
        *[np.arange(0, 2.001, 0.04)] * 2, np.arange(0, 1.001, 0.04), indexing="ij"),
        -1).reshape(-1, 3))
    cells = np.unique(cells, axis=0)
    usable = cells[w.is_free(cells)]
    assert len(usable) > 50
    verts = w.lattice.voronoi.vertices
    pts = (w.lattice.to_world(usable)[:, None] + verts[None]).reshape(-1, 3)
    pts = np.concatenate([pts, w.lattice.to_world(usable)])
    assert not inside(pts).any()
    for i in range(0, len(pts), 2000):  # the nearest unknown point is on a boundary voxel
        assert _box_dist(pts[i: i + 2000], lo, hi).min() >= r - 1e-9
    # and the robot also keeps r from the wall
    wl, wh = obst.boxes - 0.05, obst.boxes + 0.05
    assert _box_dist(pts, wl, wh).min() >= r - 1e-9


def test_unknown_free_crosses_unknown_cells_and_counts_them():
    obst = _room()
    start, goal = (0.5, 1.7, 0.5), (1.5, 1.7, 0.5)  # both in unknown space
    free = planner.build_world(obst, "cubic", cell_volume=0.05**3, radius=0.0, unknown="free")
    res = planner.plan(free, start, goal)
    assert res.found and res.unknown_cells > 0
    assert "planned through" in res.unknown_note
    blocked = planner.build_world(obst, "cubic", cell_volume=0.05**3, radius=0.0)
    with pytest.raises(PlanError, match="blocked by unknown space"):
        planner.plan(blocked, start, goal)
    # In observed space the path goes through the gap and never touches unknown space.
    res = planner.plan(blocked, (0.5, 0.5, 0.5), (1.5, 0.5, 0.5))
    assert res.found and res.unknown_cells == 0
    assert res.path[:, 1].max() > 1.15  # around the wall's end


def test_plain_clouds_say_everything_not_occupied_is_free():
    w = planner.build_world(np.array([[1.0, 1.0, 1.0], [2.0, 2.0, 2.0]]), "fcc",
                            cell_volume=0.01, radius=0.0)
    assert w.unknown_policy == "free" and w.n_unknown == 0
    assert "no free-space information" in w.unknown_note
    with pytest.raises(MapError, match="says nothing about free space"):
        planner.build_world(np.array([[1.0, 1.0, 1.0]]), unknown="blocked", cell_volume=0.01,
                            radius=0.0, bounds=[[0, 0, 0], [2, 2, 2]])


def test_posed_scan_rays_mark_free_space():
    # A sensor at the origin sees a wall at x = 2: space between is free, behind it unknown.
    y, z = np.meshgrid(np.arange(-1, 1.001, 0.05), np.arange(-1, 1.001, 0.05))
    pts = np.column_stack([np.full(y.size, 2.0), y.ravel(), z.ravel()])
    obst = Obstacles(points=pts, boxes=np.zeros((0, 3)), box_size=0.0, bounds=None,
                     resolution=None, source="scan", origins=np.zeros((1, 3)),
                     point_origin=np.zeros(len(pts), dtype=np.int64))
    w = planner.build_world(obst, "cubic", cell_volume=0.1**3, radius=0.0,
                            bounds=[[-0.5, -1, -1], [3, 1, 1]])
    assert w.unknown_policy == "blocked"
    q = w.lattice.quantize(np.array([[1.0, 0, 0], [2.6, 0, 0], [-0.3, 0, 0]]))
    assert w.is_unknown(q).tolist() == [False, True, True]
    assert w.is_free(q).tolist() == [True, False, False]


def _in_bounds_count(world, cells: np.ndarray) -> int:
    cells = np.unique(cells, axis=0)
    return int(world.in_bounds(cells).sum())


def test_saved_world_round_trip_and_mismatches(tmp_path):
    obst = _room()
    w = planner.build_world(obst, "bcc", cell_volume=0.04**3, radius=0.03)
    out = tmp_path / "room.npz"
    planner.world.file.save_world(w, out)
    back = planner.build_world(out)
    assert back.lattice == w.lattice and back.lattice.name == "bcc"
    # out-of-bounds cells are never free, so the file keeps the in-bounds ones only
    assert back.n_blocked == _in_bounds_count(w, w.blocked)
    assert back.n_unknown == _in_bounds_count(w, w.unknown) > 0
    assert back.radius == 0.03 and back.unknown_policy == "blocked"
    assert np.array_equal(back.bounds, w.bounds)
    a = planner.plan(w, (0.5, 0.5, 0.5), (1.5, 0.5, 0.5))
    b = planner.plan(back, (0.5, 0.5, 0.5), (1.5, 0.5, 0.5))
    assert a.found and np.allclose(a.path, b.path) and a.cell_checks == b.cell_checks
    for kw, what in [({"radius": 0.2}, "radius"), ({"lattice": "fcc"}, "lattice"),
                     ({"cell_volume": 0.001}, "cell volume"), ({"unknown": "free"}, "unknown")]:
        with pytest.raises(MapError, match=f"saved with {what}"):
            planner.build_world(out, **kw)


def _ros_map(tmp_path: Path) -> Path:
    """A 40 x 30 px map (0.05 m): walls, a pillar and an unknown corner."""
    img = np.full((30, 40), 254, dtype=np.uint8)
    img[0, :] = img[-1, :] = 0
    img[:, 0] = img[:, -1] = 0
    img[10:30, 20] = 0  # a wall with a gap at the top, rows 1..9
    img[10:14, 8:12] = 0  # pillar
    img[20:29, 30:39] = 205  # unknown corner
    pgm = tmp_path / "room.pgm"
    pgm.write_bytes(b"P5\n40 30\n255\n" + img.tobytes())
    yaml = tmp_path / "room.yaml"
    yaml.write_text("image: room.pgm\nresolution: 0.05\norigin: [-1.0, -0.5, 0.0]\n"
                    "negate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n")
    return yaml


@pytest.mark.parametrize("name", ["square", "hex2d"])
@pytest.mark.parametrize("method", ["astar", "dijkstra", "theta", "lazy-theta"])
def test_ros_map_plans_on_2d_lattices_with_the_radius_guarantee(tmp_path, name, method):
    yaml = _ros_map(tmp_path)
    obst = planner.io.load_obstacles(yaml)
    r = 0.08
    w = planner.build_world(yaml, name, cell_volume=0.03**2, radius=r)
    assert w.dim == 2 and w.unknown_policy == "blocked"
    res = planner.plan(w, (-0.7, 0.0), (0.3, 0.3), method=method)
    assert res.found and res.unknown_cells == 0
    assert np.allclose(res.path[:, 2], 0)
    assert math.isclose(res.cell_volume, 0.03**2)
    # Exact segment-to-square distances: every occupied and unknown pixel kept >= r away.
    h = 0.025
    sq = np.concatenate([obst.boxes])
    lo, hi = sq - h, sq + h
    t = np.linspace(0, 1, 200)[:, None]
    for a, b in zip(res.path[:-1, :2], res.path[1:, :2], strict=True):
        p = a + t * (b - a)
        assert _box_dist(p, lo, hi).min() >= r - 1e-6


def test_2d_lattices_are_named_and_world_accepts_them():
    sq = Lattice.named("square", 0.01)
    assert sq.dim == 2 and sq.neighbors("full").shape == (8, 2)
    hx = Lattice.named("hex2d", 0.01)
    assert hx.neighbors("full").shape == (6, 2)
    w = planner.World(sq, [[5, 5]], [[0, 0], [1, 1]])
    assert w.dim == 2 and not w.checker.is_valid((0.52, 0.49, 0.0))
    assert w.lattice.neighbors("full").shape == (8, 3)
    res = planner.plan(w, (0.2, 0.5), (0.8, 0.5))
    assert res.found and np.abs(res.path[:, 1] - 0.5).max() >= 0.1 - 1e-9  # around the cell
    assert not (res.cells == [5, 5, 0]).all(axis=1).any()


def test_saved_2d_world_keeps_planar_moves(tmp_path):
    yaml = _ros_map(tmp_path)
    w = planner.build_world(yaml, "hex2d", cell_volume=0.03**2, radius=0.05)
    out = tmp_path / "room2d.npz"
    planner.world.file.save_world(w, out)
    back = planner.build_world(out)
    assert back.dim == 2 and back.lattice.neighbors("full").shape == (6, 3)
    assert back.n_blocked == _in_bounds_count(w, w.blocked)
    assert back.n_unknown == _in_bounds_count(w, w.unknown) > 0
    a = planner.plan(w, (-0.7, 0.0), (0.3, 0.3))
    b = planner.plan(back, (-0.7, 0.0), (0.3, 0.3))
    assert a.found and np.allclose(a.path, b.path)


@pytest.mark.skipif(not GEB.is_file(), reason="geb079.bt not present")
def test_geb079_default_planning_stays_in_observed_space():
    # Unknown space planned as free (the old behaviour) solves this query straight through
    # unobserved space; by default the start is reported blocked by unknown space, and a
    # query between observed free cells finds a path touching no unknown cell.
    free = planner.build_world(GEB, "cubic", cell_volume=0.1**3, radius=0.2, unknown="free")
    old = planner.plan(free, (0, 0, 1), (20, 0, 1))
    assert old.found and old.unknown_cells > 0
    world = planner.build_world(GEB, "cubic", cell_volume=0.1**3, radius=0.2)
    assert world.unknown_policy == "blocked"
    with pytest.raises(PlanError, match="start .* is blocked by unknown space"):
        planner.plan(world, (0, 0, 1), (20, 0, 1))
    res = planner.plan(world, (-0.2, -0.5, 1.0), (8.1, 0.0, 1.0))
    assert res.found and res.unknown_cells == 0


def test_cli_world_round_trip_and_path_file(tmp_path, capsys):
    import json

    from planner.cli import main

    yaml = _ros_map(tmp_path)
    out = tmp_path / "w.npz"
    assert main(["world", str(yaml), "--lattice", "square", "--cell-volume", "0.0009",
                 "--radius", "0.05", "--out", str(out)]) == 0
    path = tmp_path / "p.json"
    assert main(["plan", str(out), "--start", "-0.7,0.0", "--goal", "0.3,0.3", "--out",
                 str(path), "--shortcut"]) == 0
    rec = json.loads(path.read_text())
    assert rec["map"] == "room.yaml" and rec["frame"] == "map" and rec["lattice"] == "square"
    assert rec["map_sha256"] == planner.world.file.sha256(yaml)
    assert rec["radius"] == 0.05 and rec["cell_volume"] == 0.0009 and rec["dim"] == 2
    assert rec["start"] == [-0.7, 0.0] and rec["goal"] == [0.3, 0.3]
    assert rec["unknown_cells"] == 0 and rec["unknown_policy"] == "blocked"
    assert rec["smoothed_length"] <= rec["raw_length"]
    wp = np.array(rec["waypoints"])
    assert wp.shape[1] == 3 and np.allclose(wp[0, :2], [-0.7, 0.0])
    d = np.diff(wp[:, :2], axis=0)
    moving = np.abs(d).sum(axis=1) > 0
    assert np.allclose(wp[:-1][moving, 2], np.arctan2(d[moving, 1], d[moving, 0]), atol=1e-6)
    csv_path = tmp_path / "p.csv"
    assert main(["plan", str(out), "--start", "-0.7,0.0", "--goal", "0.3,0.3", "--out",
                 str(csv_path)]) == 0
    text = csv_path.read_text()
    assert text.startswith("x,y,yaw\n") and "#" not in text
    assert json.loads(csv_path.with_suffix(".json").read_text())["radius"] == 0.05
    capsys.readouterr()
    assert main(["plan", str(out), "--radius", "0.1", "--start", "-0.7,0.0", "--goal",
                 "0.3,0.3"]) == 2
    assert "saved with radius 0.05 m, asked for 0.1 m" in capsys.readouterr().err
    assert main(["compare", str(out), "--start", "-0.7,0.0", "--goal", "0.3,0.3"]) == 0
    assert "square" in capsys.readouterr().out


def test_bundled_floorplan_compares_square_and_hex(capsys):
    from planner.cli import main

    assert main(["compare", "floorplan", "--lattices", "square,hex2d"]) == 0
    out = capsys.readouterr().out
    assert "square" in out and "hex2d" in out and "3/3" in out


def test_posed_scans_plan_in_ray_cast_free_space(tmp_path, capsys):
    # Two scans of a 4 x 4 x 2 m room from sensors inside it: planning inside works by
    # default, and a goal outside the walls (never observed) is blocked by unknown space.
    from planner.cli import main

    g = np.arange(0, 4.001, 0.1)
    h = np.arange(0, 2.001, 0.1)
    walls = []
    for fixed, axis in [(0.0, 0), (4.0, 0), (0.0, 1), (4.0, 1)]:
        a, z = np.meshgrid(g, h)
        p = np.zeros((a.size, 3))
        p[:, axis], p[:, 1 - axis], p[:, 2] = fixed, a.ravel(), z.ravel()
        walls.append(p)
    fx, fy = np.meshgrid(g, g)
    for zz in (0.0, 2.0):
        walls.append(np.column_stack([fx.ravel(), fy.ravel(), np.full(fx.size, zz)]))
    room = np.concatenate(walls)
    for i, origin in enumerate([(1.0, 2.0, 1.0), (3.0, 2.0, 1.0)]):
        np.savetxt(tmp_path / f"s{i}.xyz", room - origin)  # scans in the sensor frame
    (tmp_path / "poses.txt").write_text("s0.xyz 1 2 1 0 0 0 1\ns1.xyz 3 2 1 0 0 0 1\n")
    common = ["plan", str(tmp_path / "poses.txt"), "--format", "poses", "--lattice", "fcc",
              "--cell-volume", "0.001", "--radius", "0.1", "--bounds", "-1,-1,0,5,5,2"]
    assert main([*common, "--start", "1,1,1", "--goal", "3,3,1", "--json"]) == 0
    import json

    res = json.loads(capsys.readouterr().out)
    assert res["found"] and res["unknown_cells"] == 0
    assert main([*common, "--start", "1,1,1", "--goal", "4.6,2,1"]) == 2
    assert "blocked by unknown space" in capsys.readouterr().err


def test_a_world_knows_it_meets_unknown_space_after_every_change(tmp_path):
    """``has_unknown`` (asked by every plan, and remembered) follows the cells added to the
    unknown set: one by one, from an inflation grid, and through a saved file."""
    def empty_world():
        return planner.World(Lattice.named("cubic", 1.0), np.zeros((0, 3), np.int64),
                             [[0, 0, 0], [7, 7, 7]])

    w = empty_world()
    assert not w.has_unknown
    note = w.unknown_note
    w.add_unknown(np.array([[3, 3, 3]]))
    assert w.has_unknown and w.n_unknown == 1 and w.unknown_note != note

    w = empty_world()
    assert not w.has_unknown
    grid = np.zeros(8 * 8 * 8, np.uint8)
    grid[(2 * 8 + 2) * 8 + 2] = 1
    w.block_marked(grid, np.zeros(3, np.int64), np.full(3, 8, np.int64), 1, unknown=True)
    assert w.has_unknown and w.is_unknown([[2, 2, 2]])[0]

    out = tmp_path / "w.npz"
    planner.world.file.save_world(w, out)
    back = planner.build_world(out)
    assert back.has_unknown and back.n_unknown == 1


@pytest.mark.parametrize("name", [*NAMED_LATTICES, "custom"])
def test_endpoints_give_what_endpoint_gives(name):
    """World.endpoints (one compiled lookup for both points when it can) returns the
    values, counts the lookups and raises the errors of two endpoint calls, start first."""
    if name == "custom":
        lat = Lattice(np.array([[1.0, 0.3, 0.0], [0.0, 1.0, 0.2], [0.0, 0.0, 0.9]]))
    else:
        lat = Lattice.named(name, 0.37)
    rng = np.random.default_rng(7)
    w = planner.World(lat, rng.integers(0, 8, (60, 3)), [[0.0, 0.0, 0.0], [6.0, 6.0, 6.0]])
    pts = [rng.uniform(-0.5, 6.5, 3) for _ in range(80)]
    pts += [np.array([np.nan, 1.0, 1.0]), np.array([1.0, np.inf, 1.0]), [1.0, 2.0, 3.0],
            np.array([1, 2, 3]), np.array([1.0, 2.0]), np.array([6.0 + 1e-10, 3.0, 0.0])]
    for i in range(len(pts)):
        a, b = pts[i], pts[(i * 7 + 3) % len(pts)]
        before = w.cell_checks
        try:
            want = (*w.endpoint(a, "start"), *w.endpoint(b, "goal"))
        except PlanError as e:
            want = str(e)
        n_want = w.cell_checks - before
        before = w.cell_checks
        try:
            s, sc, g, gc = w.endpoints(a, b)
            got = (s, sc, g, gc)
        except PlanError as e:
            got = str(e)
        assert w.cell_checks - before == n_want
        if isinstance(want, str):
            assert got == want
        else:
            assert all(np.array_equal(x, y) and x.dtype == y.dtype
                       for x, y in zip(got, want, strict=True))
