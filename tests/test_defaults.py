"""One resolver of map defaults: the API and the CLI build the same world from the same map
(radius, lattice by dimension, cell volume, unknown-space policy), and a map that suggests no
radius needs one in both."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import planner
from planner.errors import PlanError
from planner.io import load_sidecar
from planner.lattice.paper import NAMED_LATTICES_2D
from planner.maps import map_path, resolve

ROOT = Path(__file__).resolve().parents[1]


def _cli(*args: str) -> subprocess.CompletedProcess:
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    return subprocess.run([sys.executable, "-m", "planner", *args], capture_output=True,
                          text=True, env=env, timeout=600)


def _xyz(v) -> str:
    return ",".join(f"{x:g}" for x in v)


def _cli_record(tmp_path: Path, name: str, start, goal) -> dict:
    out = tmp_path / f"{name}.json"
    r = _cli("plan", name, "--start", _xyz(start), "--goal", _xyz(goal), "--out", str(out))
    assert r.returncode == 0, r.stderr
    return json.loads(out.read_text())


def test_plan_office_in_the_api_and_the_cli_gives_the_same_world(tmp_path):
    side = load_sidecar(map_path("office"))
    start, goal = side["queries"][0]["start"], side["queries"][0]["goal"]
    res = planner.plan("office", start, goal)
    world = planner.build_world("office")
    rec = _cli_record(tmp_path, "office", start, goal)
    assert world.radius == side["robot_radius"] > 0  # the map's radius, not a point robot
    assert (rec["lattice"], rec["radius"], rec["unknown_policy"]) == (
        res.lattice, round(world.radius, 6), world.unknown_policy)
    assert rec["cell_volume"] == round(res.cell_volume, 6) == round(world.lattice.cell_volume, 6)
    assert res.found and rec["found"]
    assert rec["raw_length"] == pytest.approx(res.extra["raw_length"], abs=1e-6)


def test_plan_on_the_2d_floorplan_picks_a_2d_lattice():
    # (2, 2) is a pillar of this map: a clear error, not a lattice-dimension one
    with pytest.raises(PlanError, match="goal .* is inside an obstacle"):
        planner.plan("floorplan", (1, 1), (2, 2))
    side = load_sidecar(resolve("floorplan"))
    q = side["queries"][0]
    res = planner.plan("floorplan", q["start"], q["goal"])
    world = planner.build_world("floorplan")
    assert res.found and res.lattice == world.lattice.name
    assert world.dim == 2 and world.lattice.name in NAMED_LATTICES_2D
    assert world.radius == side["robot_radius"]


def test_floorplan_through_the_cli_matches_the_api(tmp_path):
    q = load_sidecar(resolve("floorplan"))["queries"][0]
    res = planner.plan("floorplan", q["start"], q["goal"])
    rec = _cli_record(tmp_path, "floorplan", q["start"], q["goal"])
    assert (rec["lattice"], rec["dim"], rec["found"]) == (res.lattice, 2, True)
    assert rec["raw_length"] == pytest.approx(res.extra["raw_length"], abs=1e-6)


def test_the_unknown_policy_is_an_option_of_plan():
    side = load_sidecar(map_path("office"))
    start, goal = side["queries"][0]["start"], side["queries"][0]["goal"]
    res = planner.plan("office", start, goal, unknown="free")
    assert res.found and "no free-space information" in res.unknown_note
    with pytest.raises(planner.MapError, match="says nothing about free space"):
        planner.plan("office", start, goal, unknown="blocked")


def test_a_map_without_a_radius_needs_one_in_the_api_and_the_cli(tmp_path):
    pts = np.array([[1.0, 1.0, 1.0], [2.0, 2.0, 1.0], [3.0, 1.0, 1.0]])
    f = tmp_path / "cloud.xyz"
    np.savetxt(f, pts)
    with pytest.raises(PlanError, match="suggests no robot radius"):
        planner.plan(str(f), (0.5, 0.5, 1.0), (2.5, 0.5, 1.0), cell_volume=0.01)
    with pytest.raises(PlanError, match="suggests no robot radius"):
        planner.build_world(pts, cell_volume=0.01)
    r = _cli("plan", str(f), "--start", "0.5,0.5,1", "--goal", "2.5,0.5,1",
             "--cell-volume", "0.01")
    assert r.returncode == 2 and "suggests no robot radius" in r.stderr
    assert len(r.stderr.strip().splitlines()) == 1 and "Traceback" not in r.stderr
    assert planner.plan(pts, (0.5, 0.5, 1.0), (2.5, 0.5, 1.0), cell_volume=0.01, radius=0.0,
                        bounds=[[0, 0, 0], [4, 3, 2]]).found
