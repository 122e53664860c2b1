"""Bundled example maps: present, loadable, reproducible, and as described in their sidecars."""

import hashlib
import json
from pathlib import Path

import numpy as np
import pytest
from plyfile import PlyData
from scipy.spatial import cKDTree

from planner import maps
from planner.errors import MapError

NAMES = ["office", "two_storey", "warehouse", "forest", "narrow_passage"]


def read_ply(path):
    vertex = PlyData.read(str(path))["vertex"]
    return np.column_stack([vertex["x"], vertex["y"], vertex["z"]]).astype(np.float64)


def sha256(path):
    return hashlib.sha256(path.read_bytes()).hexdigest()


@pytest.fixture(scope="module")
def fresh(tmp_path_factory):
    """A fresh regeneration of every map into a temporary folder."""
    out = tmp_path_factory.mktemp("fresh_maps")
    maps.generate_all(out)
    return out


@pytest.fixture(scope="module", params=NAMES)
def bundled(request):
    """(name, points, info) of one bundled map, read from maps/ with plyfile."""
    name = request.param
    return name, read_ply(maps.map_path(name)), maps.load_map_info(name)


def test_registry_lists_the_five_maps():
    assert list(maps.MAPS) == NAMES
    for name in NAMES:
        assert callable(maps.MAPS[name])


@pytest.mark.parametrize("name", NAMES)
def test_bundled_files_exist_are_small_and_binary_float32(name):
    ply = maps.map_path(name)
    assert ply == maps.MAPS_DIR / f"{name}.ply"
    assert (maps.MAPS_DIR / f"{name}.json").is_file()
    assert ply.stat().st_size < 3_000_000
    data = PlyData.read(str(ply))
    assert not data.text and data.byte_order == "<"
    vertex = data["vertex"]
    assert [p.name for p in vertex.properties] == ["x", "y", "z"]
    assert all(vertex[k].dtype == np.float32 for k in "xyz")
    assert vertex.count == maps.load_map_info(name)["n_points"]


def test_bundled_map_matches_a_fresh_regeneration(bundled, fresh):
    name, points, info = bundled
    regenerated = read_ply(fresh / f"{name}.ply")
    assert regenerated.shape == points.shape
    # byte-identical on one platform; the tolerance only absorbs last-ulp libm differences
    np.testing.assert_allclose(regenerated, points, rtol=0, atol=1e-5)
    assert json.loads((fresh / f"{name}.json").read_text()) == {
        k: v for k, v in info.items() if k != "ply_path"
    }


def test_generation_is_byte_for_byte_deterministic(fresh, tmp_path):
    maps.generate_all(tmp_path)
    for name in NAMES:
        for ext in ("ply", "json"):
            assert sha256(tmp_path / f"{name}.{ext}") == sha256(fresh / f"{name}.{ext}")


def test_generator_functions_return_the_bundled_points(bundled):
    name, points, _ = bundled
    generated = maps.MAPS[name](seed=0)
    assert generated.shape == points.shape and generated.shape[1] == 3
    np.testing.assert_allclose(generated, points, rtol=0, atol=1e-5)


def test_other_seeds_give_other_valid_maps():
    a, b = maps.forest(seed=0), maps.forest(seed=1)
    assert a.shape != b.shape or not np.array_equal(a, b)


def test_bounds_contain_every_point_and_are_tight(bundled):
    name, points, info = bundled
    lo, hi = np.array(info["bounds"][0]), np.array(info["bounds"][1])
    tol = 0.03  # six sigma of the 5 mm sensor noise
    assert (points >= lo - tol).all(), name
    assert (points <= hi + tol).all(), name
    # the outer walls (floor, ...) lie at the bounds: no slack box around the map
    assert np.abs(points.min(axis=0) - lo).max() < 0.1, name
    assert np.abs(points.max(axis=0) - hi).max() < 0.1, name


def test_sidecar_documents_radius_cell_volume_and_queries(bundled):
    name, _, info = bundled
    assert info["name"] == name and info["description"]
    assert 0.1 <= info["robot_radius"] <= 0.5
    assert 0.0005 <= info["cell_volume"] <= 0.01
    lo, hi = np.array(info["bounds"])
    cells = np.prod(hi - lo) / info["cell_volume"]
    assert 1e5 <= cells <= 2e6, f"{name}: {cells:.0f} cells with the suggested cell volume"
    assert 2 <= len(info["queries"]) <= 4
    assert info["clearance"] == pytest.approx(2 * info["robot_radius"] + 0.1)


