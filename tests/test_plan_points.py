"""plan() on a prebuilt world looks its endpoints up in the search's own kernel call
(planner.search.run.search_points): the same results, lookups and errors as the endpoint
checks followed by search()."""

from __future__ import annotations

import itertools
import pickle

import numpy as np
import pytest

from planner import search as S
from planner.errors import PlanError
from planner.lattice import Lattice
from planner.path import path_length
from planner.planning import joined, plan
from planner.search.run import PROBE_AFTER, search_points
from planner.world import World


def _world(name="cubic", n=12, blocked=(), vol=1.0, **kw):
    lat = Lattice.named(name, vol)
    b = np.array(blocked, dtype=np.int64).reshape(-1, 3)
    return World(lat, b, np.array([[0.0, 0, 0], [n, n, n]]) * vol ** (1 / 3), **kw)


def _reference(w, a, b, **kw):
    """What plan's search is without the one-call path: endpoints, then search."""
    _, sc, _, gc = w.endpoints(a, b)
    return S.search(w, sc, gc, **kw)


def _same(r, ref):
    assert r.status == ref.status and r.cost == ref.cost and r.reason == ref.reason
    assert (r.expansions, r.generated, r.cell_checks, r.peak_bytes) == (
        ref.expansions, ref.generated, ref.cell_checks, ref.peak_bytes)
    assert np.array_equal(r.cells, ref.cells) and r.guarantee == ref.guarantee


@pytest.mark.parametrize("name", ["cubic", "bcc", "fcc", "hex"])
def test_one_call_search_matches_endpoints_then_search(name):
    rng = np.random.default_rng(3)
    w = _world(name, n=10, blocked=rng.integers(0, 10, (120, 3)), vol=0.5)
    S.warm_up()
    lo, hi = w.bounds
    done = 0
    for _ in range(60):
        a, b = rng.uniform(lo, hi), rng.uniform(lo, hi)
        try:
            ref = _reference(w, a, b)
        except PlanError:
            continue
        before = w.cell_checks
        r = search_points(w, w.end_coords(a, b))
        if r is None:  # the first search of its kind on this thread
            r = search_points(w, w.end_coords(a, b))
        assert r is not None
        assert w.cell_checks - before == r.cell_checks + 2  # and the endpoints' lookups
        _same(r, ref)
        done += 1
    assert done > 10


def test_plan_reports_what_it_reported_through_endpoints_and_search():
    w = _world(n=12, blocked=[(5, y, z) for y in range(12) for z in range(11)])
    a, b = np.array([1.0, 1.0, 1.0]), np.array([10.0, 9.0, 2.0])
    for _ in range(3):  # the first call sets up the one-call path of the next
        before = w.cell_checks
        p = plan(w, a, b)
        # the search's lookups, the two ends' and those joining the ends to the path
        assert w.cell_checks - before == p.cell_checks + 2 + p.extra["join_checks"]
        ref = _reference(w, a, b)
        assert p.found and p.length == plan(w, a.tolist(), b.tolist()).length
        assert p.cell_checks == ref.cell_checks and p.expansions == ref.expansions
        assert np.array_equal(p.cells, ref.cells)
        want = joined(w, np.concatenate([a[None], w.lattice.to_world(ref.cells), b[None]]))
        assert np.array_equal(p.path, want) and p.extra["join_checks"] > 0
        assert p.length == path_length(want) and p.generated == ref.generated
        assert (p.lattice, p.cell_volume, p.method, p.neighbors, p.reason, p.status) == (
            "cubic", 1.0, "astar", "full", "", "found")
        assert (p.peak_bytes, p.guarantee, p.unknown_cells) == (ref.peak_bytes, True, 0)
        assert p.build_seconds == (w.build_seconds or 0.0) and p.unknown_note == w.unknown_note
        assert p.extra == {"cost_between_centres": ref.cost, "raw_length": p.length,
                           "smoothed_length": None, "join_checks": p.extra["join_checks"]}
        assert 0 < p.seconds < 1


