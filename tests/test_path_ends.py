"""A path is what the robot drives: it starts exactly at the start and ends exactly at the
goal without first hopping to a cell centre, headings are the travel direction, and every
output lists the same waypoints."""

from __future__ import annotations

import csv
import json
import sys
from pathlib import Path

import numpy as np
import pytest

import planner
from planner.cli import main
from planner.path import headings
from planner.planning import joined

sys.path.insert(0, str(Path(__file__).parent))
from _nav2 import write_office_map  # noqa: E402

START, GOAL = np.array([2.0, 3.0]), np.array([5.0, 11.0])


@pytest.fixture(scope="module")
def office_map(tmp_path_factory):
    return write_office_map(tmp_path_factory.mktemp("nav2"))


@pytest.mark.parametrize(("method", "shortcut"), [("astar", False), ("astar", True),
                                                  ("lazy-theta", False)])
def test_the_path_joins_its_ends_without_a_hop_to_a_cell_centre(office_map, method, shortcut):
    world = planner.build_world(office_map, radius=0.2)
    res = planner.plan(world, START, GOAL, method=method, shortcut=shortcut)
    assert res.found
    p = res.path[:, :2]
    assert np.array_equal(p[0], START) and np.array_equal(p[-1], GOAL)
    lat = world.lattice
    # the first move leaves the start's cell, the last one arrives from another cell
    assert (lat.quantize(res.path[1:2]) != lat.quantize(res.path[:1])).any()
    assert (lat.quantize(res.path[-2:-1]) != lat.quantize(res.path[-1:])).any()
    # the joining segments pass the search's rule
    assert world.segment_free(res.path[0], res.path[1])
    assert world.segment_free(res.path[-2], res.path[-1])
    # no backward first step: it heads within 90 degrees of where the path goes next
    assert np.dot(p[1] - p[0], p[2] - p[0]) > 0
    assert len(np.unique(np.round(res.path, 6), axis=0)) == len(res.path)


def test_a_joining_segment_that_fails_the_check_keeps_the_hop():
    class Walls:  # every segment blocked: the ends keep their cell centres
        def segment_free(self, a, b):
            return False

    path = np.array([[0.1, 0.1, 0], [0.0, 0, 0], [1, 0, 0], [2, 0, 0], [2.1, -0.1, 0]])
    np.testing.assert_array_equal(joined(Walls(), path), path)


def test_headings_are_the_travel_direction_through_sub_millimetre_hops():
    travel = np.arctan2(1.0, 2.0)
    # a 0.27 mm sideways hop at the start, a 0.4 mm one mid-run, a vertical move
    path = np.array([[0.0, 0, 0], [1.5e-4, -2.2e-4, 0], [2, 1, 0], [2 + 3e-4, 1 - 2e-4, 0],
                     [4, 2, 0], [4, 2, 1], [6, 3, 1]])
    np.testing.assert_allclose(headings(path), travel, atol=2e-4)


def test_every_output_lists_the_same_waypoints(office_map, tmp_path, capsys):
    common = ["plan", str(office_map), "--radius", "0.2", "--start", "2,3", "--goal", "5,11"]
    tum, js, cs = tmp_path / "p.tum", tmp_path / "p.json", tmp_path / "p.csv"
    assert main([*common, "--out", str(tum)]) == 0  # the reproducer
    printed = capsys.readouterr().out
    assert main([*common, "--out", str(js), "--json"]) == 0
    shown = json.loads(capsys.readouterr().out)["path"]
    assert main([*common, "--out", str(cs)]) == 0
    rows = np.loadtxt(tum)
    rec = json.loads(js.read_text())
    with open(cs, newline="") as f:
        table = list(csv.reader(f))[1:]
    n = len(shown)
    assert f"{n} waypoints" in printed
    assert len(rows) == len(rec["path"]) == len(rec["waypoints"]) == len(table) == n
    np.testing.assert_allclose(rows[:, 1:4], np.array(shown), atol=1e-9)
    np.testing.assert_allclose(np.array(rec["path"]), np.array(shown), atol=1e-6)
    assert rows[0, 1:3].tolist() == [2.0, 3.0] and rows[-1, 1:3].tolist() == [5.0, 11.0]
    # TUM stamps: arc length at 1 m/s; orientation: the path files' headings
    arc = np.concatenate([[0], np.cumsum(np.linalg.norm(np.diff(rows[:, 1:4], axis=0),
                                                        axis=1))])
    np.testing.assert_allclose(rows[:, 0], arc, atol=1e-8)
    yaw = 2 * np.arctan2(rows[:, 6], rows[:, 7])
    np.testing.assert_allclose(np.angle(np.exp(1j * (yaw - [w[-1] for w in rec["waypoints"]]))),
                               0, atol=1e-5)
    if pytest.importorskip("rosbags"):
        from rosbags.highlevel import AnyReader

        bag = tmp_path / "p_bag"
        assert main([*common, "--bag", str(bag)]) == 0
        with AnyReader([bag]) as r:
            (conn, _, raw), = list(r.messages())
            msg = r.deserialize(raw, conn.msgtype)
        got = np.array([[q.pose.position.x, q.pose.position.y] for q in msg.poses])
        np.testing.assert_allclose(got, np.array(shown)[:, :2], atol=1e-9)
