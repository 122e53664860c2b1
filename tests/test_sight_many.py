"""``planner.search.sight_many``: line of sight for a batch of segments, as the searches
test it, agrees with ``World.segment_free`` between the same cell centres."""

from __future__ import annotations

import numpy as np
import pytest

from planner.errors import PlanError
from planner.lattice import NAMED_LATTICES, Lattice
from planner.search import sight_many
from planner.world import World


def _cluttered(name: str, seed: int = 0) -> tuple[World, np.ndarray]:
    """A 12 m box of the lattice at unit cell volume with random blocked cells (about one
    in eight), and its free cells."""
    rng = np.random.default_rng(seed)
    lat = Lattice.named(name, 1.0)
    step = 2 * lat.packing_radius
    pts = rng.uniform(-6, 6, (6000, 3)) * step
    cells = np.unique(lat.quantize(pts), axis=0)
    blocked = cells[rng.random(len(cells)) < 0.12]
    world = World(lat, blocked, np.array([[-8.0 * step] * 3, [8.0 * step] * 3]))
    free = cells[world.is_free(cells)]
    return world, free


@pytest.mark.parametrize("name", NAMED_LATTICES)
def test_sight_many_agrees_with_segment_free(name):
    world, free = _cluttered(name)
    rng = np.random.default_rng(1)
    p = free[rng.integers(len(free), size=300)]
    q = free[rng.integers(len(free), size=300)]
    before = world.cell_checks
    got = sight_many(world, p, q)
    assert got.free.shape == (300,) and got.lookups.shape == (300,)
    assert world.cell_checks - before == got.lookups.sum()
    a, b = world.lattice.to_world(p), world.lattice.to_world(q)
    want = np.array([world.segment_free(x, y) for x, y in zip(a, b, strict=True)])
    assert (got.free == want).all(), np.flatnonzero(got.free != want)
    # both answers occur, so the test would see a walk that always says yes or no
    assert 0 < want.sum() < len(want)
    assert (got.lookups >= 1).all()
    # a free line looks up at least every cell of its own two ends
    assert (got.lookups[got.free & (np.abs(p - q).sum(axis=1) > 0)] >= 2).all()


def test_sight_many_bad_input():
    world, free = _cluttered("cubic")
    with pytest.raises(PlanError, match="same shape"):
        sight_many(world, free[:3], free[:2])
    with pytest.raises(PlanError, match="integer"):
        sight_many(world, free[:3] + 0.5, free[:3])
    empty = sight_many(world, np.zeros((0, 3), int), np.zeros((0, 3), int))
    assert empty.free.shape == (0,) and empty.lookups.shape == (0,)
