"""Occupied voxel lists: membership, merging, files, box obstacles, inflation guarantee."""

from __future__ import annotations

import itertools
import math
import os
from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import linprog, minimize

from planner import voxels as V
from planner.errors import MapError, PlanError
from planner.io import Obstacles
from planner.lattice import NAMED_LATTICES, Lattice
from planner.voxels import OccupiedVoxelList, exact_inflation
from planner.world import World

DATA = (Path(__file__).parents[1] / ".." / "shared" / "data").resolve()
GEB079 = DATA / "octomap" / "geb079.bt"

HEX2D = Lattice(np.array([[1.0, 0.5], [0.0, math.sqrt(3) / 2]]), name="hex2d")


def _lattices() -> list[Lattice]:
    return [Lattice.named(n, 1.0) for n in NAMED_LATTICES] + [HEX2D]


LATTICES = _lattices()
IDS = [lat.name for lat in LATTICES]


# -- membership and construction -------------------------------------------------------------
@pytest.mark.parametrize("lat", LATTICES, ids=IDS)
def test_membership_matches_python_set(lat):
    rng = np.random.default_rng(1)
    d = lat.dim
    w = rng.integers(-20, 20, size=(3000, d))
    w = np.concatenate([w, w[:500]])  # duplicates
    occ = OccupiedVoxelList(lat, w)
    ref = {tuple(r) for r in w.tolist()}
    assert len(occ) == len(ref)
    assert occ.nbytes == 8 * len(ref)
    q = rng.integers(-22, 22, size=(20000, d))
    got = occ.contains(q)
    assert got.tolist() == [tuple(r) in ref for r in q.tolist()]
    # Sorted, lexicographic, round trip through keys.
    idx = occ.indices
    assert {tuple(r) for r in idx.tolist()} == ref
    assert [tuple(r) for r in idx.tolist()] == sorted(ref)
    assert np.all(np.diff(occ.keys) > 0)
    np.testing.assert_allclose(occ.centers(), idx @ lat.generator.T)
    b = occ.bounds()
    assert b.shape == (2, d)
    np.testing.assert_allclose(b, [occ.centers().min(0), occ.centers().max(0)])
    assert OccupiedVoxelList.from_indices(w, lat) == occ
    assert "OccupiedVoxelList" in repr(occ)


def test_contains_edge_cases():
    lat = Lattice.named("fcc", 1.0)
    occ = OccupiedVoxelList(lat, [[0, 0, 0], [1, 2, 3]])
    far = [[2**40, 0, 0], [0, -(2**40), 0], [1, 2, 3]]
    assert occ.contains(far).tolist() == [False, False, True]
    assert occ.contains([1, 2, 3]).tolist() == [True]
    assert occ.contains(np.zeros((0, 3), np.int64)).shape == (0,)
    empty = OccupiedVoxelList(lat, np.zeros((0, 3), np.int64))
    assert len(empty) == 0 and not empty.contains([[0, 0, 0]]).any()
    with pytest.raises(MapError, match="empty"):
        empty.bounds()


@pytest.mark.parametrize("lat", LATTICES, ids=IDS)
def test_from_points_and_add_points(lat):
    rng = np.random.default_rng(2)
    a = rng.normal(0, 5, size=(2000, lat.dim))
    b = rng.normal(3, 5, size=(3000, lat.dim))
    occ = OccupiedVoxelList.from_points(a, lat)
    assert set(map(tuple, occ.indices.tolist())) == set(map(tuple, lat.quantize(a).tolist()))
    assert occ.add_points(b) is occ
    assert occ == OccupiedVoxelList.from_points(np.concatenate([a, b]), lat)
    assert np.all(np.diff(occ.keys) > 0)
    occ.add_points(np.zeros((0, lat.dim)))
    assert occ == OccupiedVoxelList.from_points(np.concatenate([b, a]), lat)


@pytest.mark.parametrize(
    ("points", "match"),
    [
        (np.zeros((0, 3)), "empty"),
        (np.array([[0.0, np.nan, 1.0]]), r"NaN or infinite.*row 0"),
        (np.array([[0.0, 1.0, 2.0], [np.inf, 0, 0]]), r"NaN or infinite.*row 1"),
        (np.zeros((5, 2)), r"shape \(N, 3\)"),
        (np.zeros((2, 3, 1)), r"shape \(N, 3\)"),
        ([["a", "b", "c"]], "numeric"),
    ],
)
def test_bad_points(points, match):
    lat = Lattice.named("bcc", 1.0)
    with pytest.raises(MapError, match=match):
        OccupiedVoxelList.from_points(points, lat)


