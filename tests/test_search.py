"""Search engine: world lookups, exact segment walk, movement rule, heuristic, A* family."""

from __future__ import annotations

import itertools
import pickle
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from planner import search as S
from planner.errors import PlanError
from planner.lattice import NAMED_LATTICES, Lattice
from planner.search.run import PROBE_AFTER
from planner.world import World

DATA = Path(__file__).resolve().parents[1] / ".." / "shared" / "data"
WARFRAME = DATA / "warframe"


def _box_world(name="cubic", n=8, blocked=(), vol=1.0, **kw):
    lat = Lattice.named(name, vol)
    b = np.array(blocked, dtype=np.int64).reshape(-1, 3)
    return World(lat, b, np.array([[0.0, 0, 0], [n, n, n]]) * vol ** (1 / 3), **kw)


# -- world ---------------------------------------------------------------------------------
@pytest.mark.parametrize("budget", [None, 0])
def test_world_lookups_dense_and_hash(budget):
    kw = {} if budget is None else {"dense_budget": budget}
    w = _box_world(blocked=[(1, 1, 1), (2, 3, 4)], n=5, **kw)
    assert w.storage == ("hash" if budget == 0 else "dense")
    q = np.array([[1, 1, 1], [2, 3, 4], [0, 0, 0], [5, 5, 5], [6, 0, 0], [-1, 2, 2]])
    assert w.is_free(q).tolist() == [False, False, True, True, False, False]
    assert w.cell_checks == 6
    assert w.points_free(np.array([[1.2, 0.9, 1.1], [0.1, 0.2, 0.3]])).tolist() == [False, True]
    assert w.cell_checks == 8
    assert w.in_bounds(q).tolist() == [True, True, True, True, False, False]


def test_world_pickles_without_numba_state():
    w = _box_world(blocked=[(1, 1, 1)])
    w.is_free(np.zeros((1, 3), np.int64))
    w2 = pickle.loads(pickle.dumps(w))
    assert w2._checker is None
    assert w2.is_free(np.array([[1, 1, 1], [2, 2, 2]])).tolist() == [False, True]
    assert w2.lattice == w.lattice and np.array_equal(w2.bounds, w.bounds)


def test_nearest_free_and_endpoint_errors():
    w = _box_world(blocked=[(2, 2, 2)])
    with pytest.raises(PlanError, match=r"start cell \[2, 2, 2\] \(centre \(2\.000, 2\.000, "
                                        r"2\.000\)\) is inside an obstacle.*nearest free"):
        S.search(w, [2, 2, 2], [0, 0, 0])
    with pytest.raises(PlanError, match=r"goal cell .*outside the map bounds"):
        S.search(w, [0, 0, 0], [20, 0, 0])
    near = w.nearest_free(np.array([2, 2, 2]))
    assert np.abs(near - 2).sum() == 1


# -- exact segment walk --------------------------------------------------------------------
def _slab_touches(a, b, c, tol=1e-9):
    """Cube [c - 1/2, c + 1/2] meets segment a-b (slab clipping, closed)."""
    lo, hi = 0.0, 1.0
    d = b - a
    for k in range(3):
        if abs(d[k]) < 1e-15:
            if abs(a[k] - c[k]) > 0.5 + tol:
                return False
            continue
        t1 = (c[k] - 0.5 - tol - a[k]) / d[k]
        t2 = (c[k] + 0.5 + tol - a[k]) / d[k]
        lo, hi = max(lo, min(t1, t2)), min(hi, max(t1, t2))
    return lo <= hi


def test_segment_cells_cubic_matches_slab_clipping():
    rng = np.random.default_rng(0)
    w = _box_world(n=30)
    for _ in range(60):
        a, b = rng.uniform(2, 20, (2, 3))
        if rng.random() < 0.3:  # exact lattice geometry: centres and corners
            a, b = np.round(a), np.round(b) + 0.5 * rng.integers(0, 2, 3)
        got = {tuple(c) for c in w.segment_cells(a, b).tolist()}
        lo = np.floor(np.minimum(a, b)) - 1
        hi = np.ceil(np.maximum(a, b)) + 1
        axes = [range(int(x), int(y) + 1) for x, y in zip(lo, hi, strict=True)]
        want = {
            c for c in itertools.product(*axes) if _slab_touches(a, b, np.array(c, float))
        }
        assert got == want


