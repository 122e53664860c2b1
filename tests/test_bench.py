"""The benchmark suite: runs are resumable, identical across executors, and every path
that is reported found keeps the robot clearance against the raw obstacles."""

import json
import math
import os
import signal
import threading

import numpy as np
import pytest

import planner
from planner.bench import rows as rows_mod
from planner.bench import runner, summary
from planner.bench import tasks as tasks_mod
from planner.bench.metrics import Clearance
from planner.bench.stopping import Interrupted, signals_raise
from planner.bench.suite import SuiteError, load_suite
from planner.maps import map_path

SUITE = """
name = "tiny"
seed = 3
queries = 3
lattices = ["cubic", "fcc"]
neighbors = ["face"]
methods = ["astar", "theta"]
min_distance = 0.2

[[maps]]
path = "{map}"
cell_volumes = [0.03]
radii = [0.2]
"""


@pytest.fixture(scope="module")
def tiny_suite(tmp_path_factory):
    d = tmp_path_factory.mktemp("suite")
    p = d / "tiny.toml"
    p.write_text(SUITE.format(map=map_path("office").as_posix()))
    return load_suite(str(p))


@pytest.fixture(scope="module")
def tiny_tasks(tiny_suite):
    return tasks_mod.plan_tasks(tiny_suite, log=lambda m: None)


def _stable(rows):
    """Everything but timings and the Dask worker's address."""
    return sorted(json.dumps({k: v for k, v in r.items() if k != "worker"
                              and not k.endswith("seconds")}, sort_keys=True) for r in rows)


def test_queries_are_shared_by_every_lattice_and_method(tiny_tasks):
    tasks, record = tiny_tasks
    (group,) = record.values()
    assert group["kept"] == 3
    per = {}
    for t in tasks:
        per.setdefault((t["lattice"], t["method"]), []).extend(
            (q["start"], q["goal"]) for q in t["queries"])
    first = next(iter(per.values()))
    assert all(v == first for v in per.values())


def test_a_killed_run_resumes_without_redoing_finished_rows(tiny_tasks, tmp_path):
    tasks, _ = tiny_tasks
    out = tmp_path / "results.jsonl"
    rows = runner.run(tasks[:2], out, progress=False)
    n_first = len(rows)
    with open(out, "a") as f:  # a row cut short by a kill
        f.write('{"map": "trunc')
    rows = runner.run(tasks, out, resume=True, progress=False)
    keys = [rows_mod.row_key(r) for r in rows]
    assert len(keys) == len(set(keys)) == sum(len(t["queries"]) for t in tasks)
    assert n_first > 0
    for r in rows:
        if r["found"]:
            assert r["collision_free"], r
            assert r["clearance"] >= 0.2 - 1e-9
            assert r["length_smoothed"] <= r["length"] + 1e-9


@pytest.mark.slow
def test_results_are_identical_in_processes_and_on_a_dask_cluster(tiny_tasks, tmp_path):
    distributed = pytest.importorskip("distributed")
    tasks, _ = tiny_tasks
    tasks = [t for t in tasks if t["method"] == "astar"]
    serial = runner.run(tasks, tmp_path / "a.jsonl", progress=False)
    pool = runner.run(tasks, tmp_path / "b.jsonl", jobs=2, progress=False)
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=True,
                                  protocol="tcp", dashboard_address=None) as cluster:
        dask_rows = runner.run(tasks, tmp_path / "c.jsonl", scheduler=cluster.scheduler_address,
                               progress=False)
        workers = set(cluster.scheduler_info["workers"])  # their addresses
    assert _stable(serial) == _stable(pool) == _stable(dask_rows)
    # every row names the machine that ran it; a Dask row also the worker
    import socket

    assert {r["host"] for r in serial + pool + dask_rows} == {socket.gethostname()}
    assert {r["worker"] for r in serial + pool} == {None}
    assert {r["worker"] for r in dask_rows} == workers


