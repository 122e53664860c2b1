"""Exploration: the robot discovers a wall it did not know, detours through its door, and
every repaired plan costs what A* from scratch finds on the same map state."""

from __future__ import annotations

import numpy as np
import pytest

from planner.errors import PlanError
from planner.explore import explore, ray_directions

BOUNDS = [[0.0, 0.0, 0.0], [10.0, 6.0, 2.0]]


def _wall(door: bool, step: float = 0.05) -> np.ndarray:
    """Points on the plane x = 5 over the whole box cross-section, with a door at
    y 4..5.5 (full height) when ``door``."""
    y, z = np.meshgrid(np.arange(0, 6 + 1e-9, step), np.arange(0, 2 + 1e-9, step))
    y, z = y.ravel(), z.ravel()
    if door:
        keep = (y < 4.0) | (y > 5.5)
        y, z = y[keep], z[keep]
    return np.column_stack([np.full_like(y, 5.0), y, z])


@pytest.mark.parametrize("replanner", ["astar", "dstar"])
@pytest.mark.parametrize("lattice", ["cubic", "fcc"])
def test_robot_finds_the_door_and_replans_like_astar(lattice, replanner):
    r = explore(_wall(door=True), [1, 1, 1], [9, 1, 1], lattice=lattice, radius=0.2,
                cell_volume=0.1**3, bounds=BOUNDS, sensor_range=3.0, fov=(360, 20),
                resolution=5.0, replanner=replanner)
    assert r.replanner == replanner and 1 <= r.searched.sum() < r.replans
    assert r.status == "reached"
    assert r.mismatches == 0 and r.contacts == 0
    assert r.replans >= 3  # the first plan, then the wall coming into view
    assert np.all(r.changed[1:] > 0)  # a replan happens only when the map changed
    # It went through the door: some trajectory point crosses x = 5 inside y 4..5.5.
    near = r.trajectory[np.abs(r.trajectory[:, 0] - 5.0) < 0.15]
    assert len(near) and np.all((near[:, 1] > 4.0) & (near[:, 1] < 5.5))
    assert r.distance > 2 * np.hypot(4.0, 3.0)  # via the door: x = 5, y > 4
    assert np.all(np.isfinite(r.replan_cost)) and np.allclose(r.replan_cost, r.astar_cost,
                                                             atol=1e-9)
    assert r.replan_checks[1:].sum() < r.astar_checks[1:].sum()
    s = r.summary()
    assert s["replans"] == r.replans and s["points_seen"] == int(r.seen.sum()) > 0
    assert s["replanner"] == replanner and s["searched"] == int(r.searched.sum())


def test_closed_wall_is_proved_unreachable():
    r = explore(_wall(door=False), [1, 1, 1], [9, 1, 1], lattice="cubic", radius=0.2,
                cell_volume=0.1**3, bounds=BOUNDS, sensor_range=3.0, fov=(360, 30),
                resolution=5.0)
    assert r.status == "unreachable"
    assert r.mismatches == 0 and r.contacts == 0
    assert np.isinf(r.replan_cost[-1]) and np.isinf(r.astar_cost[-1])


def test_step_budget_stops_the_robot_and_start_at_goal_is_reached():
    r = explore(_wall(door=True), [1, 1, 1], [9, 1, 1], lattice="cubic", radius=0.2,
                cell_volume=0.1**3, bounds=BOUNDS, max_steps=3)
    assert r.status == "budget" and len(r.trajectory) == 4
    r = explore(_wall(door=True), [1, 1, 1], [1, 1, 1], lattice="cubic", radius=0.2,
                cell_volume=0.1**3, bounds=BOUNDS)
    assert r.status == "reached" and r.distance == 0 and r.replans == 1


@pytest.mark.slow
def test_summary_figure_is_written(tmp_path):
    r = explore(_wall(door=True), [1, 1, 1], [9, 1, 1], lattice="cubic", radius=0.2,
                cell_volume=0.1**3, bounds=BOUNDS, sensor_range=3.0, resolution=6.0)
    out = r.plot(tmp_path / "explore.png")
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_ray_directions_cover_the_field_of_view():
    d = ray_directions((360, 30), 10)
    assert np.allclose(np.linalg.norm(d, axis=1), 1)
    assert len(d) == 36 * 7
    el = np.degrees(np.arcsin(d[:, 2]))
    assert el.min() == pytest.approx(-30) and el.max() == pytest.approx(30)
    assert len(ray_directions((90, 0), 10)) == 10  # -45..45 inclusive, one elevation


