"""What a new user meets on the command line: help that describes the software, every format
listed, required options marked as such, no duplicate commands."""

from __future__ import annotations

import pytest

from planner.cli import main


def _help(capsys, *argv: str) -> str:
    with pytest.raises(SystemExit) as info:
        main([*argv, "--help"])
    assert info.value.code == 0
    return " ".join(capsys.readouterr().out.split())


def test_top_level_help_describes_the_software_not_its_layout(capsys):
    text = _help(capsys)
    assert "argument parsing" not in text and "library modules" not in text
    assert "lattice" in text.lower()


@pytest.mark.parametrize("cmd", ["plan", "compare", "world", "explore"])
def test_map_help_lists_every_format_and_bundled_map(capsys, cmd):
    text = _help(capsys, cmd)
    for fmt in ("bag", "LAS/LAZ", "E57", "map_server YAML", ".npz", ".3dmap", "PCD", "PLY",
                ".bt", ".npy", "text", "office", "two_storey", "warehouse", "forest",
                "narrow_passage"):
        assert fmt in text, (cmd, fmt)
    for name in ("bag", "las", "e57", "rosmap", "3dmap", "pcd", "ply", "bt", "npy", "xyz"):
        assert f" {name}" in text.split("--format FORMAT", 2)[-1], (cmd, name)


@pytest.mark.parametrize("cmd", ["plan", "explore"])
def test_required_options_are_shown_as_required_without_a_none_default(capsys, cmd):
    text = _help(capsys, cmd)
    assert "(default: None)" not in text and "None:" not in text
    for opt in ("--start START", "--goal GOAL"):
        after = text.split(f"{opt} ", 2)[-1]  # the option's own help, after the usage line
        assert after.split("--")[0].rstrip().endswith("(required)"), (opt, after[:80])


def test_the_duplicate_voxels_command_is_gone(capsys):
    with pytest.raises(SystemExit) as info:
        main(["voxels", "office", "--out", "v.npz"])
    assert info.value.code == 2
    assert "invalid choice: 'voxels'" in capsys.readouterr().err
    assert "voxels" not in _help(capsys)


def test_plan_line_gives_the_cell_edge_and_says_when_unseen_space_counts_as_free(capsys):
    # office is a plain cloud: it records no observed free space.
    main(["plan", "office", "--start", "2,2,1", "--goal", "18,10,1", "--cell-volume", "0.01"])
    line, warning = capsys.readouterr().out.strip().splitlines()
    assert f"cell volume 0.01 m^3, edge {0.01 ** (1 / 3):.4g} m" in line
    assert warning.startswith("WARNING: no sensor origin: space the sensor never saw counts "
                              "as free") and "--origin" in warning


def test_rerunning_a_suite_into_a_folder_with_results_needs_resume_or_force(tmp_path, capsys):
    from planner.bench.run_folder import write_marker
    from planner.bench.suite import load_suite

    out = tmp_path / "out"
    out.mkdir()
    write_marker(out, load_suite("quick"))  # a run of the same suite left it
    row = '{"map": "office.ply", "found": true}\n'
    (out / "results.jsonl").write_text(row)
    assert main(["bench", "quick", "--out", str(out), "--no-progress"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "--resume" in err and "--force" in err
    assert (out / "results.jsonl").read_text() == row  # nothing replaced
