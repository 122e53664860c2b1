"""Readers refuse before they allocate: YAML aliases, map images and text numbers against
the memory budget, data after a complete PGM or PNG, generator files that are not a real,
finite 2x2 or 3x3 matrix. Each is one line."""

from __future__ import annotations

import io

import numpy as np
import pytest

from planner.cli import main
from planner.errors import MapError
from planner.io import load_obstacles

MAP = ("image: {img}\nresolution: 0.05\norigin: [0, 0, 0]\nnegate: 0\n"
       "occupied_thresh: 0.65\nfree_thresh: 0.196\n")
PGM = b"P5\n4 4\n255\n" + bytes([254] * 16)


def test_a_yaml_alias_bomb_is_refused_before_it_is_built(tmp_path):
    (tmp_path / "m.pgm").write_bytes(PGM)
    lol = "a0: &a0 [x, x, x, x, x, x, x, x, x]\n" + "".join(
        f"a{i + 1}: &a{i + 1} [{', '.join([f'*a{i}'] * 9)}]\n" for i in range(9))
    (tmp_path / "m.yaml").write_text(lol + MAP.format(img="m.pgm"))
    with pytest.raises(MapError, match="aliases"):
        load_obstacles(tmp_path / "m.yaml")
    (tmp_path / "ok.yaml").write_text("shared: &s [0, 0, 0]\n" + MAP.format(img="m.pgm"))
    assert len(load_obstacles(tmp_path / "ok.yaml").free_boxes) == 16  # a few aliases: fine


@pytest.mark.parametrize("ext", ["pgm", "png"])
def test_data_after_a_map_image_is_refused(tmp_path, ext):
    if ext == "pgm":
        data = PGM
    else:
        from PIL import Image

        buf = io.BytesIO()
        Image.fromarray(np.full((4, 4), 254, np.uint8)).save(buf, format="PNG")
        data = buf.getvalue()
    (tmp_path / f"m.{ext}").write_bytes(data)
    (tmp_path / "m.yaml").write_text(MAP.format(img=f"m.{ext}"))
    assert len(load_obstacles(tmp_path / "m.yaml").free_boxes) == 16
    (tmp_path / f"m.{ext}").write_bytes(data + b"more")
    with pytest.raises(MapError, match=f"4 bytes of data after the end of the {ext.upper()}"):
        load_obstacles(tmp_path / "m.yaml")


def test_a_map_image_over_the_budget_is_refused_from_its_header(tmp_path, monkeypatch):
    (tmp_path / "m.pgm").write_bytes(b"P5\n6000 6000\n255\n" + bytes(6000 * 6000))
    (tmp_path / "m.yaml").write_text(MAP.format(img="m.pgm"))
    monkeypatch.setenv("PLANNER_MEMORY_BUDGET", "1G")
    with pytest.raises(MapError, match=r"6000x6000 map image needs .* \(--memory-budget\)"):
        load_obstacles(tmp_path / "m.yaml")


def test_parsing_text_numbers_is_budgeted(tmp_path, monkeypatch):
    rng = np.random.default_rng(0)
    np.savetxt(tmp_path / "c.xyz", rng.uniform(0, 10, (200_000, 3)), fmt="%.4f")
    monkeypatch.setenv("PLANNER_MEMORY_BUDGET", "16M")
    with pytest.raises(MapError, match="parsing .* characters of numbers needs"):
        load_obstacles(tmp_path / "c.xyz")
    monkeypatch.setenv("PLANNER_MEMORY_BUDGET", "1G")
    assert load_obstacles(tmp_path / "c.xyz").points.shape == (200_000, 3)


@pytest.mark.parametrize("g, why", [
    (np.eye(3) + 0j, "real 2x2 or 3x3"), (np.array([["a"] * 3] * 3), "real 2x2 or 3x3"),
    (np.eye(4), "real 2x2 or 3x3"), (np.ones(9), "real 2x2 or 3x3"),
    (np.full((3, 3), np.nan), "finite"), (np.eye(3) * 1e300, "too large"),
])
def test_generator_files_are_real_finite_square_matrices(tmp_path, g, why, capsys):
    np.save(tmp_path / "g.npy", g)
    with pytest.raises(SystemExit) as got:  # an argument error: argparse exits with 2
        main(["plan", "office", "--start", "1,1,1", "--goal", "7.6,7.8,0.8", "--generator",
              str(tmp_path / "g.npy")])
    err = capsys.readouterr().err.strip().splitlines()
    assert got.value.code == 2 and len(err) == 1 and why in err[0], err


def test_a_generator_file_declaring_a_huge_shape_is_refused_by_the_budget(tmp_path, capsys):
    buf = io.BytesIO()
    np.save(buf, np.eye(3))
    (tmp_path / "g.npy").write_bytes(buf.getvalue().replace(b"(3, 3)", b"(3000000000, 3)"))
    with pytest.raises(SystemExit) as got:
        main(["plan", "office", "--start", "1,1,1", "--goal", "7.6,7.8,0.8", "--generator",
              str(tmp_path / "g.npy")])
    assert got.value.code == 2
    assert "over the memory budget" in capsys.readouterr().err