@pytest.mark.parametrize("name", NAMED_LATTICES)
def test_segment_cells_contain_sampled_cells(name):
    lat = Lattice.named(name, 0.5)
    w = World(lat, np.zeros((0, 3), np.int64), np.array([[-9.0] * 3, [9.0] * 3]))
    rng = np.random.default_rng(1)
    rel = lat.relevant_vectors
    for _ in range(20):
        a, b = rng.uniform(-4, 4, (2, 3))
        cells = w.segment_cells(a, b)
        got = {tuple(c) for c in cells.tolist()}
        pts = a + np.linspace(0, 1, 2000)[:, None] * (b - a)
        assert {tuple(c) for c in lat.quantize(pts).tolist()} <= got
        # Every reported cell really meets the segment: the closest segment point to the
        # cell lies in the (slightly widened) cell.
        cen = lat.to_world(cells)
        for c in cen:
            x = pts - c
            slack = (x @ rel.T - 0.5 * (rel * rel).sum(1)).max(axis=1).min()
            assert slack <= 1e-2 * lat.packing_radius


def _touched_brute(lat, a, b, s):
    """Every cell in an index box around the segment whose closed Voronoi cell (widened by
    the walk's tolerance) meets it: the walk's clip test, evaluated for each candidate."""
    from planner.occupancy.walk import SEG_TOL as _SEG_TOL

    g, rel = lat.generator, lat.relevant_vectors
    rhs = 0.5 * (rel * rel).sum(1)
    wv = rel @ g
    c0 = g @ s
    lim0 = rhs * (1.0 + _SEG_TOL) - (a - c0) @ rel.T
    dq = (b - a) @ rel.T
    ginv = np.linalg.inv(g)
    ends = np.stack([ginv @ a, ginv @ b])
    lo = np.floor(ends.min(0)).astype(int) - 3
    hi = np.ceil(ends.max(0)).astype(int) + 3
    u = np.stack(np.meshgrid(*[np.arange(x, y + 1) for x, y in zip(lo, hi, strict=True)],
                             indexing="ij"), -1).reshape(-1, 3)
    lim = lim0 + (u - s) @ wv.T
    with np.errstate(divide="ignore"):
        t = lim * np.where(dq != 0, 1.0 / np.where(dq != 0, dq, 1), 0.0)
    up = np.where(dq > 0, t, np.inf).min(1).clip(max=1.0)
    dn = np.where(dq < 0, t, -np.inf).max(1).clip(min=0.0)
    par = np.where(dq == 0, lim < 0, False).any(1)
    return {tuple(c) for c in u[(dn <= up) & ~par].tolist()}


@pytest.mark.parametrize("name", NAMED_LATTICES)
def test_segment_walk_matches_brute_force(name):
    """The walk (forward offsets only) finds exactly the cells a brute-force clip over a
    box finds: random segments, centre-to-centre segments (boundary ties) and axis ones."""
    lat = Lattice.named(name, 0.3)
    w = World(lat, np.zeros((0, 3), np.int64), np.array([[-9.0] * 3, [9.0] * 3]))
    rng = np.random.default_rng(5)
    moves = lat.neighbors("full+1")
    for k in range(150):
        if k % 3 == 0:
            a, b = rng.uniform(-2, 2, (2, 3))
        else:  # cell centre to cell centre: the lattice's own ties
            p = rng.integers(-3, 4, 3)
            q = p + (moves[rng.integers(len(moves))] * rng.integers(1, 4) if k % 3 == 1
                     else rng.integers(-6, 7, 3))
            a, b = lat.to_world(np.stack([p, q]))
        s = lat.quantize(a[None])[0]
        got = {tuple(c) for c in w.segment_cells(a, b).tolist()}
        assert got == _touched_brute(lat, a, b, s), (name, a, b)


