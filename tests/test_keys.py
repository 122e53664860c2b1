"""The one key layout: 3D indices packed into int64 keys, and the key sets built on them."""

import numpy as np
import pytest

from planner.occupancy.keys import (
    build_key_set,
    in_key_set,
    in_key_set3,
    index_limit,
    pack,
    pack3,
    step3,
    unpack,
    unpack3,
)

LIM = index_limit(3)


def test_pack3_is_pack_and_unpack3_inverts_it_to_the_range_ends():
    ends = np.array([[-LIM, -LIM, -LIM], [LIM - 1, LIM - 1, LIM - 1], [-LIM, 0, LIM - 1],
                     [5, -7, 11]])
    keys = pack(ends)
    for (i, j, k), key in zip(ends.tolist(), keys.tolist(), strict=True):
        assert pack3(i, j, k) == key
        assert unpack3(key) == (i, j, k)
    assert (unpack(keys, 3) == ends).all()


def test_a_step_adds_its_key_offset():
    rng = np.random.default_rng(3)
    for _ in range(200):
        u = rng.integers(-1000, 1000, 3)
        d = rng.integers(-2, 3, 3)
        assert pack3(*(u + d).tolist()) == pack3(*u.tolist()) + step3(*d.tolist())


def test_key_set_membership_matches_a_python_set():
    rng = np.random.default_rng(4)
    cells = rng.integers(-50, 50, (300, 3))
    table = build_key_set(pack(cells), 1024)
    stored = {tuple(c) for c in cells.tolist()}
    for c in rng.integers(-50, 50, (2000, 3)).tolist():
        assert in_key_set(table, 1023, pack3(*c)) == (tuple(c) in stored)
        assert in_key_set3(table, 1023, *c) == (tuple(c) in stored)


@pytest.mark.parametrize(("stored", "past"), [
    ((0, 1, -LIM), (0, 0, LIM)),  # z past the range carries into y
    ((1, -LIM, 0), (0, LIM, 0)),  # y into x
])
def test_an_index_past_the_packable_range_is_never_in_a_key_set(stored, past):
    table = build_key_set(pack(np.array([stored])), 4)
    assert pack3(*past) == pack3(*stored)  # what the range test guards against
    assert in_key_set3(table, 3, *stored)
    assert not in_key_set3(table, 3, *past)
    assert not in_key_set3(table, 3, -LIM - 1, 0, 0)