def test_default_queries_are_well_inside_free_space(bundled):
    name, points, info = bundled
    tree = cKDTree(points)
    lo, hi = np.array(info["bounds"])
    needed = 2 * info["robot_radius"] + 0.1
    for q in info["queries"]:
        for end in (np.array(q["start"]), np.array(q["goal"])):
            assert (end > lo).all() and (end < hi).all(), (name, q)
            assert tree.query(end)[0] >= needed, (name, q)


def test_default_queries_need_a_real_route(bundled):
    """The straight segment from start to goal is blocked for the suggested robot."""
    name, points, info = bundled
    tree = cKDTree(points)
    for q in info["queries"]:
        start, goal = np.array(q["start"]), np.array(q["goal"])
        line = start + np.linspace(0, 1, 2000)[:, None] * (goal - start)
        assert tree.query(line)[0].min() < info["robot_radius"], (name, q)


def test_narrow_passage_clear_width_and_height_are_as_documented():
    points, info = maps.load_map_points("narrow_passage"), maps.load_map_info("narrow_passage")
    extra = info["extra"]
    assert extra["passage_width"] == 0.7 and info["robot_radius"] == 0.3
    (x0, y0, _), (x1, y1, _) = extra["passage_box"]
    yc = (y0 + y1) / 2
    inside = points[(points[:, 0] > x0 + 0.3) & (points[:, 0] < x1 - 0.3)
                    & (np.abs(points[:, 1] - yc) < 1.0)]
    walls = inside[(inside[:, 2] > 0.1) & (inside[:, 2] < 0.9)]
    width = walls[walls[:, 1] > yc, 1].min() - walls[walls[:, 1] < yc, 1].max()
    assert abs(width - extra["passage_width"]) <= 0.05
    assert width > 2 * info["robot_radius"]  # passable, barely
    centre = inside[np.abs(inside[:, 1] - yc) < 0.2]
    height = centre[centre[:, 2] > 0.5, 2].min() - centre[centre[:, 2] < 0.5, 2].max()
    assert abs(height - extra["passage_height"]) <= 0.05


def test_narrow_passage_is_the_only_way_between_the_chambers():
    points = maps.load_map_points("narrow_passage")
    wall = points[np.abs(points[:, 0] - 6.0) < 0.02]  # east wall of the west chamber
    grid = np.zeros((60, 30), dtype=bool)  # 0.1 m cells over y 0..6, z 0..3
    iy = np.clip((wall[:, 1] / 0.1).astype(int), 0, 59)
    iz = np.clip((wall[:, 2] / 0.1).astype(int), 0, 29)
    grid[iy, iz] = True
    holes = np.argwhere(~grid)
    assert len(holes) > 0
    assert (np.abs(holes[:, 0] * 0.1 + 0.05 - 3.0) < 0.4).all()  # all within y 2.65..3.35
    assert (holes[:, 1] * 0.1 < 1.0).all()  # and below the passage ceiling


def test_forest_ground_is_uneven_but_smooth():
    points = maps.load_map_points("forest")
    # lowest point in each 1 m x 1 m column: the ground (trunks stand on it)
    ij = np.floor(points[:, :2]).astype(int).clip(0, 29)
    ground = np.full((30, 30), np.inf)
    np.minimum.at(ground, (ij[:, 0], ij[:, 1]), points[:, 2])
    assert np.isfinite(ground).all()
    assert ground.max() - ground.min() > 1.5
    assert ground.std() > 0.2
    assert np.abs(np.diff(ground, axis=0)).max() < 0.6  # smooth: < 0.6 m per metre
    assert np.abs(np.diff(ground, axis=1)).max() < 0.6
    assert 60 <= maps.load_map_info("forest")["extra"]["n_trees"] <= 100


def test_forest_has_no_ceiling_over_open_ground():
    points = maps.load_map_points("forest")
    info = maps.load_map_info("forest")
    start = np.array(info["queries"][0]["start"])
    column = points[np.hypot(points[:, 0] - start[0], points[:, 1] - start[1]) < 0.3]
    assert column[:, 2].max() < start[2]  # nothing above the first query point


def test_two_storey_slab_has_an_opening_above_the_stairs():
    points = maps.load_map_points("two_storey")
    in_slab = (points[:, 2] > 2.9) & (points[:, 2] < 3.3)
    well = (points[:, 0] > 0.3) & (points[:, 0] < 4.8) & (points[:, 1] > 0.3) & (points[:, 1] < 2.0)
    elsewhere = (points[:, 0] > 6.5) & (points[:, 1] > 3.0)
    assert not (in_slab & well).any()
    assert (in_slab & elsewhere).sum() > 1000
    # stair treads climb from the ground floor to the upper floor inside the well
    treads = points[well & (points[:, 1] < 1.1)]
    assert treads[:, 2].max() > 2.5 and treads[:, 2].min() < 0.3