def test_plan_errors_are_the_endpoint_errors():
    w = _world(n=8, blocked=[(3, 3, 3)])
    good = np.array([1.0, 1.0, 1.0])
    plan(w, good, np.array([6.0, 6.0, 6.0]))
    plan(w, good, np.array([6.0, 6.0, 6.0]))  # the one-call path is set up
    cases = [(np.array([3.0, 3.0, 3.0]), good), (good, np.array([3.0, 3.0, 3.0])),
             (np.array([30.0, 1.0, 1.0]), good), (good, np.array([1.0, -5.0, 1.0])),
             (np.array([np.nan, 1.0, 1.0]), good), (good, np.array([1.0, np.inf, 1.0]))]
    for a, b in cases:
        with pytest.raises(PlanError) as one_call:
            plan(w, a, b)
        with pytest.raises(PlanError) as checked:
            w.endpoint(a, "start")
            w.endpoint(b, "goal")
        assert str(one_call.value) == str(checked.value)
    with pytest.raises(PlanError, match="unknown method"):
        plan(w, good, np.array([6.0, 6.0, 6.0]), method="nope")
    with pytest.raises(PlanError, match="start"):  # the endpoint's error comes first
        plan(w, np.array([3.0, 3.0, 3.0]), good, method="nope")


def test_tuple_and_list_endpoints_take_the_one_call_path_with_the_same_results():
    """The README's own form, plan(world, (x, y, z), ...), takes the same compiled call as
    float64 arrays: the same path, lookups and errors; other forms are checked as before."""
    w = _world(n=12, blocked=[(5, y, z) for y in range(12) for z in range(11)])
    a, b = np.array([1.0, 1.0, 1.0]), np.array([10.0, 9.0, 2.0])
    ref = plan(w, a, b)
    forms = [(tuple(a.tolist()), tuple(b.tolist())), (a.tolist(), b.tolist()),
             ((1, 1, 1), [10, 9, 2]), ((np.float64(1), 1.0, 1), b)]
    for s, g in forms:
        before = w.cell_checks
        p = plan(w, s, g)
        assert w.cell_checks - before == p.cell_checks + 2 + p.extra["join_checks"]
        assert np.array_equal(p.path, ref.path) and p.length == ref.length
        assert (p.cell_checks, p.expansions) == (ref.cell_checks, ref.expansions)
    for bad, what in [((30.0, 1.0, 1.0), "start"), ((1.0, float("nan"), 1.0), "start"),
                      ((10**400, 1, 1), "start"),
                      ((1.0, 1.0), "start")]:
        with pytest.raises(PlanError, match=what) as one_call:
            plan(w, bad, b)
        with pytest.raises(PlanError) as checked:
            w.endpoint(bad, "start")
        assert str(one_call.value) == str(checked.value)


def test_long_and_sealed_searches_through_the_one_call_path():
    """A search that grows its arrays and pauses for the goal probe, and one whose goal is
    sealed in a pocket (the probe stops it), go on from the one call as search() does."""
    n, wall = 40, 2
    c = np.array([n - 8] * 3)
    shell = [c + d for d in itertools.product(range(-wall, wall + 1), repeat=3)
             if max(map(abs, d)) == wall]
    w = _world(n=n, blocked=shell)
    near = np.array([1.0, 1.0, 1.0]), np.array([2.0, 1.0, 1.0])
    far = np.array([1.0, 1.0, 1.0]), np.array([38.0, 2.0, 37.0])
    sealed = np.array([1.0, 1.0, 1.0]), c.astype(float)
    for a, b in (far, sealed):
        plan(w, *near)
        plan(w, *near)  # the one-call path is set up
        r = search_points(w, w.end_coords(a, b))
        assert r is not None
        ref = _reference(w, a, b)
        _same(r, ref)
    assert r.status == "unreachable" and 0 < r.expansions <= PROBE_AFTER
    p = plan(w, *sealed)
    assert not p.found and p.reason == ref.reason


@pytest.mark.parametrize("name", ["cubic", "bcc", "fcc", "mcc", "hex"])
def test_path_points_are_the_cell_centres_to_world_gives(name):
    """A plan writes its cell centres with to_world(cells, out=...): the same floats as
    to_world(cells), also for an array a compiled kernel returned (its int64 dtype is an
    object of its own, as an unpickled one is)."""
    own = pickle.loads(pickle.dumps(np.dtype(np.int64)))
    assert own == np.dtype(np.int64) and own is not np.dtype(np.int64)
    rng = np.random.default_rng(11)
    for vol in (1.0, 0.37, 2.5, 0.08**3):
        lat = Lattice.named(name, vol)
        for k in (*range(1, 12), 31, 100, 1000):
            cells = rng.integers(-100_000, 100_000, (k, 3))
            want = lat.to_world(cells)
            # to_world writes the same floats to any ``out`` (np.dot or np.matmul inside)
            for out in (np.empty((k, 3)), np.empty((k, 3), order="F"), np.empty((k, 4))[:, :3],
                        np.empty((k + 2, 3))[1:-1]):
                assert np.array_equal(lat.to_world(cells, out=out), want)
                assert np.array_equal(lat.to_world(cells.view(own), out=out), want)
