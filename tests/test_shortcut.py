"""Shortcutting (``planner.search.shortcut``, what ``plan(..., shortcut=True)`` delivers):
every kept segment is in sight on the inflated world, the path is never longer than the
searched one, the rule is the documented gallop-then-bisect one (a Python replay of it,
lookups included), and a straight stretch of k cells costs O(k log k) cells walked."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from planner import search as S
from planner.lattice import NAMED_LATTICES, Lattice
from planner.world import World
from planner.world.build import build_world


def _length(world: World, cells: np.ndarray) -> float:
    return float(np.linalg.norm(np.diff(world.lattice.to_world(cells), axis=0), axis=1).sum())


def _sight(world: World, p: np.ndarray, q: np.ndarray) -> tuple[bool, int]:
    r = S.sight_many(world, p[None], q[None])
    return bool(r.free[0]), int(r.lookups[0])


def _replay(world: World, cells: np.ndarray) -> tuple[list[int], int]:
    """The rule, one sight test at a time: from each kept cell i, gallop to i + 2, i + 4,
    ... (capped at the last cell) until a test fails or the last cell is in sight, then
    bisect between the last cell in sight and the first out of sight; then drop each kept
    cell that the last one kept before it and the next one see past. Returns the kept
    indices and the cells looked up."""
    n, keep, looked, i = len(cells), [0], 0, 0
    while i < n - 1:
        lo, hi, d = i + 1, n, 2
        while lo < n - 1:
            j = min(i + d, n - 1)
            ok, c = _sight(world, cells[i], cells[j])
            looked += c
            if not ok:
                hi = j
                break
            lo, d = j, 2 * d
        while hi - lo > 1:
            m = (lo + hi) // 2
            ok, c = _sight(world, cells[i], cells[m])
            looked += c
            lo, hi = (m, hi) if ok else (lo, m)
        keep.append(lo)
        i = lo
    out = keep[:1]
    for b, c in itertools.pairwise(keep[1:]):
        ok, n_looked = _sight(world, cells[out[-1]], cells[c])
        looked += n_looked
        if not ok:
            out.append(b)
    return out + keep[-1:], looked


def _paths(world: World, n: int, seed: int):
    """Up to ``n`` A* paths between random free cells of ``world``."""
    rng = np.random.default_rng(seed)
    lo, hi = world.bounds
    for _ in range(4 * n):
        pts = world.lattice.quantize(rng.uniform(lo, hi, (2, 3)))
        if not world.is_free(pts).all():
            continue
        r = S.search(world, pts[0], pts[1])
        if r.found and len(r.cells) > 2:
            yield r
            n -= 1
            if n == 0:
                return


@pytest.fixture(scope="module", params=NAMED_LATTICES)
def office(request) -> World:
    return build_world("office", request.param)


def _check_delivered(world: World, cells: np.ndarray) -> tuple[np.ndarray, int]:
    """Shortcut ``cells`` and check the result against them: ends kept, a subsequence,
    every kept segment in sight by the searches' walk and free by the validity checker's
    generic walk, no longer. Returns the kept indices and the lookups counted."""
    before = world.cell_checks
    cut = S.shortcut(world, cells)
    looked = world.cell_checks - before
    idx = np.array([np.flatnonzero((cells == c).all(axis=1))[0] for c in cut])
    assert idx[0] == 0 and idx[-1] == len(cells) - 1 and (np.diff(idx) > 0).all()
    pts = world.lattice.to_world(cut)
    for (a, b), (p, q) in zip(itertools.pairwise(idx), itertools.pairwise(pts), strict=True):
        assert b == a + 1 or _sight(world, cells[a], cells[b])[0]
        assert world.segment_free(p, q)
    assert _length(world, cut) <= _length(world, cells) * (1 + 1e-12)
    return idx, looked


def test_the_delivered_path_is_free_and_no_longer_on_the_inflated_office(office):
    """The office map inflated by its robot radius, every lattice: what plan() delivers."""
    n = 0
    for r in _paths(office, 3, seed=1):
        idx, looked = _check_delivered(office, r.cells)
        assert len(idx) < len(r.cells) and looked > 0  # it shortcuts, its lookups counted
        n += 1
    assert n == 3


@pytest.mark.parametrize("name", NAMED_LATTICES)
def test_the_kernel_is_the_documented_rule_and_counts_every_lookup(name):
    """Kept cells and lookups equal the rule replayed one sight test at a time, on random
    clutter where sight along a path is often not monotone."""
    lat = Lattice.named(name, 1.0)
    rng = np.random.default_rng(7)
    bounds = np.array([[0.0, 0, 0], [12, 12, 6]])
    blocked = np.unique(lat.quantize(rng.uniform(bounds[0], bounds[1], (220, 3))), axis=0)
    world = World(lat, blocked, bounds)
    done = 0
    for r in _paths(world, 6, seed=2):
        idx, looked = _check_delivered(world, r.cells)
        want, want_looked = _replay(world, r.cells)
        assert idx.tolist() == want and looked == want_looked
        done += 1
    assert done >= 4


@pytest.mark.parametrize("name", NAMED_LATTICES)
def test_a_straight_stretch_costs_k_log_k_cells_walked(name):
    """A free straight path of k cells becomes its two ends after gallop sight tests of
    2, 4, ..., up to k cells: some 2k cells walked, where a scan testing every later cell
    in turn walks about k^2 / 2."""
    lat = Lattice.named(name, 1.0)
    world = World(lat, np.zeros((0, 3), np.int64), np.array([[-5.0] * 3, [205.0, 5, 5]]))
    s, g = lat.quantize(np.array([[0.0, 0, 0], [200.0, 0, 0]]))
    r = S.search(world, s, g)
    k = len(r.cells)
    before = world.cell_checks
    cut = S.shortcut(world, r.cells)
    looked = world.cell_checks - before
    assert np.array_equal(cut, r.cells[[0, -1]])
    per_cell = looked / _sight(world, r.cells[0], r.cells[-1])[1]  # walks of the whole line
    assert k > 100 and per_cell < 4


@pytest.mark.parametrize("name", NAMED_LATTICES)
def test_the_scratch_kept_between_calls_answers_as_a_fresh_one(name):
    """Calls on one thread reuse the sight scratch (fresh generation stamps each time): the
    same kept cells and lookups as the kernel on a new scratch, call after call, and on a
    second world of the lattice (its own walk: a scratch of its own)."""
    from planner.search._los import new_scratch, reach, shortcut_kernel

    lat = Lattice.named(name, 1.0)
    rng = np.random.default_rng(11)
    bounds = np.array([[0.0, 0, 0], [10, 10, 5]])
    for _ in range(2):
        blocked = np.unique(lat.quantize(rng.uniform(bounds[0], bounds[1], (150, 3))), axis=0)
        world = World(lat, blocked, bounds)
        chk = world.checker
        for r in _paths(world, 5, seed=int(rng.integers(1000))):
            before = world.cell_checks
            cut = S.shortcut(world, r.cells)
            fresh = new_scratch(reach(chk.walk.g, r.cells), chk.walk)
            keep, looked, _ = shortcut_kernel(chk.occupancy, chk.walk, r.cells, fresh, 0)
            assert np.array_equal(cut, r.cells[keep])
            assert world.cell_checks - before == looked


def test_shortcut_alternating_between_lattices_keeps_each_lattices_scratch():
    """Comparing lattices on one map alternates between worlds: each non-cubic walk keeps
    its own scratch (built once, reused while the store holds it), and the answers are
    those of a fresh scratch."""
    from planner.search._kept import KEEP, kept_scratch

    worlds = [World(Lattice.named(name, 1.0), np.zeros((0, 3), np.int64), [[0, 0, 0], [9, 9, 9]])
              for name in ("bcc", "fcc", "hex")]
    paths = [S.search(w, w.lattice.quantize([[1.0, 1, 1]])[0],
                      w.lattice.quantize([[8.0, 7, 6]])[0]).cells for w in worlds]
    first = [S.shortcut(w, c) for w, c in zip(worlds, paths, strict=True)]
    for _ in range(3):
        for w, c, kept in zip(worlds, paths, first, strict=True):
            np.testing.assert_array_equal(S.shortcut(w, c), kept)
    store: dict = {}
    walks = [w.checker.walk for w in worlds]
    built = [kept_scratch(store, wk, 5.0) for wk in walks]
    assert [kept_scratch(store, wk, 4.0) for wk in walks] == built  # kept, same objects
    assert kept_scratch(store, walks[0], 50.0) is not built[0]  # longer lines: rebuilt
    for k in range(KEEP):  # more walks than the store keeps: the oldest go
        kept_scratch(store, World(Lattice.named("bcc", 2.0 + k), np.zeros((0, 3), np.int64),
                                  [[0, 0, 0], [9, 9, 9]]).checker.walk, 1.0)
    assert len(store) == KEEP and all(id(wk) not in store for wk in walks)


def test_every_kind_of_path_array_gets_the_same_answer():
    """The compiled call skips numba's argument typing, so it must never see another type:
    a read-only path, a list, a Fortran-ordered or int32 copy, and a world that went through
    pickle (a worker's) all give the answer of the plain int64 array."""
    import pickle

    world = World(Lattice.named("bcc", 1.0), np.zeros((0, 3), np.int64), [[0, 0, 0], [9, 9, 9]])
    cells = S.search(world, world.lattice.quantize([[1.0, 1, 1]])[0],
                     world.lattice.quantize([[8.0, 7, 2]])[0]).cells
    want = S.shortcut(world, cells)
    assert len(want) < len(cells)
    frozen = cells.copy()
    frozen.flags.writeable = False
    for kind in (frozen, cells.tolist(), np.asfortranarray(cells), cells.astype(np.int32)):
        np.testing.assert_array_equal(S.shortcut(world, kind), want)
    np.testing.assert_array_equal(S.shortcut(pickle.loads(pickle.dumps(world)), cells), want)
