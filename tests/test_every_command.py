"""Every command on a 2D and a 3D map: each runs, or refuses in one line where it has no
meaning (scan matching a 2D map). And the help a user reads first."""

from __future__ import annotations

import json
import sqlite3

import pytest

from planner.cli import build_parser, main
from planner.export.arena import write_arena_db

# a quick query and cell size per map kind
MAPS = {
    "floorplan": (["--start", "1,1", "--goal", "3,1"], ["--cell-volume", "0.01"], "square"),
    "office": (["--start", "2.5,2.5,1.2", "--goal", "4.5,2.5,1.2"],
               ["--cell-volume", "0.01", "--radius", "0.1"], "cubic"),
}


def _suite(folder, name: str, lattices: list[str], extra: list[str]) -> str:
    cv = extra[extra.index("--cell-volume") + 1]
    radius = extra[extra.index("--radius") + 1] if "--radius" in extra else "0.2"
    path = folder / "s.toml"
    path.write_text(f'name = "s"\nqueries = 1\nlattices = {json.dumps(lattices)}\n'
                    'neighbors = ["full"]\nmethods = ["astar"]\nmin_distance = 0.1\n'
                    'rotation = "yaw"\nrotations = 2\n'
                    f'[[maps]]\npath = "{name}"\ncell_volumes = [{cv}]\nradii = [{radius}]\n')
    return str(path)


@pytest.mark.parametrize("name", list(MAPS))
def test_every_command_runs_on_a_2d_and_a_3d_map(name, tmp_path, capsys):
    ends, world_opts, ref = MAPS[name]
    lattices = ["square", "hex2d"] if name == "floorplan" else ["cubic", "fcc"]
    w = str(tmp_path / "w.npz")
    runs = [
        ["plan", name, *ends, *world_opts, "--out", str(tmp_path / "p.json"),
         "--view", str(tmp_path / "p.html"), "--plot", str(tmp_path / "p.png")],
        ["compare", name, *ends, *world_opts],  # every lattice of the map's dimension
        ["world", name, *world_opts, "--out", w],
        ["plan", w, *ends],
        ["view", name, *world_opts, "--path", str(tmp_path / "p.json"),
         "--out", str(tmp_path / "v.html")],
        ["explore", name, *ends, *world_opts, "--sensor-range", "2", "--resolution", "10"],
        ["bench", _suite(tmp_path, name, lattices, world_opts), "--out",
         str(tmp_path / "b"), "--no-progress"],
    ]
    for argv in runs:
        assert main(argv) == 0, argv
        out = capsys.readouterr().out
        if argv[0] == "compare":  # ratios against the dimension's reference lattice
            assert f"vs {ref}" in out and ("vs cubic" in out) == (ref == "cubic")
            assert ("hex2d" in out) == (name == "floorplan")
    rows = [json.loads(x) for x in (tmp_path / "b" / "results.jsonl").read_text().split("\n")
            if x]
    assert {r["lattice"] for r in rows} == set(lattices) and all(r["found"] for r in rows)


def test_matching_a_2d_map_is_refused_in_one_line(capsys):
    assert main(["match", "floorplan", "floorplan"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "3D" in err[0]


def test_help_names_the_2d_map_and_tum_stamps():
    text = " ".join(build_parser()._subparsers._group_actions[0].choices["plan"]
                    .format_help().split())
    assert "2D: floorplan" in text
    assert "arc length to it at 1 m/s" in text


def test_a_point_on_a_2d_map_asks_for_two_numbers(capsys):
    with pytest.raises(SystemExit) as e:
        main(["plan", "floorplan", "--start", "2", "3", "--goal", "5,5"])
    err = capsys.readouterr().err
    assert e.value.code == 2 and "two finite numbers x,y" in err and "three" not in err
    with pytest.raises(SystemExit):
        main(["plan", "office", "--start", "2", "3", "--goal", "5,5,1"])
    assert "three finite numbers x,y,z" in capsys.readouterr().err


def test_planner_arena_records_the_ompl_time_limit(tmp_path):
    base = {"map": "office.ply", "cell_volume": 0.01, "radius": 0.1, "rotation": 0,
            "found": True, "seconds": 0.1, "length": 3.0, "cell_checks": 5, "expansions": 2}
    rows = [{**base, "lattice": "cubic", "neighbors": "full", "method": "astar"},
            {**base, "lattice": "cubic", "neighbors": "-", "method": "ompl:rrtconnect",
             "time_limit": 0.5}]
    for got, want in ((rows, 0.5), (rows[:1], 0.0)):
        out = tmp_path / f"{want}.db"
        write_arena_db(out, got)
        con = sqlite3.connect(out)
        try:
            assert con.execute("SELECT timelimit FROM experiments").fetchone()[0] == want
        finally:
            con.close()