def test_cubic_sight_blocks_exactly_the_walked_cells():
    """The cubic line of sight (nested clipping) is blocked by a cell iff the exact walk
    touches it: each cell on and around random centre-to-centre segments is blocked in
    turn (lattice ties included: axis, face- and space-diagonal segments)."""
    from planner.search._los import cubic_sight

    w = _box_world(n=24)
    occ = w.occupancy
    rng = np.random.default_rng(11)
    ring = np.array([d for d in itertools.product((-1, 0, 1), repeat=3)])
    for k in range(60):
        p = rng.integers(6, 18, 3)
        q = p + (rng.integers(-5, 6, 3) if k % 2 else rng.integers(-1, 2, 3) * rng.integers(1, 6))
        walked = {tuple(c) for c in w.segment_cells(*w.lattice.to_world(np.stack([p, q])))}
        near = {tuple(np.add(c, d)) for c in walked for d in ring}
        assert cubic_sight(occ, p, q)[0]
        for c in near:
            changed = w.set_cells([c], blocked=True)
            assert cubic_sight(occ, p, q)[0] == (c not in walked), (p, q, c)
            w.set_cells(changed, blocked=False)


def test_cubic_integer_walk_matches_the_clipping():
    """The integer-stepping walk on the cubic lattice accepts and rejects exactly as the
    nested clipping, with one cell blocked in turn around random and tie-heavy segments
    (axis, face- and space-diagonal, knight-like; some leave the grid's box), in dense
    and hash storage."""
    from planner.search._los import cubic_sight, cubic_walk

    rng = np.random.default_rng(5)
    ring = np.array([d for d in itertools.product((-1, 0, 1), repeat=3)])
    lat, bounds = Lattice.named("cubic", 1.0), [[0, 0, 0], [16, 16, 16]]
    for k in range(36):
        p = rng.integers(-1, 18, 3)
        d = (rng.integers(-1, 2, 3) * rng.integers(1, 7) if k % 3 == 0
             else np.array([2, 1, 0])[rng.permutation(3)] * rng.integers(-3, 4)
             if k % 3 == 1 else rng.integers(-7, 8, 3))
        q = p + d
        near = {tuple(np.rint(p + t * d).astype(int) + r) for t in np.linspace(0, 1, 15)
                for r in ring}
        for c in [None, *sorted(near)]:
            blocked = np.array([c] if c else np.zeros((0, 3)), np.int64).reshape(-1, 3)
            for budget in ({}, {"dense_budget": 0}) if k % 4 == 0 else ({},):
                occ = World(lat, blocked, bounds, **budget).occupancy
                ref = cubic_sight(occ, p, q)[0]
                assert cubic_walk(occ, *p, *q)[0] == ref, (p, q, c, budget)


def test_segment_free_counts_lookups():
    w = _box_world(blocked=[(3, 3, 3)], n=10)
    assert not w.segment_free([1, 1, 1], [5, 5, 5])
    n = w.cell_checks
    assert 0 < n < len(w.segment_cells([1, 1, 1], [5, 5, 5]))  # stopped early
    assert w.segment_free([1, 1, 1], [1, 1, 6])
    assert w.cell_checks == n + 6


# -- movement rule and heuristic -------------------------------------------------------------
def test_cubic26_safe_rule_is_bounding_box():
    lat = Lattice.named("cubic", 1.0)
    moves, _, _, _, _, per_move = S.move_stencils(lat, "full", False)
    for d, cells in zip(moves, per_move, strict=True):
        box = {c for c in itertools.product(*[sorted({0, int(x)}) for x in d]) if any(c)}
        assert {tuple(c) for c in cells.tolist()} == box
    _, _, union, _, _, per_cc = S.move_stencils(lat, "full", True)
    assert all(len(c) == 1 for c in per_cc) and len(union) == 26