@pytest.mark.slow
def test_summary_report_and_figures(tiny_tasks, tiny_suite, tmp_path):
    tasks, record = tiny_tasks
    rows = runner.run(tasks, tmp_path / "r.jsonl", progress=False)
    summ = summary.summarize(rows)
    labels = {(s["lattice"], s["method"]) for s in summ}
    assert labels == {(lat, m) for lat in ("cubic", "fcc") for m in ("astar", "theta")}
    for s in summ:
        if s["lattice"] == "cubic":
            assert s["cell_checks_vs_cubic"] == pytest.approx(1.0)
        if s["success"] > 0:
            assert s["length_ratio_median"] >= 1.0 - 1e-9
    figs = summary.plot(rows, tmp_path)
    rep = summary.write_report(tmp_path, tiny_suite, rows, summ, record, figs, "planner bench x")
    text = rep.read_text()
    for f in figs:
        assert f.stat().st_size > 5000
        assert f"]({f.name})" in text


@pytest.mark.slow
def test_clearance_is_exact_against_brute_force():
    rng = np.random.default_rng(0)
    pts = rng.uniform(0, 10, (400, 3))
    boxes = rng.integers(0, 10, (30, 3)).astype(float)
    c = Clearance(pts, boxes, 0.6)
    path = rng.uniform(0, 10, (4, 3))
    t = np.linspace(0, 1, 20001)[:, None]
    s = np.concatenate([a + t * (b - a) for a, b in zip(path[:-1], path[1:], strict=True)])
    d_pts = np.min(np.linalg.norm(s[:, None] - pts[None], axis=2))
    d_box = np.min(np.linalg.norm(np.maximum(np.abs(s[:, None] - boxes[None]) - 0.3, 0), axis=2))
    assert c.of_path(path, 0.3) == pytest.approx(min(d_pts, d_box), abs=1e-6)


@pytest.mark.parametrize("text, match", [
    ("lattices = ['diamond']\n", "diamond"),
    ("this is = = not toml", "TOML"),
    ('methods = ["astra"]\n[[maps]]\npath = "office"\ncell_volumes = [0.01]\n', "astra"),
    ('[ompl]\nplanners = ["rrtfast"]\n', "rrtfast"),
])
def test_bad_suites_are_refused_when_read(tmp_path, text, match):
    bad = tmp_path / "bad.toml"
    bad.write_text(text)
    with pytest.raises(SuiteError, match=match):
        load_suite(str(bad))


def test_unknown_suite_names_list_the_bundled_ones():
    with pytest.raises(SuiteError, match="no such suite.*quick"):
        load_suite("nonexistent")


@pytest.mark.slow
def test_bundled_suites_load():
    for name in ("quick", "paper", "full"):
        s = load_suite(name)
        assert s.name == name
    assert math.isfinite(load_suite("quick").ompl_time)


def test_duplicate_rows_are_counted_once(tiny_tasks, tmp_path):
    tasks, _ = tiny_tasks
    rows = runner.run(tasks[:2], tmp_path / "r.jsonl", progress=False)
    once = summary.summarize([dict(r) for r in rows])
    twice = summary.summarize([dict(r) for r in rows + rows])
    assert [s["runs"] for s in once] == [s["runs"] for s in twice]


def test_a_report_of_a_partial_run_says_so(tiny_tasks, tiny_suite, tmp_path):
    tasks, record = tiny_tasks
    rows = runner.run(tasks[:1], tmp_path / "r.jsonl", progress=False)
    rep = summary.write_report(tmp_path, tiny_suite, rows, summary.summarize(rows), record, [],
                               "planner bench x", partial="interrupted by SIGINT: 3 of 36 runs")
    text = rep.read_text()
    assert "(PARTIAL)" in text.splitlines()[0] and "interrupted by SIGINT" in text
    assert "commit" in text and "CPU" in text and "jobs: 1" in text
    assert "| lattice |" in text and "```" not in text  # Markdown tables, not code blocks


def test_saved_queries_are_reused(tiny_suite):
    _, record = tasks_mod.plan_tasks(tiny_suite, log=lambda m: None)
    sampled = []
    tasks, again = tasks_mod.plan_tasks(tiny_suite, log=sampled.append, saved=record)
    assert again == record and not sampled
    assert {q["id"] for t in tasks for q in t["queries"]} == {0, 1, 2}


