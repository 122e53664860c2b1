"""Compact worlds: the cells a world built on bit sets holds are exactly those of the list
path, on every lattice, and survive saving."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import planner
from planner.errors import MapError
from planner.io import Obstacles
from planner.lattice import NAMED_LATTICES
from planner.occupancy.keys import pack
from planner.world.assemble import reference_cells
from planner.world.build import resolve_defaults
from planner.world.file import save_world

GEB = Path("../shared/data/octomap/geb079.bt")


def _room(res: float = 0.1) -> Obstacles:
    """A 2 x 2 x 1 m grid map: a wall at x = 1 with a gap, free space observed only for
    y < 1.4 (unknown beyond), and a few obstacle points."""
    ax = [np.arange(0, 2, res) + res / 2, np.arange(0, 2, res) + res / 2,
          np.arange(0, 1, res) + res / 2]
    c = np.stack(np.meshgrid(*ax, indexing="ij"), -1).reshape(-1, 3)
    wall = (np.abs(c[:, 0] - 1.05) < res / 2 + 1e-9) & (c[:, 1] < 1.2)
    free = ~wall & (c[:, 1] < 1.4)
    pts = np.random.default_rng(5).uniform([0, 0, 0], [2, 2, 1], (12, 3))
    return Obstacles(points=pts, boxes=c[wall], box_size=res, free_boxes=c[free],
                     free_box_sizes=np.full(int(free.sum()), res), bounds=[[0, 0, 0], [2, 2, 1]],
                     resolution=res, source="room")


def _box_cells(world) -> np.ndarray:
    """Every cell whose centre lies within a cell of the bounds, and a margin of cells."""
    lat = world.lattice
    lo, hi = world.bounds
    pad = 2 * lat.covering_radius
    step = lat.packing_radius
    ax = [np.arange(a - pad, b + pad + step, step) for a, b in zip(lo, hi, strict=True)]
    pts = np.stack(np.meshgrid(*ax, indexing="ij"), -1).reshape(-1, 3)
    return np.unique(lat.quantize(pts), axis=0)


def _expect(obst, name: str, radius: float, unknown: str):
    got = resolve_defaults(obst, {}, lattice=name, cell_volume=0.08**3, radius=radius,
                           unknown=unknown)
    return got, reference_cells(obst, got.lattice, got.bounds, radius, unknown, False)


@pytest.mark.parametrize("name", NAMED_LATTICES)
@pytest.mark.parametrize(("radius", "unknown"), [(0.0, "free"), (0.13, "blocked")])
def test_compact_world_holds_exactly_the_cells_of_the_list_path(name, radius, unknown):
    obst = _room()
    w = planner.build_world(obst, name, cell_volume=0.08**3, radius=radius, unknown=unknown)
    _, (cells, unknown_cells) = _expect(obst, name, radius, unknown)
    inside = np.unique(pack(cells[w.in_bounds(cells)]))
    assert w.storage == "dense" and len(inside) > 100
    assert np.array_equal(pack(w.blocked), inside)
    assert w.n_blocked == len(inside)
    u = np.unique(pack(unknown_cells[w.in_bounds(unknown_cells)]))
    assert len(u) > 0 and np.array_equal(pack(w.unknown), u)
    probe = _box_cells(w)
    free = w.in_bounds(probe) & ~np.isin(pack(probe), inside)
    assert np.array_equal(w.is_free(probe), free)
    assert np.array_equal(w.is_unknown(probe), np.isin(pack(probe), u))


@pytest.mark.parametrize("name", ["cubic", "fcc", "hex"])
def test_hash_storage_world_holds_the_same_free_cells(name):
    obst = _room()
    dense = planner.build_world(obst, name, cell_volume=0.08**3, radius=0.13)
    got, _ = _expect(obst, name, 0.13, "blocked")
    from planner.world.assemble import assemble

    huge = assemble(obst, got.lattice, got.bounds, 0.13, "blocked", False, dense_budget=0)
    assert huge.storage == "hash"
    probe = _box_cells(dense)
    assert np.array_equal(huge.is_free(probe), dense.is_free(probe))
    assert np.array_equal(huge.is_unknown(probe), dense.is_unknown(probe))


def test_saved_compact_world_round_trips_cell_for_cell(tmp_path):
    obst = _room()
    w = planner.build_world(obst, "fcc", cell_volume=0.08**3, radius=0.13)
    path = tmp_path / "room.npz"
    save_world(w, path)
    back = planner.build_world(path)
    probe = _box_cells(w)
    assert np.array_equal(back.is_free(probe), w.is_free(probe))
    assert np.array_equal(back.is_unknown(probe), w.is_unknown(probe))
    assert back.n_blocked == w.n_blocked and back.n_unknown == w.n_unknown


def test_saved_world_of_an_older_version_is_refused_in_one_line(tmp_path):
    path = tmp_path / "old.npz"
    np.savez(path, format=np.array("planner.World"), version=np.array(2))
    with pytest.raises(MapError, match=r"old.npz: saved world version 2; this planner reads "
                                       r"version 3 \(rebuild it"):
        planner.build_world(path)


def test_flipped_bit_in_a_saved_world_is_found(tmp_path):
    w = planner.build_world(_room(), "bcc", cell_volume=0.08**3, radius=0.13)
    path = tmp_path / "room.npz"
    save_world(w, path)
    d = dict(np.load(path))
    d["blocked"] = d["blocked"].copy()
    d["blocked"][len(d["blocked"]) // 2] ^= 1
    np.savez_compressed(path, **d)
    with pytest.raises(MapError, match="corrupt or modified world file"):
        planner.build_world(path)


@pytest.mark.slow
@pytest.mark.skipif(not GEB.is_file(), reason="geb079.bt not present")
@pytest.mark.parametrize("name", NAMED_LATTICES)
def test_geb079_compact_world_equals_the_list_path(name):
    obst = planner.io.load_obstacles(GEB)
    got = resolve_defaults(obst, {}, lattice=name, cell_volume=0.16**3, radius=0.2,
                           unknown="blocked")
    w = planner.build_world(obst, name, cell_volume=0.16**3, radius=0.2, unknown="blocked")
    cells, unknown_cells = reference_cells(obst, got.lattice, got.bounds, 0.2, "blocked",
                                           False)
    assert np.array_equal(pack(w.blocked), np.unique(pack(cells[w.in_bounds(cells)])))
    u = unknown_cells[w.in_bounds(unknown_cells)]
    assert np.array_equal(pack(w.unknown), np.unique(pack(u)))