def test_heuristic_cubic26_is_octile():
    lat = Lattice.named("cubic", 1.0)
    hm = S.move_heuristic(lat, "full")
    rng = np.random.default_rng(2)
    d = rng.integers(-50, 50, (500, 3))
    h = (d @ hm.T).max(axis=1)
    a = np.sort(np.abs(d), axis=1)
    octile = (np.sqrt(3) - np.sqrt(2)) * a[:, 0] + (np.sqrt(2) - 1) * a[:, 1] + a[:, 2]
    np.testing.assert_allclose(h, octile, rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("name", NAMED_LATTICES)
@pytest.mark.parametrize("nb", ["face", "full", "full+1"])
def test_heuristic_admissible_and_tight_on_moves(name, nb):
    lat = Lattice.named(name, 2.0)
    hm = S.move_heuristic(lat, nb)
    moves = lat.neighbors(nb)
    cost = np.linalg.norm(moves @ lat.generator.T, axis=1)
    h = (moves @ hm.T).max(axis=1)
    assert np.all(h <= cost * (1 + 1e-12))  # consistency: h(s) <= c(s) for every move
    # The gauge is tight on the hull's vertices: at least the shortest moves are exact.
    assert np.isclose(h[0], cost[0])


@pytest.mark.parametrize("name", NAMED_LATTICES)
def test_path_excess_is_the_longest_path_over_the_straight_line(name):
    """``path_excess``: no direction's free-space path is longer than the straight line by
    more (random directions come close), and the shortest moves' directions are exact."""
    from planner.search.moves import path_excess

    lat = Lattice.named(name, 2.0)
    excess = path_excess(lat)
    hm = S.move_heuristic(lat, "full")
    rng = np.random.default_rng(3)
    x = rng.normal(size=(20_000, 3))  # world directions, in index coordinates below
    ratio = (x @ np.linalg.inv(lat.generator).T @ hm.T).max(axis=1) / np.linalg.norm(x, axis=1)
    assert ratio.max() <= excess * (1 + 1e-12) and ratio.max() > excess - 0.01
    if name == "cubic":
        assert np.isclose(excess, np.sqrt(1 + (np.sqrt(2) - 1) ** 2
                                          + (np.sqrt(3) - np.sqrt(2)) ** 2))


@pytest.mark.parametrize("name", NAMED_LATTICES)
def test_compiled_and_numpy_heuristics_agree(name):
    """Every engine's heuristic (gauge / octile for A* and D* Lite, Euclidean for the
    any-angle methods, zero for Dijkstra) gives the same value compiled and in numpy."""
    from planner.search import heuristic as H
    from planner.search.moves import move_set

    lat = Lattice.named(name, 2.0)
    g = np.ascontiguousarray(lat.generator, dtype=np.float64)
    d = np.random.default_rng(5).integers(-40, 40, (200, 3))
    for hkind in (H.H_ZERO, H.H_GAUGE, H.H_EUCLID):
        ms = move_set(lat, "full", False, hkind)
        want = H.estimate_np(ms, g, d)
        got = [H.estimate(ms, g, int(a), int(b), int(c)) for a, b, c in d]
        np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-12)
        if hkind == H.H_GAUGE:  # the closed form on cubic-26 is the facet maximum too
            np.testing.assert_allclose(want, H.gauge_np(ms.hmat, d), rtol=1e-12, atol=1e-12)
    assert np.all(H.estimate_np(move_set(lat, "full", False, H.H_ZERO), g, d) == 0.0)



@pytest.mark.parametrize("name", NAMED_LATTICES)
@pytest.mark.parametrize("nb", ["face", "full", "full+1"])
def test_half_facets_give_the_gauge_to_the_bit(name, nb):
    """The search loop's gauge, max |f . e| over one facet of each antipodal pair
    (``DenseTables.hhalf``), is the full facet maximum bit for bit, so A* orders its
    nodes exactly as with every facet."""
    from planner.search import heuristic as H
    from planner.search.moves import move_set

    hmat = move_set(Lattice.named(name, 2.0), nb, False, H.H_GAUGE).hmat
    half, habs = H.half_facets(hmat)
    assert habs and 2 * len(half) == len(hmat)  # lattice move sets are symmetric
    d = np.random.default_rng(7).integers(-60, 60, (500, 3)).astype(np.float64)
    got = [H.half_gauge(half, habs, *e) for e in d]
    want = [H.gauge(hmat, *e) for e in d]
    assert np.array_equal(got, want)
    lone = np.array([[1.0, 2.0, 3.0], [-1.0, -2.0, -3.0], [0.0, 0.0, 1.0]])
    back, habs = H.half_facets(lone)  # a facet without its negation: every facet is kept
    assert not habs and np.array_equal(back, lone)
    one_sided = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    back, habs = H.half_facets(one_sided)
    e = np.array([-1.0, -2.0, 4.0])  # behind every facet: the gauge's floor at 0
    assert not habs and H.half_gauge(back, habs, *e) == H.gauge(one_sided, *e) == 0.0


