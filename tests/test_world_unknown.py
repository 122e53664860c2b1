"""Grid maps with unknown space (OctoMap-like leaves of several sizes): the world's unknown
and blocked cells equal a plain reference on every lattice."""

from __future__ import annotations

import numpy as np
import pytest

import planner
from planner.io import Obstacles
from planner.lattice import NAMED_LATTICES
from planner.occupancy.keys import pack, unpack
from planner.voxels import exact_box_inflation, inflation_stencil
from planner.voxels.unknown import unknown_box_keys

RES = 0.1
SHIFT = 0.013  # the voxel grid does not start at the origin


def _leaf_map() -> Obstacles:
    """3 x 2 x 1.2 m: observed for x < 2 except a hole, a wall with a gap, a pillar of 0.2 m
    leaves, a few random occupied voxels; free space pruned into 0.2 m leaves where whole."""
    n = (30, 20, 12)
    state = np.zeros(n, dtype=np.int8)  # 0 unknown, 1 free, 2 occupied
    state[:20] = 1
    state[8:12, 12:16] = 0  # an unobserved hole inside observed space
    state[14, :14] = 2  # a wall, open for y >= 1.4
    state[4:8, 4:6] = 2  # a pillar (0.2 m leaves below)
    rng = np.random.default_rng(7)
    for v in rng.integers(0, (20, 20, 12), size=(30, 3)):
        if state[tuple(v)] == 1:
            state[tuple(v)] = 2
    boxes, sizes = {1: [], 2: []}, {1: [], 2: []}
    taken = np.zeros(n, dtype=bool)
    for b in np.ndindex(n[0] // 2, n[1] // 2, n[2] // 2):  # prune whole 2x2x2 blocks
        sl = tuple(slice(2 * x, 2 * x + 2) for x in b)
        s = state[sl]
        if s.min() == s.max() and s.min() > 0:
            boxes[int(s.min())].append((np.array(b) * 2 + 1) * RES + SHIFT)
            sizes[int(s.min())].append(2 * RES)
            taken[sl] = True
    for v in np.argwhere((state > 0) & ~taken):
        boxes[int(state[tuple(v)])].append((v + 0.5) * RES + SHIFT)
        sizes[int(state[tuple(v)])].append(RES)
    lo = np.full(3, SHIFT)
    return Obstacles(points=np.zeros((0, 3)), boxes=np.array(boxes[2]), box_size=2 * RES,
                     box_sizes=np.array(sizes[2]), free_boxes=np.array(boxes[1]),
                     free_box_sizes=np.array(sizes[1]),
                     bounds=[lo, lo + np.array(n) * RES], resolution=RES, source="leaves")


def _reference(obst: Obstacles, lat, radius: float) -> tuple[np.ndarray, np.ndarray]:
    """Sorted keys of (the cells meeting unknown space, the blocked cells): unknown cells
    by the key-list classification over the bounds padded by a robot centre cell's reach;
    blocked = the exact obstacle inflation plus every unknown cell moved by every offset of
    the inflation stencil, kept where its centre lies within a covering radius of the
    bounds (cells further out are never searched)."""
    pad = radius + 2 * lat.covering_radius
    b = np.asarray(obst.bounds, dtype=float)
    unknown = unknown_box_keys(obst.boxes, obst.box_sizes, obst.free_boxes,
                               obst.free_box_sizes, RES, lat, b[0] - pad, b[1] + pad)
    moved = (unpack(unknown, 3)[:, None, :] + inflation_stencil(lat, radius)[None]).reshape(-1, 3)
    c = lat.to_world(moved)
    near = np.all((c >= b[0] - lat.covering_radius) & (c <= b[1] + lat.covering_radius), axis=1)
    h = obst.box_sizes[:, None] / 2
    occupied = exact_box_inflation(obst.boxes - h, obst.boxes + h, lat, radius).keys
    return unknown, np.union1d(occupied, pack(moved[near]))


@pytest.mark.parametrize("name", NAMED_LATTICES)
def test_grid_map_unknown_and_blocked_cells_equal_the_reference(name):
    obst = _leaf_map()
    assert len(np.unique(obst.free_box_sizes)) == 2 and len(np.unique(obst.box_sizes)) == 2
    for radius in (0.0, 0.17):
        w = planner.build_world(obst, name, cell_volume=0.07**3, radius=radius)
        unknown, blocked = _reference(obst, w.lattice, radius)
        # a world holds the cells in bounds (the others are never free)
        unknown = unknown[w.in_bounds(unpack(unknown, 3))]
        blocked = blocked[w.in_bounds(unpack(blocked, 3))]
        assert w.unknown_policy == "blocked" and len(unknown) > 1000
        assert np.array_equal(np.unique(pack(w.unknown)), unknown), (name, radius)
        assert np.array_equal(np.unique(pack(w.blocked)), blocked), (name, radius)
        free = planner.build_world(obst, name, cell_volume=0.07**3, radius=radius,
                                   unknown="free")
        assert np.array_equal(np.unique(pack(free.unknown)), unknown), (name, radius)
        assert free.n_blocked < len(blocked)