# -- rotations: the paper's fairness rule ---------------------------------------------------
ROTATED = SUITE.replace('min_distance = 0.2', 'min_distance = 0.2\nrotation = "yaw"\nrotations = 2')


def test_rotating_by_the_identity_gives_the_unrotated_world():
    from planner import build_world
    from planner.bench.worlds import rotated_world

    p = str(map_path("office"))
    for lat in ("cubic", "fcc"):
        plain = build_world(p, lat, cell_volume=0.03, radius=0.2)
        turned = rotated_world(p, lat, 0.03, 0.2, [0.0, 0.0, 0.0, 1.0])  # x, y, z, w
        assert np.allclose(plain.bounds, turned.bounds)
        assert {tuple(c) for c in plain.blocked} == {tuple(c) for c in turned.blocked}


@pytest.mark.slow
@pytest.mark.parametrize("name", ["cubic", "bcc", "fcc", "mcc", "hex"])
def test_turning_the_lattice_blocks_the_cells_turning_the_map_blocks(name):
    # The rotated world's premise: cell w of lattice G is within r of the turned points R p
    # exactly when cell w of lattice R^T G is within r of p.
    from scipy.spatial.transform import Rotation

    from planner import Lattice
    from planner.bench.rotations import sample_rotations
    from planner.bench.worlds import rotated_lattice
    from planner.voxels import exact_inflation

    pts = np.random.default_rng(3).uniform(-2, 2, (300, 3))
    for q in sample_rotations("so3", 3, seed=1):
        R = Rotation.from_quat(q).as_matrix()
        lat = Lattice.named(name, 0.05)
        turned_map = exact_inflation(pts @ R.T, lat, 0.21)
        turned_lattice = exact_inflation(pts, rotated_lattice(name, 0.05, q), 0.21)
        assert np.array_equal(np.sort(turned_map.keys), np.sort(turned_lattice.keys))


def test_a_rotated_world_keeps_the_map_box_and_its_corridor():
    from planner.bench.worlds import rotated_world

    p = str(map_path("office"))
    q = [0.0, 0.0, np.sin(np.pi / 8), np.cos(np.pi / 8)]  # 45 degrees about z (x, y, z, w)
    plain = rotated_world(p, "bcc", 0.03, 0.2, [0.0, 0.0, 0.0, 1.0])
    w = rotated_world(p, "bcc", 0.03, 0.2, q)
    assert np.allclose(w.bounds, plain.bounds)
    assert w.points_free(np.array([[10.0, 6.0, 1.5]]))[0]  # the corridor
    assert not w.points_free(np.array([w.bounds[1] + 0.1]))[0]  # outside the map box


@pytest.mark.slow
def test_rotated_suites_share_one_rotation_sample_and_record_it(tmp_path):

    p = tmp_path / "rot.toml"
    p.write_text(ROTATED.format(map=map_path("office").as_posix()))
    suite = load_suite(str(p))
    assert (suite.rotation, suite.rotations) == ("yaw", 2)
    tasks, record = tasks_mod.plan_tasks(suite, log=lambda m: None)
    assert len(record) == 2
    quats = {t["rotation"]: tuple(t["quaternion_xyzw"]) for t in tasks}
    assert sorted(quats) == [0, 1] and quats[0] != quats[1]
    for t in tasks:  # every lattice and method of a rotation sees the same rotation
        assert tuple(t["quaternion_xyzw"]) == quats[t["rotation"]]
    from planner.bench.worlds import map_frame

    frame = map_frame(str(map_path("office")))
    for rec in record.values():  # queries (and worlds) are in the map's own frame
        pts = np.array([q["start"] for q in rec["queries"]] + [q["goal"] for q in rec["queries"]])
        assert np.all(pts >= frame.bounds[0]) and np.all(pts <= frame.bounds[1])
    rows = runner.run(tasks, tmp_path / "results.jsonl", progress=False)
    assert {r["rotation"] for r in rows} == {0, 1}
    assert all(len(r["quaternion_xyzw"]) == 4 for r in rows)
    assert all(r["commit"] for r in rows)  # the code that ran each row
    assert len({rows_mod.row_key(r) for r in rows}) == len(rows)
    for r in rows:
        if r["found"]:
            assert r["collision_free"], r