# -- search ------------------------------------------------------------------------------
def _random_world(name, seed, n=5, frac=0.25):
    rng = np.random.default_rng(seed)
    lat = Lattice.named(name, 1.0)
    bounds = np.array([[0.0, 0, 0], [n, n, n * 0.7]])
    cells = np.unique(lat.quantize(rng.uniform(bounds[0], bounds[1], (4000, 3))), axis=0)
    w = World(lat, np.zeros((0, 3), np.int64), bounds)
    cells = cells[w.in_bounds(cells)]
    blocked = cells[rng.random(len(cells)) < frac]
    world = World(lat, blocked, bounds)
    free = cells[world.is_free(cells)]
    s, g = free[rng.choice(len(free), 2, replace=False)]
    return world, s, g


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    name=st.sampled_from(NAMED_LATTICES),
    seed=st.integers(0, 10_000),
    nb=st.sampled_from(["face", "full"]),
    cc=st.booleans(),
)
def test_numba_matches_networkx(name, seed, nb, cc):
    world, s, g = _random_world(name, seed)
    a = S.search(world, s, g, neighbors=nb, corner_cutting=cc)
    b = S.search(world, s, g, neighbors=nb, corner_cutting=cc, backend="networkx")
    d = S.search(world, s, g, neighbors=nb, corner_cutting=cc, method="dijkstra")
    assert a.found == b.found == d.found
    if a.found:
        assert a.cost == pytest.approx(b.cost, rel=1e-9)
        assert d.cost == pytest.approx(b.cost, rel=1e-9)
        _check_lattice_path(world, a, nb, cc)
    else:
        assert "unreachable" in a.reason


def _check_lattice_path(world, res, nb, cc):
    lat = world.lattice
    moves, mcost, _, _, _, per_move = S.move_stencils(lat, nb, cc)
    index = {tuple(m): i for i, m in enumerate(moves.tolist())}
    total = 0.0
    for u, v in itertools.pairwise(res.cells):
        m = index[tuple((v - u).tolist())]
        assert world.is_free(u + per_move[m]).all()
        total += mcost[m]
    assert total == pytest.approx(res.cost, rel=1e-9)


@pytest.mark.parametrize("name", NAMED_LATTICES)
@pytest.mark.parametrize("method", ["theta", "lazy-theta"])
def test_any_angle_paths_valid_and_short(name, method):
    for seed in range(6):
        world, s, g = _random_world(name, seed, n=6, frac=0.15)
        a = S.search(world, s, g)
        r = S.search(world, s, g, method=method)
        assert r.found == a.found
        if not a.found:
            continue
        pts = world.lattice.to_world(r.cells)
        seg = np.linalg.norm(np.diff(pts, axis=0), axis=1).sum()
        assert r.cost == pytest.approx(seg, rel=1e-9)
        assert r.cost <= a.cost * (1 + 1e-9)
        assert r.cost >= np.linalg.norm(pts[-1] - pts[0]) * (1 - 1e-9)
        for p, q in itertools.pairwise(pts):
            assert world.segment_free(p, q)
        sc = S.shortcut(world, a.cells)
        assert np.array_equal(sc[0], a.cells[0]) and np.array_equal(sc[-1], a.cells[-1])
        sp = world.lattice.to_world(sc)
        for p, q in itertools.pairwise(sp):
            assert world.segment_free(p, q)
        assert np.linalg.norm(np.diff(sp, axis=0), axis=1).sum() <= a.cost * (1 + 1e-9)