def test_bad_sensor_settings_are_one_clear_error():
    with pytest.raises(PlanError, match="sensor_range"):
        explore(_wall(True), [1, 1, 1], [9, 1, 1], radius=0.2, cell_volume=1e-3,
                bounds=BOUNDS, sensor_range=-1)
    with pytest.raises(PlanError, match="max_steps"):
        explore(_wall(True), [1, 1, 1], [9, 1, 1], radius=0.2, cell_volume=1e-3,
                bounds=BOUNDS, max_steps=-1)
    with pytest.raises(PlanError, match="fov"):
        ray_directions((400, 10), 2)
    with pytest.raises(PlanError, match="goal"):
        explore(_wall(True), [1, 1, 1], [5, 1, 1], radius=0.2, cell_volume=1e-3,
                bounds=BOUNDS)
    with pytest.raises(PlanError, match="unknown replanner 'dstarlite'; expected one of "
                                        "astar, dstar"):
        explore(_wall(True), [1, 1, 1], [9, 1, 1], radius=0.2, cell_volume=1e-3,
                bounds=BOUNDS, replanner="dstarlite")


def test_office_exploration_animates_one_frame_per_replan(tmp_path):
    from PIL import Image

    from planner.maps import load_map_info

    q = load_map_info("office")["queries"][0]
    r = explore("office", q["start"], q["goal"], lattice="cubic", sensor_range=3.0,
                resolution=10.0, fov=(360, 10), max_steps=12)
    assert r.status == "budget" and r.replans >= 2
    out = r.animate(tmp_path / "office.gif", max_frames=3)
    with Image.open(out) as im:
        assert im.format == "GIF"
        assert im.n_frames == min(r.replans, 3) + 1  # the replans drawn, then the end
    assert not [p for p in tmp_path.iterdir() if p.name != "office.gif"]  # no temp left


def test_animation_frames_are_subsampled_evenly_keeping_first_and_last():
    from planner.explore.figures import frame_replans

    assert list(frame_replans(4, 150)) == [0, 1, 2, 3]
    f = frame_replans(1000, 150)
    assert len(f) == 150 and f[0] == 0 and f[-1] == 999 and np.all(np.diff(f) > 0)


def test_cli_writes_the_gif_and_refuses_another_suffix(tmp_path, capsys):
    from planner.cli import main

    gif = tmp_path / "run.gif"
    args = ["explore", "office", "--start", "2.5,2.5,1.2", "--goal", "18.3,10.5,1.2",
            "--lattice", "bcc", "--sensor-range", "3", "--resolution", "10", "--fov", "360,10",
            "--max-steps", "6"]
    assert main([*args, "--gif", str(gif), "--frames", "2"]) == 1  # budget: not reached
    assert "budget" in capsys.readouterr().out
    assert gif.read_bytes()[:6] in (b"GIF87a", b"GIF89a")
    assert main([*args, "--gif", str(tmp_path / "run.png")]) == 2
    assert "unsupported output type '.png'" in capsys.readouterr().err


def test_cli_reads_the_map_in_the_format_given_and_has_no_unknown_option(tmp_path, capsys):
    import shutil

    from planner.cli import main
    from planner.maps import MAPS_DIR

    renamed = tmp_path / "office.dat"  # a text-point extension: unreadable without --format
    shutil.copy(MAPS_DIR / "office.ply", renamed)
    args = ["explore", str(renamed), "--start", "2.5,2.5,1.2", "--goal", "4.0,2.5,1.2",
            "--lattice", "fcc", "--radius", "0.25", "--cell-volume", "0.05", "--max-steps", "200"]
    assert main(args) == 2
    capsys.readouterr()
    assert main([*args, "--format", "ply", "--json"]) == 0
    out = capsys.readouterr().out
    assert '"status": "reached"' in out and '"replanner": "astar"' in out
    assert main([*args, "--format", "ply", "--json", "--replanner", "dstar"]) == 0
    assert '"replanner": "dstar"' in capsys.readouterr().out
    with pytest.raises(SystemExit) as stop:
        main([*args, "--format", "ply", "--unknown", "free"])
    assert stop.value.code == 2 and "--unknown" in capsys.readouterr().err


def test_dstar_phases_are_timed_per_replan_without_changing_the_run():
    kw = dict(lattice="cubic", radius=0.2, cell_volume=0.1**3, bounds=BOUNDS,
              sensor_range=3.0, fov=(360, 20), resolution=5.0, replanner="dstar")
    plain = explore(_wall(door=True), [1, 1, 1], [9, 1, 1], **kw)
    r = explore(_wall(door=True), [1, 1, 1], [9, 1, 1], phases=True, **kw)
    assert np.array_equal(r.replan_cost, plain.replan_cost) and r.mismatches == 0
    assert np.array_equal(r.replan_checks, plain.replan_checks)
    assert r.replan_phase_seconds.shape == (r.replans, 4)
    t = r.replan_phase_seconds[1:][r.replan_checks[1:] > 0]  # the repairs
    timed = ~np.isnan(t).all(axis=1)  # the others grew the planner's arrays
    assert timed.any() and (t[timed] > 0).all()
    assert plain.replan_phase_seconds.shape == (0, 4)
    with pytest.raises(PlanError, match="replanner='dstar'"):
        explore(_wall(door=True), [1, 1, 1], [9, 1, 1], lattice="cubic", radius=0.2,
                cell_volume=0.1**3, bounds=BOUNDS, phases=True)