def test_bad_rotation_keys_are_one_line_errors(tmp_path):
    p = tmp_path / "bad.toml"
    p.write_text(ROTATED.format(map=map_path("office").as_posix()).replace('"yaw"', '"roll"'))
    with pytest.raises(SuiteError, match="rotation must be one of"):
        load_suite(str(p))


def test_queries_are_sampled_in_observed_free_space_only():
    from planner import build_world
    from planner.bench.queries import sample_queries

    class Observed:  # free space observed only at x < 10 m (and a little past the box)
        def sample(self, rng, n):
            return rng.uniform([0.0, 0.0, 0.0], [10.0, 8.2, 3.0], (n, 3))

    p = str(map_path("office"))
    w = build_world(p, "cubic", cell_volume=0.03, radius=0.2)
    s, g, dropped = sample_queries({"cubic": w}, w.bounds, 5, seed=0, min_distance=0.1,
                                   free=Observed())
    assert len(s) == 5
    assert np.all(s[:, 0] < 10.0) and np.all(g[:, 0] < 10.0)
    assert np.all(s >= w.bounds[0]) and np.all(g <= w.bounds[1])


def test_queries_no_lattice_connects_are_dropped():
    from planner import build_world
    from planner.bench.queries import sample_queries

    # a wall across the whole box at x = 2 m seals the two halves from each other
    y, z = np.meshgrid(np.arange(0.0, 2.01, 0.05), np.arange(0.0, 1.01, 0.05))
    wall = np.stack([np.full(y.size, 2.0), y.ravel(), z.ravel()], axis=1)
    box = np.array([[0.0, 0.0, 0.0], [4.0, 2.0, 1.0]])
    worlds = {lat: build_world(wall, lat, cell_volume=0.001, radius=0.0, bounds=box)
              for lat in ("cubic", "fcc")}
    s, g, dropped = sample_queries(worlds, box, 8, seed=0, min_distance=0.2)
    assert len(s) == 8
    assert np.all((s[:, 0] < 2.0) == (g[:, 0] < 2.0))  # each pair on one side
    assert dropped["start and goal connected in no lattice"] > 0
    s, g, dropped = sample_queries(worlds, box, 8, seed=0, min_distance=0.2, neighbors=None)
    assert np.any((s[:, 0] < 2.0) != (g[:, 0] < 2.0))  # unchecked: some pairs straddle it
    assert "start and goal connected in no lattice" not in dropped


def _rows(ratio_fcc: float, n: int = 30, seed: int = 0) -> list[dict]:
    rng = np.random.default_rng(seed)
    rows = []
    for q in range(n):
        c = float(rng.uniform(1000, 2000))
        for lat, k in (("cubic", 1.0), ("fcc", ratio_fcc * rng.uniform(0.9, 1.1))):
            rows.append({"map": "m", "cell_volume": 1.0, "radius": 0.0, "rotation": q % 8,
                         "query": q, "lattice": lat, "neighbors": "full", "method": "astar",
                         "seed": 0, "found": True, "cell_checks": c * k, "length": 10.0,
                         "search_checks": 0.5 * c * k, "length_smoothed": 9.0,
                         "seconds": 0.01, "cpu_seconds": 0.01})
    return rows


def test_the_report_prose_comes_from_the_paired_statistics():
    from planner.bench import paired
    from planner.bench.orientation import rotation_spread

    table, prose = paired.paired_table(_rows(0.6))
    assert "fcc" in table and "cubic" not in table.split("\n")[2]
    assert prose[0].startswith("- **fcc full astar** vs cubic full astar")
    import re

    assert re.search(r"fewer cell checks \(search \+ smoothing\) \(Hodges-Lehmann ratio "
                     r"0\.[56]\d* \[[\d.]+, [\d.]+\], p < 0\.001", prose[0]), prose[0]
    assert "no clear difference in raw (as searched) path length" in prose[0]
    assert "30 queries every lattice solved (delivered path: smoothed)" in prose[0]
    _, prose = paired.paired_table(_rows(1.0))
    assert "no clear difference in cell checks" in prose[0]
    spread, sentences = rotation_spread(_rows(0.6))
    assert "| m | fcc | full | astar | 8 |" in spread
    assert "orientation is not shown to matter" in sentences[0]


