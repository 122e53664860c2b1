"""Maps in any frame: a survey in UTM coordinates plans at the cell size its detail needs.

A world far from its map's origin is built in a local frame whose origin (``World.offset``)
is a lattice vector near the map; points go in and come out in the map's frame, and the
21-bit index limit applies to the map's extent, not its distance from the origin.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import pytest

import planner
from planner.bench.metrics import Clearance
from planner.errors import MapError, PlanError
from planner.lattice import Lattice
from planner.world.file import load_world, save_world
from planner.world.frame import local_offset

sys.path.insert(0, str(Path(__file__).parent))
from _survey import CORNER, write_survey  # noqa: E402

START = np.array([455_005.0, 5_410_005.0, 325.0])
GOAL = np.array([455_145.0, 5_410_145.0, 325.0])


@pytest.mark.parametrize("name", ["cubic", "bcc", "fcc", "hex"])
def test_the_local_origin_is_a_lattice_vector_near_a_far_box(name):
    lat = Lattice.named(name, 0.001)
    far = np.array([[455_000.0, 5_410_000.0, 320.0], [455_150.0, 5_410_150.0, 330.0]])
    o = local_offset(lat, far)
    n = np.linalg.solve(lat.generator, o)
    np.testing.assert_allclose(n, np.rint(n), atol=1e-6)  # G n, n integer
    assert np.abs(o - far.mean(axis=0)).max() < lat.packing_radius * 4
    # a map near its origin keeps the map's frame
    assert not local_offset(lat, np.array([[0.0, 0, 0], [150, 150, 10]])).any()


def _far_cloud() -> np.ndarray:
    """A 20 x 20 m site in UTM: a wall across the middle with a gap at its north end."""
    y = np.arange(0.0, 15.0, 0.1)
    z = np.arange(0.0, 3.0, 0.1)
    yy, zz = np.meshgrid(y, z)
    wall = np.column_stack([np.full(yy.size, 10.0), yy.ravel(), zz.ravel()])
    corners = np.array([[0.0, 0, 0], [20, 20, 3]])
    return np.concatenate([wall, corners]) + CORNER


def test_a_far_world_plans_and_answers_in_the_map_frame(tmp_path):
    pts = _far_cloud()
    world = planner.build_world(pts, "fcc", cell_volume=0.001, radius=0.3)
    assert world.local_frame and np.abs(world.offset - CORNER).max() < 20
    s, g = CORNER + [2.0, 2.0, 1.5], CORNER + [18.0, 2.0, 1.5]
    res = planner.plan(world, s, g)
    assert res.found and res.extra["local_offset"] == world.offset.tolist()
    assert np.array_equal(res.path[0], s) and np.array_equal(res.path[-1], g)
    assert res.path[:, 1].max() > CORNER[1] + 15  # around the wall's end, in UTM
    assert Clearance(pts, np.zeros((0, 3))).of_path(res.path, 0.02) >= 0.3
    # errors name the map's coordinates, not the local ones
    with pytest.raises(PlanError, match=r"455010\.000, 5410002\.000"):
        planner.plan(world, CORNER + [10.0, 2.0, 1.5], g)
    with pytest.raises(PlanError, match=r"outside the map bounds \(455000\.000"):
        planner.plan(world, CORNER - 1.0, g)
    # a saved world keeps its frame: the same path from the file
    out = tmp_path / "w.npz"
    save_world(world, out)
    back = load_world(out)
    assert np.array_equal(back.offset, world.offset)
    again = planner.plan(back, s, g)
    np.testing.assert_array_equal(again.path, res.path)
    # bounds asked of a saved world are the map's
    planner.build_world(out, bounds=world.to_map(world.bounds))
    # exported cell centres are the map's too
    from plyfile import PlyData

    from planner.export.cells import write_ply_cells, write_world_cells

    write_ply_cells(tmp_path / "c.ply", world)
    v = PlyData.read(str(tmp_path / "c.ply"))["vertex"]
    xyz = np.column_stack([v["x"], v["y"], v["z"]])
    ijk = np.column_stack([v["i"], v["j"], v["k"]])
    np.testing.assert_allclose(xyz, world.lattice.to_world(ijk) + world.offset, atol=1e-6)
    assert np.abs(xyz - CORNER).max() < 25
    with pytest.raises(MapError, match="OctoMap tree reaches"):
        write_world_cells(tmp_path / "c.bt", world)
    assert not (tmp_path / "c.bt").exists()


def test_a_far_2d_map_plans_in_the_map_frame(tmp_path):
    pix = np.full((40, 60), 254, np.uint8)  # 3 x 2 m, a wall from the top (north) edge
    pix[0:25, 30] = 0
    (tmp_path / "m.pgm").write_bytes(b"P5\n60 40\n255\n" + pix.tobytes())
    (tmp_path / "m.yaml").write_text(
        "image: m.pgm\nresolution: 0.05\norigin: [455000.0, 5410000.0, 0.0]\nnegate: 0\n"
        "occupied_thresh: 0.65\nfree_thresh: 0.196\n")
    world = planner.build_world(tmp_path / "m.yaml", radius=0.1)
    assert world.local_frame and world.offset[2] == 0
    res = planner.plan(world, [455_000.5, 5_410_001.5], [455_002.5, 5_410_001.5])
    assert res.found and np.array_equal(res.path[0], [455_000.5, 5_410_001.5, 0])
    assert res.path[:, 1].min() < 5_410_000.75  # around the wall's south end


def _survey(tmp_path) -> tuple[Path, np.ndarray]:
    pytest.importorskip("laspy")
    path = tmp_path / "survey_utm.las"
    return path, write_survey(path)


def test_utm_survey_plans_from_the_command_line(tmp_path):
    # the reproducer: failed with "lattice indices exceed +-1048576 cells per axis"
    from planner.cli import main

    las, raw = _survey(tmp_path)
    out = tmp_path / "p.json"
    assert main(["plan", str(las), "--radius", "1", "--start", "455005,5410005,325",
                 "--goal", "455145,5410145,325", "--out", str(out)]) == 0
    rec = json.loads(out.read_text())
    path = np.array(rec["path"])
    assert path[0].tolist() == START.tolist() and path[-1].tolist() == GOAL.tolist()
    assert rec["local_offset"] != [0.0, 0.0, 0.0]
    assert Clearance(raw, np.zeros((0, 3))).of_path(path, 0.05) >= 1.0


@pytest.mark.slow
def test_utm_survey_plans_at_fifth_of_a_metre_cells(tmp_path):
    las, raw = _survey(tmp_path)
    world = planner.build_world(las, "fcc", cell_volume=0.008, radius=1.0)  # 0.2 m cells
    assert world.lattice.cell_volume ** (1 / 3) == pytest.approx(0.2)  # the cube-root edge
    res = planner.plan(world, START, GOAL)
    assert res.found
    assert np.array_equal(res.path[0], START) and np.array_equal(res.path[-1], GOAL)
    assert Clearance(raw, np.zeros((0, 3))).of_path(res.path, 0.05) >= 1.0