def test_bad_indices_and_lattice():
    lat = Lattice.named("cubic", 1.0)
    with pytest.raises(MapError, match="integers"):
        OccupiedVoxelList(lat, np.zeros((2, 3)))
    with pytest.raises(MapError, match="shape"):
        OccupiedVoxelList(lat, np.zeros((2, 2), np.int64))
    with pytest.raises(MapError, match="Lattice"):
        OccupiedVoxelList("fcc", np.zeros((2, 3), np.int64))
    with pytest.raises(MapError, match="exceed"):
        OccupiedVoxelList(lat, [[2**22, 0, 0]])
    occ = OccupiedVoxelList(lat, [[0, 0, 0]])
    for bad in (-1.0, float("nan"), float("inf"), "x"):
        with pytest.raises(PlanError, match="radius"):
            occ.inflate(bad)


# -- files -------------------------------------------------------------------------------------
@pytest.mark.parametrize("lat", [Lattice.named("mcc", 0.3), HEX2D], ids=["mcc", "hex2d"])
def test_save_load_round_trip(tmp_path, lat):
    rng = np.random.default_rng(3)
    occ = OccupiedVoxelList(lat, rng.integers(-50, 50, size=(500, lat.dim)))
    path = tmp_path / "map.npz"
    occ.save(path)
    assert os.listdir(tmp_path) == ["map.npz"]
    back = OccupiedVoxelList.load(path)
    assert back == occ and back.lattice == lat and back.lattice.name == lat.name
    assert OccupiedVoxelList.load(path, lattice=lat) == occ
    # Named lattices come back with their fast quantizer (same answers as the original).
    x = rng.normal(0, 3, size=(200, lat.dim))
    np.testing.assert_array_equal(back.lattice.quantize(x), lat.quantize(x))
    occ.save(str(path))  # overwrite in place
    assert OccupiedVoxelList.load(str(path)) == occ


def test_load_rejects_other_lattice(tmp_path):
    occ = OccupiedVoxelList(Lattice.named("fcc", 1.0), [[0, 0, 0]])
    path = tmp_path / "m.npz"
    occ.save(path)
    with pytest.raises(MapError, match=r"m.npz: map was saved with lattice fcc.*not bcc"):
        OccupiedVoxelList.load(path, lattice=Lattice.named("bcc", 1.0))
    with pytest.raises(MapError, match=r"saved with lattice fcc \(cell volume 1\), not fcc"):
        OccupiedVoxelList.load(path, lattice=Lattice.named("fcc", 2.0))
    with pytest.raises(MapError, match="saved with lattice"):
        OccupiedVoxelList.load(path, lattice=HEX2D)


def _write_npz(path: Path, **over) -> None:
    fields = {"format": np.array(V.FORMAT), "version": np.array(1), "dim": np.array(3),
              "lattice": np.array("cubic"), "generator": np.eye(3),
              "keys": np.array([1, 5, 9], dtype=np.int64)}
    fields.update(over)
    fields = {k: v for k, v in fields.items() if v is not None}
    with open(path, "wb") as fh:
        np.savez(fh, **fields)


@pytest.mark.parametrize(
    ("over", "match"),
    [
        ({"version": np.array(2)}, "version 2 is not supported"),
        ({"format": np.array("something else")}, "not a voxel list"),
        ({"keys": None}, "missing keys"),
        ({"keys": np.array([5, 1], dtype=np.int64)}, "corrupt"),
        ({"keys": np.array([1.0, 2.0])}, "corrupt"),
        ({"generator": np.eye(2)}, "corrupt"),
        ({"generator": np.zeros((3, 3))}, "corrupt"),
    ],
)
def test_load_rejects_bad_contents(tmp_path, over, match):
    path = tmp_path / "bad.npz"
    _write_npz(path, **over)
    with pytest.raises(MapError, match=f"bad.npz: .*{match}"):
        OccupiedVoxelList.load(path)


