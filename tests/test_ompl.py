"""OMPL baseline (planner.ompl): same world, same validity checker, guarded worker."""

from __future__ import annotations

import math
import multiprocessing
import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("ompl")

from planner import ompl as baseline  # noqa: E402
from planner import planning as api  # noqa: E402
from planner import search  # noqa: E402
from planner.errors import PlanError  # noqa: E402

RADIUS = 0.3
CELL = 0.2
START = (2.1, 8.1, 5.1)
GOAL = (7.9, 8.1, 5.1)


def _wall_points() -> np.ndarray:
    """Wall x = 5 over y, z in [0, 10] with a 2 x 2 m door (y, z in [4, 6])."""
    ys, zs = np.meshgrid(np.arange(0.0, 10.001, 0.05), np.arange(0.0, 10.001, 0.05))
    ys, zs = ys.ravel(), zs.ravel()
    keep = ~((ys > 4.0) & (ys < 6.0) & (zs > 4.0) & (zs < 6.0))
    return np.stack([np.full(keep.sum(), 5.0), ys[keep], zs[keep]], axis=1)


@pytest.fixture(scope="module")
def door():
    pts = _wall_points()
    w = api.build_world(pts, "cubic", cell_volume=CELL**3, radius=RADIUS,
                        bounds=[[0, 0, 0], [10, 10, 10]])
    return w, pts


@pytest.fixture(scope="module")
def rrtc(door):
    w, _ = door
    return baseline.plan_ompl(w, START, GOAL, planner="rrtconnect", time_limit=2.0, seed=1)


def _seg_point_dist(a: np.ndarray, b: np.ndarray, pts: np.ndarray) -> float:
    d = b - a
    t = np.clip((pts - a) @ d / max(float(d @ d), 1e-300), 0.0, 1.0)
    return float(np.linalg.norm(pts - (a + t[:, None] * d), axis=1).min())


def _length(p) -> float:
    p = np.asarray(p, float)
    return float(np.linalg.norm(np.diff(p, axis=0), axis=1).sum())


def test_rrtconnect_finds_collision_free_path(door, rrtc):
    w, pts = door
    r = rrtc
    assert r.found, r.reason
    assert r.reason == "" and r.status == "found"
    assert r.planner == "rrtconnect" and r.seed == 1
    assert r.cell_checks > 0 and r.checks_per_second > 0
    assert r.valid_raw is True
    for p in (r.path_raw, r.path_simplified):
        assert p.ndim == 2 and p.shape[1] == 3 and len(p) >= 2
        np.testing.assert_allclose(p[0], START)
        np.testing.assert_allclose(p[-1], GOAL)
        for a, b in zip(p[:-1], p[1:], strict=True):
            assert w.segment_free(a, b)
            assert _seg_point_dist(a, b, pts) >= RADIUS - 1e-9
    assert r.path is r.path_raw
    assert math.isclose(r.length_raw, _length(r.path_raw))
    assert math.isclose(r.length_simplified, _length(r.path_simplified))
    assert r.length == r.length_simplified
    assert r.time_to_first_solution is not None
    assert r.time_to_first_solution <= r.seconds
    d = r.to_dict()
    assert d["path_raw"] == r.path.tolist() and d["status"] == "found"


def test_simplified_length_close_to_theta_star(door, rrtc):
    w, _ = door
    lat = w.lattice
    cells = lat.quantize(np.array([START, GOAL]))
    res = search.search(w, cells[0], cells[1], method="theta")
    assert res.found
    theta = _length(np.concatenate([[START], lat.to_world(res.cells[1:-1]), [GOAL]]))
    got = rrtc.length_simplified
    assert got >= math.dist(START, GOAL)  # the wall forces a detour
    assert got <= 1.05 * theta, (got, theta)
    assert got >= 0.95 * theta, (got, theta)


def test_reproducible_for_same_seed(door, rrtc):
    w, _ = door
    again = baseline.plan_ompl(w, START, GOAL, planner="rrtconnect", time_limit=2.0, seed=1)
    assert again.found == rrtc.found
    # The exact validity checks make RRT-Connect deterministic given the seed: it stops at
    # its first solution, so the wall clock does not enter.
    np.testing.assert_allclose(again.path_raw, rrtc.path_raw)
    assert again.cell_checks == rrtc.cell_checks


def test_rrtstar_first_solution_and_budget(door):
    w, _ = door
    r = baseline.plan_ompl(w, START, GOAL, planner="rrtstar", time_limit=0.5, seed=0)
    assert r.found, r.reason
    assert r.planner == "rrtstar"
    assert 0 < r.time_to_first_solution <= r.seconds
    assert r.seconds >= 0.5  # anytime: keeps improving to the time limit
    assert r.cell_checks > 0
    assert r.final_cost == pytest.approx(r.length_raw)


def test_cell_check_budget(door):
    w, _ = door
    r = baseline.plan_ompl(w, START, GOAL, planner="rrtstar", time_limit=5.0, seed=0,
                           max_cell_checks=2000)
    # stopped by the budget, not the time limit (its 5 s make far more checks); one motion
    # check may run past it
    assert 2000 <= r.cell_checks < 3000
    if not r.found:
        assert "budget" in r.reason and r.status == "no path"


def test_prmstar_runs(door):
    w, _ = door
    r = baseline.plan_ompl(w, START, GOAL, planner="prm*", time_limit=0.5, seed=0)
    assert r.planner == "prmstar"
    assert r.found, r.reason
    assert r.time_to_first_solution <= r.seconds