def test_office_doors_are_open_and_walls_are_closed_elsewhere():
    points, info = maps.load_map_points("office"), maps.load_map_info("office")
    doors = info["extra"]["doors"]
    assert len(doors) == 9
    for lo, hi in doors:
        lo, hi = np.array(lo), np.array(hi)
        assert hi[2] == pytest.approx(2.1)
        assert max(hi[0] - lo[0], hi[1] - lo[1]) == pytest.approx(0.9)
        box = (points > lo + [0.03, 0.03, 0.05]) & (points < hi - [0.03, 0.03, 0.05])
        assert not box.all(axis=1).any(), (lo, hi)
    # the corridor wall at y = 5 is closed next to a door
    wall = points[(np.abs(points[:, 1] - 4.94) < 0.02) & (points[:, 2] < 2.0)]
    assert ((wall[:, 0] > 4.0) & (wall[:, 0] < 6.5)).sum() > 100


def test_warehouse_aisles_are_two_metres_wide():
    points, info = maps.load_map_points("warehouse"), maps.load_map_info("warehouse")
    racks, (x0, x1) = info["extra"]["racks_y"], info["extra"]["racks_x"]
    hall = points[(points[:, 0] > x0) & (points[:, 0] < x1)
                  & (points[:, 2] > 0.1) & (points[:, 2] < 5.9)]  # no floor, ceiling, end walls
    for (_, a_end), (b_start, _) in zip(racks[:-1], racks[1:], strict=True):
        aisle = hall[(hall[:, 1] > a_end + 0.05) & (hall[:, 1] < b_start - 0.05)]
        assert len(aisle) == 0  # nothing stands in the aisle
        assert b_start - a_end == pytest.approx(2.0)


def test_load_map_info_accepts_name_json_path_and_ply_path():
    by_name = maps.load_map_info("office")
    by_json = maps.load_map_info(maps.MAPS_DIR / "office.json")
    by_ply = maps.load_map_info(str(maps.map_path("office")))
    assert by_name == by_json == by_ply
    assert by_name["ply_path"] == str(maps.map_path("office"))


def test_unknown_or_missing_maps_raise_map_error(tmp_path):
    with pytest.raises(MapError):
        maps.map_path("moon_base")
    with pytest.raises(MapError):
        maps.load_map_info(tmp_path / "nothing.json")
    with pytest.raises(MapError):
        maps.build("moon_base")
    bad = tmp_path / "bad.ply"
    bad.write_bytes(b"not a ply file")
    with pytest.raises(MapError):
        maps.load_map_points(bad)


def test_a_query_inside_an_obstacle_fails_loudly(monkeypatch):
    from planner.maps import _scenes

    original = _scenes._BUILDERS["office"]

    def broken(seed):
        m = original(seed)
        m.info["queries"][0]["start"] = [2.5, 5.0, 1.2]  # inside the corridor wall
        return m

    monkeypatch.setitem(_scenes._BUILDERS, "office", broken)
    with pytest.raises(MapError, match="from the cloud"):
        maps.office()


def test_bundled_maps_resolve_by_name_from_any_folder(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert maps.resolve("office") == maps.map_path("office")
    assert maps.resolve("office.ply") == maps.map_path("office")
    (tmp_path / "office.ply").write_bytes(b"mine")  # a local file of that name wins
    assert maps.resolve("office.ply") == Path("office.ply")
    assert maps.resolve("elsewhere/office.ply") == Path("elsewhere/office.ply")


def test_source_checkout_keeps_maps_folder_paths():
    top = Path(__file__).resolve().parents[1] / "maps" / "office.ply"
    assert top.is_file()
    assert top.read_bytes() == maps.map_path("office").read_bytes()


@pytest.mark.parametrize("text, match", [
    ('{"robot_radius": "x"}', "robot_radius"),
    ('{"cell_volume": 0}', "cell_volume"),
    ('{"bounds": "abc"}', "bounds"),
    ('{"bounds": [[0, 0, 0], [1, 1]]}', "bounds"),
    ('{"bounds": [[0, 0, 0], [-1, 1, 1]]}', "bounds"),
    ('[1, 2]', "JSON object"),
    ('{"queries": [{"start": [0, 0, 0]}]}', "goal"),
    ('{"queries": [{"start": [0, 0, "a"], "goal": [1, 1, 1]}]}', "start"),
    ("{not json", "JSON"),
])
def test_malformed_sidecars_are_one_line_map_errors(tmp_path, text, match):
    (tmp_path / "m.json").write_text(text)
    with pytest.raises(MapError, match=match) as err:
        maps.read_sidecar(tmp_path / "m.ply")
    assert "\n" not in str(err.value)


def test_a_map_without_sidecar_has_empty_info(tmp_path):
    assert maps.read_sidecar(tmp_path / "plain.ply") == {}
