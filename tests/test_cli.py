"""The command line as a user meets it: one-line errors with exit 2, negative coordinates,
custom lattices, shared defaults, outputs refused before any work, and a benchmark run that
stops cleanly on Ctrl-C or SIGTERM."""

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import psutil
import pytest

from planner.maps import map_path

ROOT = Path(__file__).resolve().parents[1]
OFFICE = str(map_path("office"))
# coarse and quick: a path exists on the office map at this cell volume
FAST = ["--cell-volume", "0.01", "--radius", "0.1"]


def planner(*args, cwd=None, timeout=120):
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    return subprocess.run([sys.executable, "-m", "planner", *args], capture_output=True,
                          text=True, cwd=cwd, env=env, timeout=timeout)


def one_line_error(r, *needles):
    assert r.returncode == 2, (r.returncode, r.stdout, r.stderr)
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1, r.stderr
    assert "Traceback" not in r.stderr
    for n in needles:
        assert n in lines[0], lines[0]
    return lines[0]


def test_help_shows_every_default():
    for cmd in ("plan", "compare", "world", "lattices", "stats", "bench"):
        r = planner(cmd, "--help")
        assert r.returncode == 0
        text = " ".join(r.stdout.split())
        assert "(default:" in text, cmd
    text = " ".join(planner("plan", "--help").stdout.split())
    for default in ("not given: fcc", "(default: astar)", "(default: full)", "(default: 1.0)"):
        assert default in text


@pytest.mark.slow
def test_negative_coordinates_work_as_typed(tmp_path):
    # the office spans x 0..20: a negative start is parsed, then refused as outside the map
    for args in (["--start", "-2.96,-0.05,1"], ["--start=-2.96,-0.05,1"]):
        r = planner("plan", "office", *args, "--goal", "2,2,1", *FAST)
        line = one_line_error(r, "outside")
        assert "-2.96" in line and "expected one argument" not in line