def test_unknown_planner(door):
    w, _ = door
    with pytest.raises(PlanError, match="rrtconnect"):
        baseline.plan_ompl(w, START, GOAL, planner="nope")


def test_blocked_or_outside_endpoints(door):
    w, _ = door
    with pytest.raises(PlanError, match="start"):
        baseline.plan_ompl(w, (5.0, 1.0, 1.0), GOAL)
    with pytest.raises(PlanError, match="goal"):
        baseline.plan_ompl(w, START, (5.0, 9.0, 9.0))
    with pytest.raises(PlanError, match="outside"):
        baseline.plan_ompl(w, START, (11.0, 1.0, 1.0))


def test_timeout_kills_worker(door):
    w, _ = door
    r = baseline.plan_ompl(w, START, GOAL, planner="rrtstar", time_limit=60.0, timeout=0.5)
    assert r.found is False
    assert "timeout" in r.reason and r.status == "timeout"
    assert r.wall_seconds < 30  # killed, far from its time limit (a loaded machine spawns slowly)
    assert r.path.shape == (0, 3) and r.path_simplified is None


def test_run_seeds_and_api_route(door):
    w, _ = door
    rs = baseline.run_seeds(w, START, GOAL, [0, 1], planner="rrtconnect", time_limit=1.0)
    assert [r.seed for r in rs] == [0, 1] and all(r.found for r in rs)
    res = api.plan(w, START, GOAL, method="ompl:rrtconnect", time_limit=1.0, seed=0)
    assert res.found and res.cell_checks > 0
    np.testing.assert_allclose(res.path[0], START)
    np.testing.assert_allclose(res.path[-1], GOAL)
    assert len(res.extra["path_raw"]) >= 2


def test_world_checker_matches_world_lookups(door):
    w, _ = door
    chk = w.checker
    before = chk.checks
    rng = np.random.default_rng(0)
    pts = rng.uniform(0, 10, size=(300, 3))
    want = w.points_free(pts)
    got = [chk.is_valid(p) for p in pts]
    assert got == want.tolist()
    assert chk.checks - before == 300
    for a, b in zip(pts[:40], pts[40:80], strict=True):
        before = w.cell_checks
        assert chk.check_motion(a, b) == w.segment_free(a, b)
        assert w.cell_checks > before


@pytest.mark.parametrize("seed", [-5, 2**70, 1.5, True, "3"])
def test_invalid_seed_is_refused_before_any_work(door, seed, monkeypatch):
    w, _ = door

    def no_work(*a, **k):
        raise AssertionError("a worker was started")

    monkeypatch.setattr(baseline, "run_guarded", no_work)
    with pytest.raises(PlanError, match="seed must be an integer"):
        baseline.plan_ompl(w, START, GOAL, seed=seed)
    monkeypatch.setattr("planner.planning.build_world", no_work)
    with pytest.raises(PlanError, match="seed must be an integer"):
        api.plan(_wall_points(), START, GOAL, method="ompl:rrtconnect", seed=seed)


def test_killed_worker_is_reported_as_crash_not_timeout(door):
    w, _ = door
    out = {}

    def run():
        out["r"] = baseline.plan_ompl(w, START, GOAL, planner="rrtstar", time_limit=120.0)

    t = threading.Thread(target=run)
    t.start()
    deadline = time.monotonic() + 30
    kids = []
    while not kids and time.monotonic() < deadline:
        kids = multiprocessing.active_children()
        time.sleep(0.05)
    assert kids, "no worker started"
    time.sleep(0.3)
    os.kill(kids[0].pid, signal.SIGKILL)
    t.join(120)
    r = out["r"]
    assert not r.found and r.status == "crashed"
    assert r.reason == f"worker crashed (signal {int(signal.SIGKILL)})"
    assert r.wall_seconds < 60  # ended by the kill, far from its time limit


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc")
def test_worker_dies_with_its_caller(tmp_path):
    """SIGKILL of the calling process does not leave the OMPL worker running."""
    script = tmp_path / "caller.py"
    script.write_text(
        "import multiprocessing, sys, threading, time\n"
        "import numpy as np\n"
        "from planner import ompl\nfrom planner import planning as api\n"
        "pts = np.array([[5.0, 5.0, 5.0]])\n"
        "w = api.build_world(pts, 'cubic', cell_volume=0.008, radius=0.3,\n"
        "                    bounds=[[0, 0, 0], [10, 10, 10]])\n"
        "def watch():\n"
        "    while not multiprocessing.active_children():\n"
        "        time.sleep(0.05)\n"
        "    print(multiprocessing.active_children()[0].pid, flush=True)\n"
        "threading.Thread(target=watch, daemon=True).start()\n"
        "ompl.plan_ompl(w, (1, 1, 1), (9, 9, 9), planner='rrtstar', time_limit=60)\n"
    )
    env = {**os.environ, "PYTHONPATH": str(Path(__file__).resolve().parents[1])}
    proc = subprocess.Popen([sys.executable, str(script)], stdout=subprocess.PIPE, text=True,
                            env=env)
    try:
        pid = int(proc.stdout.readline())
        time.sleep(0.5)
        assert _alive(pid)
    finally:
        proc.kill()
        proc.wait()
    deadline = time.monotonic() + 10
    while _alive(pid) and time.monotonic() < deadline:
        time.sleep(0.1)
    assert not _alive(pid)


def _alive(pid: int) -> bool:
    try:
        with open(f"/proc/{pid}/stat") as f:
            return f.read().split(")")[-1].split()[0] != "Z"
    except FileNotFoundError:
        return False
