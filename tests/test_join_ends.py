"""A plan joins its path's ends in one compiled call (planner.world.join): the same path,
lookups and length as joined()'s steps in Python (two World.segment_free checks, the
redundant hops dropped, points equal to 1 um merged)."""

from __future__ import annotations

import numpy as np
import pytest

from planner import search as S
from planner.errors import PlanError
from planner.lattice import Lattice
from planner.path import SHORT_PATH, path_length
from planner.planning import _joined_path, joined, plan
from planner.world import World


class _SegmentsOnly:
    """A world seen only through segment_free: joined() then takes its Python steps."""

    def __init__(self, world):
        self.world = world

    def segment_free(self, a, b):
        return self.world.segment_free(a, b)


def _python_joined(w, path):
    before = w.cell_checks
    out = joined(_SegmentsOnly(w), path)
    return out, w.cell_checks - before


def _world(name, n=10, vol=0.5, blocked=60, seed=0):
    rng = np.random.default_rng(seed)
    lat = Lattice.named(name, vol)
    b = rng.integers(0, n, (blocked, 3))
    return World(lat, b, np.array([[0.0, 0, 0], [n, n, n]]) * vol ** (1 / 3))


def _same_as_python(w, path):
    """joined() on the world (the compiled call) against its Python steps."""
    want, want_look = _python_joined(w, path)
    before = w.cell_checks
    given = path.copy()
    got = joined(w, path)
    assert np.array_equal(path, given)  # joined() writes to a copy
    assert w.cell_checks - before == want_look
    assert np.array_equal(got, want), (path, got, want)
    return got


def _chain(w, rng, k):
    """k cell centres, each a full neighbour of the one before, from a random cell."""
    lat = w.lattice
    full = lat.neighbors("full")
    cells = [rng.integers(1, 8, 3)]
    for _ in range(k - 1):
        cells.append(cells[-1] + full[rng.integers(len(full))])
    return np.array(cells), lat.to_world(np.array(cells))


@pytest.mark.parametrize("name", ["cubic", "bcc", "fcc", "mcc", "hex"])
def test_compiled_joins_match_the_python_steps(name):
    w = _world(name, seed=1)
    rng = np.random.default_rng(2)
    lat = w.lattice
    half = lat.relevant_vectors / 2  # facet centres: a start on a cell's boundary
    for trial in range(400):
        k = int(rng.choice([1, 2, 3, 4, 5, SHORT_PATH, SHORT_PATH + 1, 20]))
        cells, centres = _chain(w, rng, k)
        kind = trial % 5
        s = centres[0] + rng.normal(0, 0.2, 3)
        g = centres[-1] + rng.normal(0, 0.2, 3)
        if kind == 1:  # the start at its cell's centre, the goal 0.4 um from its own
            s, g = centres[0].copy(), centres[-1] + 4e-7
        elif kind == 2:  # on a facet between two cells
            s = centres[0] + half[rng.integers(len(half))]
        elif kind == 3:  # the goal at the start
            g = s.copy()
        elif kind == 4:  # far ends: joins longer than the walk's first scratch
            lo, hi = w.bounds
            s, g = rng.uniform(lo, hi), rng.uniform(lo, hi)
        path = np.concatenate([s[None], centres, g[None]])
        _same_as_python(w, path)


def test_merges_of_equal_points_match_the_python_steps():
    w = _world("cubic", blocked=0)
    c = w.lattice.to_world(np.array([[2, 2, 2], [3, 2, 2], [4, 2, 2]]))
    for path in ([c[0], c[0], c[1], c[2], c[2]],  # ends at their cells' centres
                 [c[0], c[0], c[0]],  # one cell, start and goal at its centre
                 [c[0] + 1e-7, c[0], c[0] - 2e-7],
                 [c[0], c[0] + 5e-7, c[1], c[1], c[2] + 4.9e-7, c[2] + 5.1e-7],
                 [c[0], c[1]], [c[0], c[0]], [c[0]]):
        got = _same_as_python(w, np.array(path, dtype=float))
        assert got[0].tolist() == path[0].tolist() and got[-1].tolist() == path[-1].tolist()


@pytest.mark.parametrize("name", ["cubic", "bcc", "fcc", "mcc", "hex"])
def test_plan_paths_lookups_and_lengths_are_the_python_steps(name):
    """plan()'s path is joined() of the start, the search's cell centres and the goal, in
    Python's steps, with their lookups counted and path_length's float."""
    w = _world(name, n=10, seed=3)
    S.warm_up()
    rng = np.random.default_rng(4)
    lo, hi = w.bounds
    done = 0
    for _ in range(80):
        a, b = rng.uniform(lo, hi), rng.uniform(lo, hi)
        try:
            for shortcut in (False, True):
                p = plan(w, a, b, shortcut=shortcut)
                if not p.found:
                    continue
                want, look = _python_joined(
                    w, np.concatenate([a[None], w.lattice.to_world(p.cells), b[None]]))
                assert np.array_equal(p.path, want)
                assert p.length == path_length(want, 0.0)
                if not shortcut:
                    assert p.extra["join_checks"] == look
                    assert p.extra["raw_length"] == p.length
                done += 1
        except PlanError:
            continue
    assert done > 20


def test_the_joined_path_of_a_long_search_sums_its_length_as_numpy_does():
    w = _world("bcc", n=12, blocked=0)
    cells, centres = _chain(w, np.random.default_rng(5), 40)
    s, g = centres[0] + 0.01, centres[-1] - 0.01
    path, look, length = _joined_path(w, s.tolist(), cells, g.tolist())
    want, want_look = _python_joined(w, np.concatenate([s[None], centres, g[None]]))
    assert np.array_equal(path, want) and look == want_look
    assert len(path) > SHORT_PATH and length == path_length(want)