def test_bundled_map_by_name_from_another_folder(tmp_path):
    r = planner("plan", "office", "--start", "2,2,1", "--goal", "18,10,1", *FAST,
                "--out", "p.json", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    saved = json.loads((tmp_path / "p.json").read_text())
    assert saved["found"] and len(saved["path"]) > 1


@pytest.mark.slow
def test_custom_generator_as_text_and_npy(tmp_path):
    g = np.diag([0.2, 0.2, 0.25])
    np.save(tmp_path / "g.npy", g)
    common = ["plan", "office", "--start", "2,2,1", "--goal", "18,10,1", "--radius", "0.1"]
    a = planner(*common, "--generator", "0.2,0,0;0,0.2,0;0,0,0.25", "--json")
    b = planner(*common, "--generator", str(tmp_path / "g.npy"), "--json")
    assert a.returncode == b.returncode == 0, a.stderr + b.stderr
    ra, rb = json.loads(a.stdout), json.loads(b.stdout)
    assert ra["cell_volume"] == pytest.approx(0.01) and ra["length"] == rb["length"]
    one_line_error(planner(*common, "--generator", "1,0;0,1,0;0,0,1"), "generator")
    one_line_error(planner(*common, "--generator", "1,0,0;0,1,0;0,0,0"), "singular")


def test_plan_and_compare_share_the_maps_radius(tmp_path):
    plan = planner("plan", "office", "--start", "2,2,1.2", "--goal", "18,10,1.2",
                   "--cell-volume", "0.008", "--lattice", "cubic", "--json")
    comp = planner("compare", "office", "--start", "2,2,1.2", "--goal", "18,10,1.2",
                   "--cell-volume", "0.008", "--lattices", "cubic", "--json")
    assert plan.returncode == comp.returncode == 0, plan.stderr + comp.stderr
    p, (c,) = json.loads(plan.stdout), json.loads(comp.stdout)
    assert p["length"] == pytest.approx(c["length"])  # same radius (the map's 0.25 m)
    assert p["cell_checks"] == c["cell_checks"]


def test_a_map_without_a_radius_needs_one(tmp_path):
    pts = np.random.default_rng(0).uniform(0, 5, (500, 3))
    np.save(tmp_path / "m.npy", pts)
    r = planner("plan", str(tmp_path / "m.npy"), "--start", "1,1,1", "--goal", "4,4,4")
    one_line_error(r, "--radius")


@pytest.mark.parametrize("target, why", [
    ("/proc/p.json", "cannot write"),
    ("{file}/p.json", "not a directory"),
    ("{dir}.json", "is a directory"),
])
def test_outputs_that_cannot_be_written_are_refused_first(tmp_path, target, why):
    f = tmp_path / "regular"
    f.write_text("x")
    for suffix in (".json", ".npz", ".png"):
        (tmp_path / f"d{suffix}").mkdir()
    out = target.format(file=f, dir=tmp_path / "d")
    r = planner("plan", "office", "--start", "2,2,1", "--goal", "18,10,1", *FAST, "--out", out)
    one_line_error(r, "--out", why)
    r = planner("world", "office", *FAST, "--out", out.replace(".json", ".npz"))
    one_line_error(r, "--out", why)
    r = planner("compare", "office", *FAST, "--plot", out.replace(".json", ".png"))
    one_line_error(r, "--plot", why)


def test_plot_with_an_unknown_suffix_is_refused_before_any_work(tmp_path):
    r = planner("plan", "office", "--start", "2,2,1", "--goal", "18,10,1", *FAST,
                "--plot", str(tmp_path / "p.xyz"), "--out", str(tmp_path / "p.json"))
    one_line_error(r, "--plot", ".xyz")
    assert list(tmp_path.iterdir()) == []  # nothing written


@pytest.mark.slow
def test_missing_output_folders_are_created_alike(tmp_path):
    r = planner("world", "office", *FAST, "--out", str(tmp_path / "a" / "b" / "v.npz"))
    assert r.returncode == 0, r.stderr
    r = planner("plan", "office", "--start", "2,2,1", "--goal", "18,10,1", *FAST,
                "--out", str(tmp_path / "c" / "d" / "p.csv"))
    assert r.returncode == 0, r.stderr
    assert (tmp_path / "a" / "b" / "v.npz").is_file() and (tmp_path / "c/d/p.csv").is_file()


@pytest.mark.parametrize("args, needle", [
    (["compare", "office", "--lattices", ""], "--lattices"),
    (["compare", "office", "--lattices", "fcc,diamond"], "diamond"),
    (["lattices", "--points", "0"], "--points"),
    (["lattices", "--points", "-1"], "--points"),
    (["plan", "office", "--start", "1,2", "--goal", "2,2,1"], "--start"),
    (["plan", "office", "--start", "2,2,1", "--goal", "18,10,1", "--seed", "-5"], "--seed"),
    (["plan", "office", "--start", "2,2,1", "--goal", "18,10,1", "--seed", str(2**70)],
     "--seed"),
    (["bench", "quick", "--jobs", "0"], "--jobs"),
    (["bench", "no_such_suite"], "no such suite"),
])
def test_bad_arguments_are_one_line_errors(args, needle):
    one_line_error(planner(*args), needle)


@pytest.mark.slow
def test_numpy_warnings_do_not_precede_the_error_line(tmp_path):
    # a degenerate cloud (all points on one plane) makes numpy warn on the way to an error
    pts = np.zeros((50, 3))
    pts[:, :2] = np.random.default_rng(1).uniform(0, 1, (50, 2))
    np.save(tmp_path / "flat.npy", pts)
    r = planner("plan", str(tmp_path / "flat.npy"), "--radius", "0.1", "--start", "0.5,0.5,0",
                "--goal", "9,9,9")
    assert r.returncode in (1, 2)
    if r.returncode == 2:
        one_line_error(r)
    assert "RuntimeWarning" not in r.stderr


# -- bench: interrupts, locks, resume ---------------------------------------------------
SUITE = """
name = "slow"
seed = 2
queries = 16
lattices = ["cubic", "bcc", "fcc", "mcc", "hex"]
neighbors = ["face", "full"]
methods = ["astar", "dijkstra"]
min_distance = 0.3

[[maps]]
path = "office"
cell_volumes = [0.004]
radii = [0.25]
"""


OMPL_ONLY = SUITE.replace('methods = ["astar", "dijkstra"]', "methods = []") + """
[ompl]
planners = ["rrtstar"]
time = 3.0
"""


def _start_bench(tmp_path, jobs, suite=SUITE):
    (tmp_path / "slow.toml").write_text(suite)
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    return subprocess.Popen(
        [sys.executable, "-m", "planner", "bench", str(tmp_path / "slow.toml"), "--out",
         str(tmp_path / "out"), "--jobs", str(jobs)],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)


def _wait_for_rows(proc, results, n=1, timeout=240):
    t0 = time.monotonic()
    while time.monotonic() - t0 < timeout:
        if results.is_file() and len(results.read_text().splitlines()) >= n:
            return
        if proc.poll() is not None:
            raise AssertionError(f"bench ended early: {proc.communicate()}")
        time.sleep(0.2)
    raise AssertionError("no finished row appeared")


@pytest.mark.parametrize("sig, code, jobs, suite", [
    (signal.SIGINT, 130, 2, SUITE),
    (signal.SIGTERM, 143, 1, SUITE),
    (signal.SIGTERM, 143, 2, SUITE),
    (signal.SIGINT, 130, 2, OMPL_ONLY),  # workers with OMPL worker processes of their own
])
@pytest.mark.slow
def test_bench_stops_cleanly_on_a_signal(tmp_path, sig, code, jobs, suite):
    proc = _start_bench(tmp_path, jobs, suite)
    results = tmp_path / "out" / "results.jsonl"
    _wait_for_rows(proc, results)
    children = psutil.Process(proc.pid).children(recursive=True)
    if suite is OMPL_ONLY:
        assert any(c.parent() and c.parent().pid != proc.pid for c in children)  # grandchildren
    proc.send_signal(sig)
    try:
        out, err = proc.communicate(timeout=15)  # generous: the machine is shared
    except subprocess.TimeoutExpired:
        proc.kill()
        raise
    assert proc.returncode == code, err
    assert "Traceback" not in err
    deadline = time.monotonic() + 5
    while time.monotonic() < deadline and any(
            c.is_running() and c.status() != psutil.STATUS_ZOMBIE for c in children):
        time.sleep(0.1)
    alive = [c.pid for c in children if c.is_running() and c.status() != psutil.STATUS_ZOMBIE]
    assert not alive, f"children left running: {alive}"
    report = (tmp_path / "out" / "report.md").read_text()
    assert "PARTIAL" in report.splitlines()[0]
    rows = [json.loads(line) for line in results.read_text().splitlines()]
    assert rows and all("found" in r for r in rows)  # only whole rows


@pytest.mark.slow
def test_second_run_on_one_folder_is_refused_and_resume_reuses_queries(tmp_path):
    proc = _start_bench(tmp_path, 1)
    try:
        _wait_for_rows(proc, tmp_path / "out" / "results.jsonl")
        r = planner("bench", str(tmp_path / "slow.toml"), "--out", str(tmp_path / "out"),
                    "--resume")
        one_line_error(r, "in use")
    finally:
        proc.send_signal(signal.SIGINT)
        proc.communicate(timeout=30)
    saved = json.loads((tmp_path / "out" / "queries.json").read_text())
    (group,) = saved.values()
    assert len(group["queries"]) == 16
    # resume: no new sampling (the log says so) and the same queries
    r = planner("bench", str(tmp_path / "slow.toml"), "--out", str(tmp_path / "out"),
                "--resume", "--report-only")
    assert r.returncode == 0, r.stderr
    assert "sampling" not in r.stderr
    assert json.loads((tmp_path / "out" / "queries.json").read_text()) == saved


@pytest.mark.slow
def test_compare_includes_a_custom_generator_at_the_common_cell_volume():
    r = planner("compare", "office", "--lattices", "cubic", "--generator",
                "1,0,0;0,1,0;0,0,1", *FAST, "--json")
    assert r.returncode == 0, r.stderr
    cubic, custom = json.loads(r.stdout)
    assert custom["lattice"] == "custom"
    assert custom["cell_volume"] == pytest.approx(0.01)
    assert custom["length"] == pytest.approx(cubic["length"])  # the same lattice