def test_load_rejects_corrupt_or_missing_file(tmp_path):
    good = tmp_path / "good.npz"
    _write_npz(good)
    assert len(OccupiedVoxelList.load(good)) == 3
    raw = good.read_bytes()
    trunc = tmp_path / "trunc.npz"
    trunc.write_bytes(raw[: len(raw) // 2])
    junk = tmp_path / "junk.npz"
    junk.write_bytes(b"not a zip file at all" * 10)
    for p in (trunc, junk):
        with pytest.raises(MapError, match=p.name):
            OccupiedVoxelList.load(p)
    with pytest.raises(MapError, match="nope.npz: .*not found"):
        OccupiedVoxelList.load(tmp_path / "nope.npz")


def test_save_failure_leaves_nothing(tmp_path, monkeypatch):
    occ = OccupiedVoxelList(Lattice.named("hex", 1.0), [[1, 2, 3]])
    missing = tmp_path / "no" / "such" / "dir" / "m.npz"
    with pytest.raises(MapError, match="does not exist"):
        occ.save(missing)
    assert not (tmp_path / "no").exists()
    # A failure while writing: the old file survives, no temporary file is left.
    target = tmp_path / "m.npz"
    occ.save(target)
    before = target.read_bytes()

    def boom(*a, **k):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(np, "savez", boom)
    with pytest.raises(MapError, match="No space left"):
        OccupiedVoxelList(Lattice.named("hex", 1.0), [[0, 0, 0]]).save(target)
    assert os.listdir(tmp_path) == ["m.npz"]
    assert target.read_bytes() == before


# -- boxes ---------------------------------------------------------------------------------------
def _box_meets_cell(lat: Lattice, centre: np.ndarray, size: float, cell: np.ndarray) -> float:
    """Largest t such that a point lies t inside both the box and the Voronoi cell (LP);
    > 0 iff they overlap with positive volume, >= 0 iff the closed sets intersect."""
    d = lat.dim
    rel = lat.relevant_vectors
    n = np.linalg.norm(rel, axis=1)
    a = rel / n[:, None]
    c = lat.generator @ cell
    a_ub = np.vstack([np.hstack([a, np.ones((len(a), 1))]),
                      np.hstack([np.eye(d), np.ones((d, 1))]),
                      np.hstack([-np.eye(d), np.ones((d, 1))])])
    b_ub = np.concatenate([n / 2 + a @ c, centre + size / 2, -(centre - size / 2)])
    res = linprog(np.r_[np.zeros(d), -1.0], A_ub=a_ub, b_ub=b_ub,
                  bounds=[(None, None)] * d + [(-100, 100)], method="highs")
    assert res.status == 0
    return -res.fun


@pytest.mark.parametrize("lat", LATTICES, ids=IDS)
def test_box_cells_exact(lat):
    # Random boxes: no touching ties (asserted), so closed and open overlap agree.
    rng = np.random.default_rng(4)
    for size in (0.37, 1.0, 2.6):
        centre = rng.uniform(-3, 3, size=lat.dim)
        got = {tuple(r) for r in unpack_keys(V.box_keys(centre[None], size, lat), lat.dim)}
        reach = size / 2 * math.sqrt(lat.dim) + lat.covering_radius + 1e-6
        k = np.ceil(reach * np.linalg.norm(np.linalg.inv(lat.generator), axis=1)).astype(int)
        base = lat.quantize(centre[None])[0]
        want = set()
        for off in itertools.product(*[range(-x - 1, x + 2) for x in k]):
            cell = base + np.array(off)
            if np.linalg.norm(lat.generator @ cell - centre) > reach:
                continue
            slack = _box_meets_cell(lat, centre, size, cell)
            assert abs(slack) > 1e-7, "degenerate random box; change the seed"
            if slack > 0:
                want.add(tuple(cell.tolist()))
        assert got == want


def test_aligned_boxes_do_not_grow():
    # .3dmap-style unit voxels on the unit cubic lattice: each box is exactly one cell (the
    # 26 neighbours only touch it), so a native-resolution cubic world is the voxel map.
    lat = Lattice.named("cubic", 1.0)
    vox = np.random.default_rng(11).integers(0, 30, size=(500, 3))
    ob = Obstacles(points=np.zeros((0, 3)), boxes=vox.astype(float), box_size=1.0,
                   bounds=None, resolution=1.0, source="t.3dmap")
    assert OccupiedVoxelList.from_obstacles(ob, lat) == OccupiedVoxelList(lat, vox)
    # A zero-size box is a point; a box thinner than the tolerance still keeps its cell.
    c = np.array([[0.3, 0.2, 0.1]])
    assert len(V.box_keys(c, 0.0, lat)) == 1
    assert len(V.box_keys(c, 1e-12, lat)) == 1
    with pytest.raises(MapError, match="box size"):
        V.box_keys(c, -1.0, lat)


def unpack_keys(keys, dim):
    from planner.occupancy.keys import unpack

    return unpack(keys, dim).tolist()


def test_from_obstacles_uses_each_box_size():
    lat = Lattice.named("fcc", 0.2)
    centres = np.array([[0.0, 0.0, 0.0], [5.0, 1.0, 2.0]])
    ob = Obstacles(points=np.zeros((0, 3)), boxes=centres, box_size=3.0, bounds=None,
                   resolution=None, source="mixed", box_sizes=np.array([1.0, 3.0]))
    want = np.union1d(V.box_keys(centres[:1], 1.0, lat), V.box_keys(centres[1:], 3.0, lat))
    np.testing.assert_array_equal(OccupiedVoxelList.from_obstacles(ob, lat).keys, want)


def test_from_obstacles_points_and_boxes():
    lat = Lattice.named("fcc", 0.5)
    rng = np.random.default_rng(5)
    pts = rng.uniform(0, 4, size=(50, 3))
    boxes = rng.uniform(0, 4, size=(40, 3))
    ob = Obstacles(points=pts, boxes=boxes, box_size=0.7, bounds=None, resolution=None,
                   source="test")
    occ = OccupiedVoxelList.from_obstacles(ob, lat)
    want = np.union1d(OccupiedVoxelList.from_points(pts, lat).keys, V.box_keys(boxes, 0.7, lat))
    np.testing.assert_array_equal(occ.keys, want)
    # Every box corner and centre lies in an occupied cell.
    corners = (boxes[:, None, :] + 0.35 * np.array(list(itertools.product((-1, 1), repeat=3)))
               ).reshape(-1, 3)
    assert occ.contains(lat.quantize(np.concatenate([corners, boxes]))).all()
    only_boxes = Obstacles(points=np.zeros((0, 3)), boxes=boxes, box_size=0.7, bounds=None,
                           resolution=None, source="t")
    np.testing.assert_array_equal(OccupiedVoxelList.from_obstacles(only_boxes, lat).keys,
                                  V.box_keys(boxes, 0.7, lat))
    with pytest.raises(MapError, match="3D"):
        OccupiedVoxelList.from_obstacles(ob, HEX2D)


# -- inflation -----------------------------------------------------------------------------------
def _segment_point_dist(a: np.ndarray, b: np.ndarray, p: np.ndarray) -> float:
    """Exact min distance from segment a-b to the points p (n, 3)."""
    u = b - a
    t = np.clip((p - a) @ u / (u @ u), 0.0, 1.0)
    return float(np.linalg.norm(p - a - t[:, None] * u, axis=1).min())


def _segment_box_dist(a: np.ndarray, b: np.ndarray, centres: np.ndarray, size: float) -> float:
    """Min distance from segment a-b to closed boxes: ternary search on the convex f(t)."""
    lo = np.zeros(len(centres))
    hi = np.ones(len(centres))

    def f(t):
        x = a + t[:, None] * (b - a)
        gap = np.maximum(np.abs(x - centres) - size / 2, 0.0)
        return np.linalg.norm(gap, axis=1)

    for _ in range(100):
        m1, m2 = lo + (hi - lo) / 3, hi - (hi - lo) / 3
        left = f(m1) > f(m2)
        lo = np.where(left, m1, lo)
        hi = np.where(left, hi, m2)
    return float(f((lo + hi) / 2).min())


def _free_pairs(world: World, blocked: OccupiedVoxelList, rng, n: int, reach: float):
    """Random pairs of free cells next to the blocked region, within ``reach`` metres."""
    lat = world.lattice
    ring = (blocked.indices[:, None, :] + lat.neighbors("full+2")[None]).reshape(-1, 3)
    ring = np.unique(ring, axis=0)
    ring = ring[world.is_free(ring)]
    i = rng.integers(0, len(ring), size=n)
    j = rng.integers(0, len(ring), size=n)
    c = lat.to_world(ring)
    keep = (np.linalg.norm(c[i] - c[j], axis=1) < reach) & (i != j)
    return c[i[keep]], c[j[keep]]


def _check_guarantee(lat, obstacle_dist, blocked, r, rng, n=2500):
    bounds = blocked.bounds() + np.array([[-3.0], [3.0]]) * lat.covering_radius
    world = World(lat, blocked.indices, bounds)
    a, b = _free_pairs(world, blocked, rng, n, reach=max(3 * r, 3.0))
    accepted = 0
    for p, q in zip(a, b, strict=True):
        if world.segment_free(p, q):
            accepted += 1
            assert obstacle_dist(p, q) >= r - 1e-9, (p, q)
    return accepted


@pytest.mark.parametrize("name", NAMED_LATTICES)
@pytest.mark.parametrize("diam", [0.5, 1.0, 3.0])
def test_inflation_guarantee_points(name, diam):
    lat = Lattice.named(name, 1.0)
    r = diam * lat.cell_volume ** (1 / 3)
    rng = np.random.default_rng([NAMED_LATTICES.index(name), int(diam * 10)])
    pts = np.concatenate([rng.uniform(0, 6, size=(12, 3)),
                          np.linspace([0, 0, 0], [4, 1, 3], 25)])  # scattered + a wall-ish line
    occ = OccupiedVoxelList.from_points(pts, lat)
    inflated = occ.inflate(r)
    exact = exact_inflation(pts, lat, r)
    assert np.isin(exact.keys, inflated.keys).all()
    assert inflated.contains(occ.indices).all()
    accepted = _check_guarantee(lat, lambda p, q: _segment_point_dist(p, q, pts), inflated, r,
                                rng, n=1500)
    assert accepted > 40
    # The exact set alone also keeps points at >= r (it is tight, not just sufficient).
    _check_guarantee(lat, lambda p, q: _segment_point_dist(p, q, pts), exact, r, rng, n=600)


@pytest.mark.parametrize("name", ["cubic", "fcc", "hex"])
def test_inflation_guarantee_boxes(name):
    lat = Lattice.named(name, 0.5)
    r = 0.6
    rng = np.random.default_rng(7)
    boxes = rng.uniform(0, 4, size=(6, 3))
    ob = Obstacles(points=np.zeros((0, 3)), boxes=boxes, box_size=0.9, bounds=None,
                   resolution=None, source="t")
    inflated = OccupiedVoxelList.from_obstacles(ob, lat).inflate(r)
    accepted = _check_guarantee(lat, lambda p, q: _segment_box_dist(p, q, boxes, 0.9),
                                inflated, r, rng, n=800)
    assert accepted > 50


def test_uninflated_map_fails_the_check():
    # The guarantee check has teeth: without inflation some accepted segment passes closer.
    lat = Lattice.named("fcc", 1.0)
    rng = np.random.default_rng(8)
    pts = rng.uniform(0, 6, size=(20, 3))
    occ = OccupiedVoxelList.from_points(pts, lat)
    with pytest.raises(AssertionError):
        _check_guarantee(lat, lambda p, q: _segment_point_dist(p, q, pts), occ, 1.0, rng)


@pytest.mark.parametrize("lat", LATTICES, ids=IDS)
def test_stencil_and_exact_inflation(lat):
    rng = np.random.default_rng(9)
    pts = rng.uniform(-4, 4, size=(60, lat.dim))
    occ = OccupiedVoxelList.from_points(pts, lat)
    for r in (0.3, 1.0, 2.5):
        st = V.inflation_stencil(lat, r)
        assert (st[0] == 0).all() and len(np.unique(st, axis=0)) == len(st)
        # Stencil contains every touching neighbour and is symmetric.
        assert {tuple(x) for x in lat.neighbors("full").tolist()} <= set(map(tuple, st.tolist()))
        assert set(map(tuple, st.tolist())) == set(map(tuple, (-st).tolist()))
        inflated = occ.inflate(r)
        # ... is every occupied cell plus every stencil offset (brute force).
        every = (occ.indices[:, None, :] + st[None]).reshape(-1, lat.dim)
        assert inflated == OccupiedVoxelList(lat, every)
        exact = exact_inflation(pts, lat, r)
        assert np.isin(exact.keys, inflated.keys).all()
        # Every exact cell is within r + covering radius of a point (centre distance).
        c = lat.to_world(exact.indices)
        near = np.linalg.norm(c[:, None] - pts[None], axis=2).min(axis=1)
        assert (near < r + lat.covering_radius + 1e-9).all()
        # Any cell whose centre is within r - rho of a point must be in the exact set.
        cand = (lat.quantize(pts)[:, None, :] + st[None]).reshape(-1, lat.dim)
        cc = lat.to_world(cand)
        must = np.linalg.norm(cc[:, None] - pts[None], axis=2).min(axis=1) < r
        assert exact.contains(cand[must]).all()
    assert occ.inflate(0.0) == occ


def _qp_cell_distance(lat: Lattice, y: np.ndarray) -> float:
    """Distance from y to the Voronoi cell of the origin by a generic QP solver."""
    rel = lat.relevant_vectors
    rhs = 0.5 * np.einsum("ij,ij->i", rel, rel)
    res = minimize(lambda x: (x - y) @ (x - y), np.zeros(lat.dim), jac=lambda x: 2 * (x - y),
                   constraints=[{"type": "ineq", "fun": lambda x: rhs - rel @ x,
                                 "jac": lambda x: -rel}],
                   method="SLSQP", options={"ftol": 1e-12, "maxiter": 500})
    # Status 8 (line search stalls at the optimum) is fine if the point is feasible.
    assert res.success or res.status == 8
    assert (rel @ res.x - rhs).max() < 1e-9
    return math.sqrt(max(res.fun, 0.0))


@pytest.mark.parametrize("lat", LATTICES, ids=IDS)
def test_exact_inflation_matches_qp(lat):
    rng = np.random.default_rng(12)
    p = rng.uniform(-1, 1, size=(1, lat.dim))
    r = 1.3
    got = exact_inflation(p, lat, r)
    base = lat.quantize(p)[0]
    offs = V.inflation_stencil(lat, 2 * r + 2 * lat.covering_radius)
    cells = base + offs[rng.permutation(len(offs))[:120]]
    checked = 0
    for cell, inside in zip(cells, got.contains(cells), strict=True):
        dist = _qp_cell_distance(lat, p[0] - lat.generator @ cell)
        if abs(dist - r) > 1e-6:
            assert inside == (dist < r), (cell, dist)
            checked += 1
    assert checked > 0.9 * len(cells)


def test_dense_and_key_backends_agree():
    lat = Lattice.named("bcc", 1.0)
    rng = np.random.default_rng(10)
    a = rng.uniform(0, 5, size=(40, 3))
    pts = np.concatenate([a, a + 2000.0])  # two far clusters: the dense box is huge
    occ = OccupiedVoxelList.from_points(pts, lat)
    sparse = occ.inflate(2.0, memory_budget=2**24)  # forces chunked key arithmetic
    dense = OccupiedVoxelList.from_points(a, lat).inflate(2.0)
    shifted = OccupiedVoxelList.from_points(a + 2000.0, lat).inflate(2.0)
    np.testing.assert_array_equal(sparse.keys, np.union1d(dense.keys, shifted.keys))


def test_over_budget_radius_raises():
    lat = Lattice.named("fcc", 1.0)
    occ = OccupiedVoxelList.from_points(np.zeros((1, 3)), lat)
    with pytest.raises(MapError, match=r"inflation for radius 5000 m needs ~.* GB, over the "
                                       r"memory budget"):
        occ.inflate(5000.0)
    with pytest.raises(MapError, match=r"\(--memory-budget / memory_budget\)"):
        occ.inflate(30.0, memory_budget=10**5)
    with pytest.raises(MapError, match="budget"):
        exact_inflation(np.zeros((1, 3)), lat, 30.0, memory_budget=10**5)


# -- real data -----------------------------------------------------------------------------------
@pytest.mark.skipif(not GEB079.exists(), reason="shared OctoMap data not present")
def test_geb079_cubic_cells():
    from planner.io import load_points

    centres = load_points(GEB079)  # occupied leaves filled with their 0.08 m voxel centres
    res = 0.08
    lat = Lattice.named("cubic", 0.08**3)
    # OctoMap voxel centres sit at (k + 1/2) res: exactly on cubic cell faces. Shifted by half
    # a voxel they are the lattice points themselves, one cell per voxel.
    occ = OccupiedVoxelList.from_points(centres - res / 2, lat)
    assert len(occ) == 185_673
    # As boxes, each 0.08 m voxel meets exactly the 2x2x2 cells around its centre.
    boxes = OccupiedVoxelList.from_obstacles(
        Obstacles(points=np.zeros((0, 3)), boxes=centres, box_size=res, bounds=None,
                  resolution=res, source="geb079.bt"), lat)
    shifted = occ.indices
    corners = np.array(list(itertools.product((0, 1), repeat=3)))
    assert boxes == OccupiedVoxelList(lat, (shifted[:, None, :] + corners[None]).reshape(-1, 3))