def test_no_path_and_trivial_path():
    blocked = [(x, y, 4) for x in range(9) for y in range(9)]
    w = _box_world(blocked=blocked, n=8)
    r = S.search(w, [1, 1, 1], [1, 1, 7])
    assert not r.found and r.reason.startswith("goal unreachable") and r.cells.shape == (0, 3)
    r = S.search(w, [1, 1, 1], [1, 1, 1])
    assert r.found and r.cost == 0 and r.cells.tolist() == [[1, 1, 1]]
    r = S.search(w, [1, 1, 1], [1, 1, 7], max_nodes=50)
    assert not r.found and "node limit" in r.reason


def test_searches_do_not_keep_a_freed_world_alive():
    """The engine keeps each thread's last world bound for the next search on it; freeing
    the world frees its arrays (and the slot array pooled for them) all the same."""
    import gc
    import weakref

    w = _box_world(blocked=[(2, 2, 2)], n=8)
    for method in ("astar", "lazy-theta"):
        assert S.search(w, [0, 0, 0], [7, 7, 7], method=method).found
    other = _box_world(blocked=[(1, 1, 1)], n=6)
    assert S.search(other, [0, 0, 0], [3, 3, 3]).found  # w's bound kept, not the last
    grid = weakref.ref(w.checker.occupancy.grid)
    del w
    gc.collect()
    assert grid() is None
    assert S.search(other, [0, 0, 0], [3, 3, 3]).found  # the engine still searches


def test_hash_storage_gives_same_results():
    world, s, g = _random_world("fcc", 7, n=6)
    w2 = World(world.lattice, world.blocked, world.bounds, dense_budget=0)
    a, b = S.search(world, s, g), S.search(w2, s, g)
    assert w2.storage == "hash" and a.found == b.found
    assert a.cost == pytest.approx(b.cost) and a.cell_checks == b.cell_checks


@pytest.mark.parametrize("name", NAMED_LATTICES)
def test_dense_and_paged_node_maps_agree(name, monkeypatch):
    """The dense cell -> node array (reused and cleared between searches; lattice methods
    then run the dense-grid loop) and the paged map (the general loop) give the same
    searches, repeated searches on one world included."""
    from planner.search.astar import driver as _driver

    world, s, g = _random_world(name, 3, n=6)
    methods = ("astar", "dijkstra", "lazy-theta")
    dense = [[S.search(world, s, g, method=m) for m in methods] for _ in range(2)]
    monkeypatch.setattr(_driver, "DENSE_SLOT_BUDGET", 0)
    # the same cells in another world: a grid's dense array, once taken, stays its own
    other = World(world.lattice, world.blocked, world.bounds)
    paged = [S.search(other, s, g, method=m) for m in methods]
    for a, b, c in zip(dense[0], dense[1], paged, strict=True):
        assert c.peak_bytes < a.peak_bytes  # no dense cell -> node array: the paged map
        assert a.cost == b.cost == c.cost
        assert a.expansions == b.expansions == c.expansions
        assert a.generated == b.generated == c.generated
        assert a.cell_checks == b.cell_checks == c.cell_checks
        assert np.array_equal(a.cells, c.cells)


def test_search_time_never_includes_compilation():
    w = _box_world(n=4)
    S.search(w, [0, 0, 0], [4, 4, 4])
    assert S.warm_up() == 0.0  # done once per process, before the first search's clock
    assert S.search(w, [0, 0, 0], [4, 4, 3]).compile_seconds == 0.0


def test_search_counts_checks_in_world():
    world, s, g = _random_world("bcc", 3)
    before = world.cell_checks
    r = S.search(world, s, g)
    assert world.cell_checks - before == r.cell_checks
    assert r.expansions > 0 and r.generated >= r.expansions and r.peak_bytes > 0


# -- MovingAI Warframe ----------------------------------------------------------------------
def _load_warframe(name):
    path = WARFRAME / f"{name}.3dmap"
    if not path.exists():
        pytest.skip("Warframe data not available")
    dims = np.loadtxt(path, max_rows=1, usecols=(1, 2, 3), dtype=np.int64)
    blocked = np.loadtxt(path, skiprows=1, dtype=np.int64, ndmin=2)
    scen = np.loadtxt(f"{path}.3dscen", skiprows=2, ndmin=2)
    world = World(Lattice.named("cubic", 1.0), blocked, np.array([[0, 0, 0], dims - 1.0]))
    return world, scen


