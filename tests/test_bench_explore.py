"""Exploration in the benchmark suite: ``methods = ["explore"]`` runs the robot on the
suite's maps and rotations, with the sensor of the ``[explore]`` table."""

import pytest

from planner.bench import rows as rows_mod
from planner.bench import runner, summary
from planner.bench import tasks as tasks_mod
from planner.bench.suite import SuiteError, load_suite
from planner.maps import map_path

SUITE = """
name = "tiny-explore"
seed = 1
queries = 2
lattices = ["cubic", "fcc"]
neighbors = ["full"]
methods = ["astar", "explore"]
min_distance = 0.3
rotation = "yaw"
rotations = 2

[explore]
sensor_range = 4.0
fov = [360.0, 40.0]
resolution = 6.0
max_steps = 3000

[[maps]]
path = "{map}"
cell_volumes = [0.01]
radii = [0.2]
"""


@pytest.mark.slow
def test_explore_rows_on_every_lattice_and_rotation(tmp_path):
    p = tmp_path / "tiny.toml"
    p.write_text(SUITE.format(map=map_path("office").as_posix()))
    suite = load_suite(str(p))
    assert suite.explore["sensor_range"] == 4.0
    tasks, record = tasks_mod.plan_tasks(suite, log=lambda m: None)
    rows = runner.run(tasks, tmp_path / "results.jsonl", progress=False)
    ex = [r for r in rows if r["method"] == "explore"]
    plans = [r for r in rows if r["method"] == "astar"]
    # one exploration per lattice x rotation x query, on the queries the planners get
    assert len(ex) == len(plans) == 2 * sum(g["kept"] for g in record.values()) > 0
    assert {(r["rotation"], r["query"], tuple(r["start"])) for r in ex} == {
        (r["rotation"], r["query"], tuple(r["start"])) for r in plans}
    assert {r["rotation"] for r in ex} == {0, 1}
    for r in ex:
        assert r["status"] in ("reached", "unreachable", "stuck", "budget"), r["reason"]
        assert r["mismatches"] == 0  # every repair costs what A* from scratch finds
        assert isinstance(r["contacts"], int)  # a sparse sensor may miss a thin obstacle
        assert r["replans"] >= 1 and r["moves"] >= 0
        assert r["replanner"] == "astar" and 1 <= r["searched"] <= r["replans"]
        assert r["length"] is None  # a travelled distance is not a planned path
        assert (r["distance"] > 0) == (r["moves"] > 0)
        if r["replans"] > 1:
            assert r["replan_checks_median"] >= 0 and r["median_checks_ratio"] is not None
    assert any(r["found"] for r in ex)
    # planning rows are what they were without exploration in the suite
    assert all("distance" not in r and "status" not in r for r in plans)
    assert len({rows_mod.row_key(r) for r in rows}) == len(rows)
    table = summary.format_summary(summary.summarize(rows))
    assert "explore" in table and "astar" in table


@pytest.mark.parametrize("table, match", [
    ("[explore]\nsensor_range = -1\n", "sensor_range"),
    ("[explore]\nfov = [400, 10]\n", "fov"),
    ("[explore]\nrange = 3\n", "unknown key 'range'"),
])
def test_bad_explore_tables_are_refused(tmp_path, table, match):
    p = tmp_path / "bad.toml"
    p.write_text(f'methods = ["explore"]\n{table}')
    with pytest.raises(SuiteError, match=match):
        load_suite(str(p))


def test_an_explore_table_without_the_method_is_refused(tmp_path):
    p = tmp_path / "bad.toml"
    p.write_text('methods = ["astar"]\n[explore]\nsensor_range = 3\n')
    with pytest.raises(SuiteError, match="needs \"explore\" in methods"):
        load_suite(str(p))
