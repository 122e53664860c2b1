"""What a benchmark row charges: the search and the post-processing that produces the
delivered path, each counted and timed, and their sums."""

import pytest

from planner.bench import runner
from planner.bench import tasks as tasks_mod
from planner.bench.suite import load_suite
from planner.maps import map_path

SUITE = """
name = "cost"
seed = 5
queries = 3
lattices = ["cubic", "bcc"]
neighbors = ["face"]
methods = ["astar", "lazy-theta"]
min_distance = 0.3

[[maps]]
path = "{map}"
cell_volumes = [0.03]
radii = [0.2]
"""


@pytest.fixture(scope="module")
def cost_rows(tmp_path_factory):
    d = tmp_path_factory.mktemp("cost")
    p = d / "cost.toml"
    p.write_text(SUITE.format(map=map_path("office").as_posix()))
    tasks, _ = tasks_mod.plan_tasks(load_suite(str(p)), log=lambda m: None)
    return runner.run(tasks, d / "results.jsonl", progress=False)


def test_a_row_charges_search_and_smoothing_and_their_sums(cost_rows):
    found = [r for r in cost_rows if r["found"]]
    assert found
    for r in found:
        assert r["cell_checks"] == r["search_checks"] + r["smooth_checks"]
        assert r["seconds"] == pytest.approx(r["search_seconds"] + r["smooth_seconds"])
        assert r["cpu_seconds"] == pytest.approx(r["search_cpu_seconds"]
                                                 + r["smooth_cpu_seconds"])
        assert r["search_checks"] > 0 and r["search_seconds"] > 0
        if r["method"] == "astar":  # the delivered path is the shortcut one, and it cost
            assert r["delivered"] == "smoothed"
            assert r["smooth_checks"] > 0 and r["smooth_seconds"] > 0
            assert r["length_smoothed"] <= r["length"] + 1e-9
        else:  # an any-angle path is delivered as searched
            assert r["delivered"] == "raw"
            assert r["smooth_checks"] == 0 and r["smooth_seconds"] == 0.0
            assert r["length_smoothed"] == r["length"]


def test_a_row_delivers_the_path_plan_delivers(cost_rows, tmp_path):
    """The smoothed row is what ``planner.plan(..., shortcut=True)`` returns for the same
    query on the same world: its length, its raw length and its cell checks."""
    import planner
    from planner.bench.task import _world

    p = tmp_path / "cost.toml"
    p.write_text(SUITE.format(map=map_path("office").as_posix()))
    tasks, _ = tasks_mod.plan_tasks(load_suite(str(p)), log=lambda m: None)
    rows = {(r["lattice"], r["method"], r["query"]): r for r in cost_rows}
    compared = 0
    for t in tasks:
        if t["method"] != "astar":
            continue
        world = _world(t)
        for q in t["queries"]:
            r = rows[(t["lattice"], "astar", q["id"])]
            if not r["found"]:
                continue
            got = planner.plan(world, q["start"], q["goal"], neighbors=t["neighbors"],
                               shortcut=True)
            assert r["length_smoothed"] == pytest.approx(got.length, abs=1e-9)
            assert r["length"] == pytest.approx(got.extra["raw_length"], abs=1e-9)
            assert r["cell_checks"] == got.cell_checks
            compared += 1
    assert compared >= 3