@pytest.mark.parametrize("name", ["Simple", "Complex", "DA1"])
def test_warframe_optimal_costs(name):
    world, scen = _load_warframe(name)
    for q in scen[:: len(scen) // 30][:30]:
        r = S.search(world, q[:3].astype(np.int64), q[3:6].astype(np.int64))
        assert r.found
        assert r.cost == pytest.approx(q[6], rel=1e-6)


# -- budget, one compilation -----------------------------------------------------------------
def _sealed_goal_world(n=60, wall=6):
    """A big empty cubic world whose goal cell (n-8, n-8, n-8) is walled in by a cube
    ``wall`` cells out (6: a pocket of 11^3 cells, more than the goal probe explores)."""
    c = np.array([n - 8] * 3)
    shell = np.array([c + d for d in itertools.product(range(-wall, wall + 1), repeat=3)
                      if max(map(abs, d)) == wall])
    return _box_world(n=n, blocked=shell), np.array([1, 1, 1]), c


def test_a_goal_sealed_in_a_small_pocket_is_unreachable_after_a_short_search():
    w, s, g = _sealed_goal_world(wall=2)  # 27 free cells around the goal
    r = S.search(w, s, g)
    # the start's component is 200,000 cells: the search stops long before exhausting it
    assert r.status == "unreachable" and 0 < r.expansions <= PROBE_AFTER
    assert r.reason == "goal unreachable: its free space is 27 cells, closed off from the start"


def test_sealed_goal_ends_with_budget_status():
    w, s, g = _sealed_goal_world()
    r = S.search(w, s, g, max_expansions=5000)
    assert not r.found and r.status == "budget" and r.expansions == 5000
    assert r.reason == f"search budget exhausted after 5000 expansions ({r.peak_bytes} bytes)"
    r = S.search(w, s, g, memory_budget=200_000)
    assert r.status == "budget" and r.generated <= 200_000 // 100
    with pytest.raises(PlanError, match="max_expansions must be a positive integer"):
        S.search(w, s, g, max_expansions=-1)


def test_unreachable_and_found_statuses():
    blocked = [(x, y, 4) for x in range(9) for y in range(9)]
    w = _box_world(blocked=blocked, n=8)
    assert S.search(w, [1, 1, 1], [1, 1, 7]).status == "unreachable"
    assert S.search(w, [1, 1, 1], [7, 7, 1]).status == "found"
    assert S.search(w, [1, 1, 1], [1, 1, 7], max_nodes=50).status == "budget"


def test_every_lattice_shares_one_compiled_kernel():
    """Every array the kernels get has one numba type on every lattice (MCC's generator is
    not C-contiguous and once forced a second compilation)."""
    from planner.occupancy.grid import free_many
    from planner.search import _los
    from planner.search.astar import bound

    for name in NAMED_LATTICES:
        for budget in ({}, {"dense_budget": 0}):
            world, s, g = _random_world(name, 1)
            world = World(world.lattice, world.blocked, world.bounds, **budget)
            for method in ("astar", "dijkstra", "lazy-theta", "theta"):
                r = S.search(world, s, g, method=method)
            S.shortcut(world, r.cells)
            world.segment_free(world.lattice.to_world(s[None])[0], [0.5, 0.5, 0.5])
    # (segment_walk is left out: numba adds a specialisation per literal ``check`` flag
    # when other kernels call it, cheap and independent of the lattice.)
    for kernel in (bound.search_bound, bound.new_bound, _los.shortcut_kernel, free_many):
        assert len(kernel.signatures) == 1, (kernel, kernel.signatures)


# -- many queries at once ------------------------------------------------------------------
@pytest.mark.parametrize("method", ["astar", "lazy-theta"])
@pytest.mark.parametrize("name", ["cubic", "fcc"])
def test_search_many_gives_each_query_the_result_of_search(name, method):
    rng = np.random.default_rng(7)
    blocked = rng.integers(0, 12, size=(250, 3))
    w = _box_world(name, n=12, blocked=blocked)
    free = np.array([c for c in itertools.product(range(12), repeat=3)
                     if w.is_free(np.array(c))])
    pick = rng.choice(len(free), size=(24, 2))
    starts, goals = free[pick[:, 0]], free[pick[:, 1]]
    one = [S.search(w, s, g, method=method) for s, g in zip(starts, goals, strict=True)]
    before = w.cell_checks
    many = S.search_many(w, starts, goals, method=method, workers=2)
    assert w.cell_checks - before == sum(r.cell_checks for r in one)  # as search counts
    for a, b in zip(one, many, strict=True):
        assert (a.status, a.expansions, a.cell_checks) == (b.status, b.expansions, b.cell_checks)
        assert a.cost == b.cost and np.array_equal(a.cells, b.cells)


def test_search_many_refuses_a_blocked_endpoint_before_searching():
    w = _box_world(blocked=[(3, 3, 3)])
    before = w.cell_checks
    with pytest.raises(PlanError, match=r"query 1: goal cell \[3, 3, 3\]"):
        S.search_many(w, [[0, 0, 0], [1, 1, 1]], [[5, 5, 5], [3, 3, 3]])
    assert w.cell_checks - before <= 4  # endpoint checks only: no search ran
    with pytest.raises(PlanError, match="same shape"):
        S.search_many(w, [[0, 0, 0]], [[5, 5, 5], [1, 1, 1]])


def test_a_query_loop_gets_what_each_search_gets_alone():
    """A search with the arguments of the thread's last one repeats them without comparing
    them again; whatever ran before (another world or method, a search long enough to grow
    the arrays, cells blocked in place), each query gets the result it gets on its own."""
    rng = np.random.default_rng(11)
    small = _box_world(n=12, blocked=rng.integers(0, 12, size=(250, 3)))
    big = _box_world(n=40, blocked=rng.integers(0, 40, size=(3000, 3)))
    loop = []
    for i in range(40):
        w = big if i % 7 in (3, 4) else small  # two long searches in a row, then short ones
        n = 40 if w is big else 12
        free = np.argwhere(np.ones((n, n, n), bool))
        free = free[w.is_free(free)]
        s, g = free[rng.choice(len(free), 2, replace=False)]
        method = "dijkstra" if i % 5 == 4 else "astar"
        loop.append((w, s, g, method, S.search(w, s, g, method=method)))
        if i == 30:  # cells blocked in place: the same world, structs and arrays
            hit = w.set_cells(loop[-1][4].cells[1:-1], True)
            assert len(hit)
            loop.append((w, s, g, method, S.search(w, s, g, method=method)))
            assert loop[-1][4].cost > loop[-2][4].cost
    for w, s, g, method, r in loop[-10:]:
        alone = S.search_many(w, s[None], g[None], method=method, workers=1)[0]
        assert (r.status, r.expansions, r.generated, r.cell_checks) == (
            alone.status, alone.expansions, alone.generated, alone.cell_checks)
        assert r.cost == alone.cost and np.array_equal(r.cells, alone.cells)
    assert any(r.generated > 4096 for *_, r in loop)  # grown past the kept arrays


def test_found_result_is_the_keyword_built_result():
    """search()'s fast path builds its result with found_result (keyword-only, filling the
    slots itself): every field as SearchResult built by keyword, so a field added to the
    class and not to found_result fails here (an unset slot raises on reading)."""
    import dataclasses

    from planner.search.result import SearchResult, found_result

    cells = np.array([[0, 0, 0], [1, 0, 0]], np.int64)
    kw = dict(cells=cells, cost=1.5, cell_checks=7, expansions=2, generated=26,
              seconds=3e-6, peak_bytes=4096, guarantee=False, compile_seconds=0.25)
    got, want = found_result(**kw), SearchResult(found=True, **kw)
    assert type(got) is SearchResult
    for f in dataclasses.fields(SearchResult):
        assert getattr(got, f.name) is getattr(want, f.name) or \
            getattr(got, f.name) == getattr(want, f.name), f.name
    with pytest.raises(TypeError):
        SearchResult(True, cells, 1.5, 7, 2, 26, 3e-6, 4096)  # keyword only