def test_failed_queries_count_in_success_not_in_ratios():
    from planner.bench import paired

    rows = _rows(0.5)
    for r in rows:
        if r["lattice"] == "fcc" and r["query"] < 4:
            r.update(found=False, length=None, length_smoothed=None)
    c = paired.compare_to_cubic(rows, "fcc", "full", "astar")
    assert c["success"]["cubic_only"] == 4 and c["success"]["x_only"] == 0
    assert c["cell_checks"].n == 26


def test_operating_points_compare_lattices_on_the_queries_all_solved():
    from planner.bench.figures import operating_points

    rows = _rows(0.5, n=10)
    for r in rows:
        r["cell_volume"] = 1.0
        if r["query"] < 3:
            r["cell_checks"] = 1e9  # hard queries
            if r["lattice"] == "cubic":
                r.update(found=False, length=None, length_smoothed=None)
    summary.add_ratios(rows)
    pts = {p["lattice"]: p for p in operating_points(rows)}
    assert pts["cubic"]["success"] == 0.7 and pts["fcc"]["success"] == 1.0
    assert pts["fcc"]["common_queries"] == pts["cubic"]["common_queries"] == 7
    assert pts["fcc"]["cell_checks"] < pts["cubic"]["cell_checks"] < 1e9


def test_a_cached_world_is_the_world_it_was_built_as(tmp_path):
    from planner.bench.worlds import cached_world

    p = str(map_path("office"))
    q = (np.cos(0.3), 0.0, 0.0, np.sin(0.3))
    built = cached_world(str(tmp_path), p, "fcc", 0.03, 0.2, q)
    loaded = cached_world(str(tmp_path), p, "fcc", 0.03, 0.2, q)
    assert loaded is not built and len(list(tmp_path.iterdir())) == 1
    assert {tuple(c) for c in built.blocked} == {tuple(c) for c in loaded.blocked}
    assert np.array_equal(built.lattice.generator, loaded.lattice.generator)
    assert np.allclose(built.bounds, loaded.bounds)


@pytest.mark.slow
def test_worlds_built_in_parallel_give_the_same_queries(tmp_path):
    p = tmp_path / "rot.toml"
    p.write_text(ROTATED.format(map=map_path("office").as_posix()))
    suite = load_suite(str(p))
    _, serial = tasks_mod.plan_tasks(suite, log=lambda m: None)
    _, parallel = tasks_mod.plan_tasks(suite, log=lambda m: None, jobs=2,
                                    world_cache=str(tmp_path / "worlds"))
    assert len(list((tmp_path / "worlds").iterdir())) == 2 * len(suite.lattices)
    assert json.dumps(serial, sort_keys=True) == json.dumps(parallel, sort_keys=True)


def test_rows_name_the_host_that_ran_them(tiny_tasks, tmp_path):
    import socket

    tasks, _ = tiny_tasks
    rows = runner.run(tasks[:1], tmp_path / "r.jsonl", progress=False)
    assert rows and all(r["host"] == socket.gethostname() and r["worker"] is None
                        for r in rows)


def test_a_signal_during_searches_stops_them_as_interrupted():
    # the handler raises wherever Python runs next, often inside a compiled search (numba
    # runs Python to box a new array); the run must still stop as Interrupted (exit 130/143)
    world = planner.build_world("office", "cubic")
    start, goal = (2.5, 2.5, 1.2), (3.5, 2.9, 1.2)
    for delay in (0.005, 0.01, 0.02, 0.03, 0.05):
        timer = threading.Timer(delay, os.kill, (os.getpid(), signal.SIGTERM))
        with pytest.raises(Interrupted), signals_raise():
            timer.start()
            for _ in range(100_000):
                planner.plan(world, start, goal)
        timer.join()
