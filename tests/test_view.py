"""The 3D viewer: one self-contained HTML page, checked in a real (headless) browser."""

import base64
import io
import json
import re

import numpy as np
import pytest

from planner import Lattice, World
from planner.cli import main
from planner.view import render_view
from planner.view.scene import build_scene, surface_cells


def _block_world(n=5, **kw):
    lat = Lattice.named("cubic", 1.0)
    cells = np.stack(np.meshgrid(*[np.arange(n)] * 3, indexing="ij"), -1).reshape(-1, 3)
    return World(lat, cells, [[-2, -2, -2], [n + 2, n + 2, n + 2]], **kw), cells


def _data(page: str) -> dict:
    return json.loads(re.search(r"const DATA = (\{.*?\});\n", page, re.S).group(1))


def test_hidden_interior_cells_are_dropped_and_the_page_says_how_many_are_shown():
    world, cells = _block_world(5)
    faces = world.lattice.neighbors("face")
    shell = surface_cells(cells, faces)
    assert shell.sum() == 5**3 - 3**3  # the 3 x 3 x 3 inside is hidden by the shell
    scene = build_scene(world, max_cells=50)
    (blocked,) = [x for x in scene.layers if x.name == "blocked cells"]
    assert (blocked.total, blocked.surface, blocked.shown) == (125, 98, 50)
    assert any("50 of 125" in n for n in scene.notes)


def test_page_is_self_contained_and_embeds_cells_and_paths_as_binary():
    world, cells = _block_world(3)
    path = np.array([[-1.5, -1.5, -1.5], [4.0, -1.5, 1.0], [4.0, 4.0, 4.0]])
    page = render_view(world, {"demo": path})
    assert "<script src" not in page and "<link" not in page  # nothing fetched when opened
    data = _data(page)
    (layer,) = [x for x in data["layers"] if x["name"] == "blocked cells"]
    got = np.frombuffer(base64.b64decode(layer["data"]), "<i2").reshape(-1, 3)
    assert {tuple(c) for c in got} == {tuple(c) for c in cells} - {(1, 1, 1)}
    p = np.frombuffer(base64.b64decode(data["paths"][0]["data"]), "<f4").reshape(-1, 3)
    np.testing.assert_allclose(p, path, atol=1e-6)
    assert data["start"] == [-1.5, -1.5, -1.5] and data["goal"] == [4.0, 4.0, 4.0]


def test_cli_view_of_a_map_with_a_planned_path(tmp_path):
    office = ["office", "--cell-volume", "0.01", "--radius", "0.1", "--lattice", "bcc"]
    assert main(["plan", *office, "--start", "1,1,1", "--goal", "7.9,5.4,1.1",
                 "--out", str(tmp_path / "p.json"), "--view", str(tmp_path / "plan.html")]) == 0
    assert main(["view", *office, "--path", str(tmp_path / "p.json"),
                 "--out", str(tmp_path / "v.html")]) == 0
    data = _data((tmp_path / "v.html").read_text())
    assert [p["label"] for p in data["paths"]] == ["bcc (p.json)"]
    assert {x["name"] for x in data["layers"]} >= {"raw points", "blocked cells"}
    assert _data((tmp_path / "plan.html").read_text())["paths"]


def test_cli_view_refuses_a_bad_path_file_in_one_line(tmp_path, capsys):
    bad = tmp_path / "bad.json"
    bad.write_text("{}")
    assert main(["view", "office", "--path", str(bad), "--out", str(tmp_path / "v.html")]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "bad.json" in err
    assert not (tmp_path / "v.html").exists()


@pytest.mark.slow
@pytest.mark.real_data
def test_geb079_view_renders_in_headless_chromium_with_the_path_visible(real_data, tmp_path):
    from planner.view.browser import find_browser, open_page

    found = find_browser()
    if isinstance(found, str):
        pytest.skip(found)
    import matplotlib.image

    geb = [str(real_data / "octomap" / "geb079.bt"), "--lattice", "bcc", "--radius", "0.2"]
    world_file = tmp_path / "geb.npz"
    assert main(["world", *geb, "--out", str(world_file)]) == 0
    assert main(["plan", str(world_file), "--start=-5.9,-0.87,0.81", "--goal", "8.38,-0.71,0.55",
                 "--out", str(tmp_path / "p.json")]) == 0
    assert main(["view", str(world_file), "--path", str(tmp_path / "p.json"),
                 "--out", str(tmp_path / "v.html")]) == 0
    run = open_page(tmp_path / "v.html")
    assert run.console == [] and run.state["errors"] == []
    img = matplotlib.image.imread(io.BytesIO(run.png), format="png")[..., :3]
    assert img.shape[:2] == (run.height, run.width)
    assert (img.std(axis=2) + (1 - img.mean(axis=2)) > 0.1).mean() > 0.05  # not blank
    magenta = (img[..., 0] > 0.8) & (img[..., 1] < 0.35) & (img[..., 2] > 0.8)
    (path,) = run.state["paths"]
    hits = []
    for x, y in path["screen"]:
        if 0 <= x < run.width and 0 <= y < run.height:
            c, r = int(x), int(y)
            hits.append(magenta[max(r - 4, 0):r + 5, max(c - 4, 0):c + 5].any())
    assert len(hits) > 10 and np.mean(hits) > 0.9
    assert magenta.mean() < 0.05  # the path's colour is the path's, not the cells'
