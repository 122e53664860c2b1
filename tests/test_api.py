"""planner.plan, build_world and the `planner` command line, as the README uses them."""

import json

import numpy as np
import pytest

import planner
from planner import io
from planner.cli import main
from planner.errors import PlanError

BOUNDS = np.array([[0.0, 0.0, 0.0], [10.0, 6.0, 3.0]])
START, GOAL = (2.0, 3.0, 1.5), (8.0, 3.0, 1.5)


def _wall_with_door(spacing: float = 0.05) -> np.ndarray:
    """Points on the plane x = 5 over the box, except a 1.2 m wide, 2 m high door."""
    y, z = np.meshgrid(np.arange(0, 6 + 1e-9, spacing), np.arange(0, 3 + 1e-9, spacing))
    y, z = y.ravel(), z.ravel()
    door = (np.abs(y - 3.0) < 0.6) & (z < 2.0)
    return np.column_stack([np.full((~door).sum(), 5.0), y[~door], z[~door]])


@pytest.fixture(scope="module")
def wall():
    return _wall_with_door()


@pytest.fixture(scope="module")
def wall_file(tmp_path_factory, wall):
    p = tmp_path_factory.mktemp("maps") / "wall.ply"
    io.save_points(p, wall)
    return p


def _min_distance(path: np.ndarray, pts: np.ndarray) -> float:
    best = np.inf
    for a, b in zip(path[:-1], path[1:], strict=True):
        ab = b - a
        t = np.clip((pts - a) @ ab / max(ab @ ab, 1e-300), 0, 1)
        best = min(best, np.linalg.norm(a + t[:, None] * ab - pts, axis=1).min())
    return best


@pytest.mark.parametrize("lattice", ["cubic", "bcc", "fcc", "mcc", "hex"])
def test_plan_goes_through_the_door_and_keeps_the_radius(wall, lattice):
    res = planner.plan(wall, START, GOAL, lattice=lattice, cell_volume=0.001, radius=0.3,
                       bounds=BOUNDS, method="astar", neighbors="face")
    assert res.found and res.reason == ""
    assert np.allclose(res.path[0], START) and np.allclose(res.path[-1], GOAL)
    assert res.length == pytest.approx(np.linalg.norm(np.diff(res.path, axis=0), axis=1).sum())
    assert res.length >= np.linalg.norm(np.subtract(GOAL, START))
    assert _min_distance(res.path, wall) >= 0.3
    assert res.cell_checks > 0 and res.expansions > 0
    d = json.loads(json.dumps(res.to_dict()))
    assert d["found"] and len(d["path"]) == len(res.path) and d["lattice"] == lattice


def test_any_angle_and_shortcut_paths_are_shorter_than_lattice_astar(wall):
    world = planner.build_world(wall, "fcc", cell_volume=0.001, radius=0.3, bounds=BOUNDS)
    astar = planner.plan(world, START, GOAL)
    for kw in ({"method": "theta"}, {"method": "lazy-theta"}, {"shortcut": True}):
        res = planner.plan(world, START, GOAL, **kw)
        assert res.found and res.length <= astar.length + 1e-9, kw
        assert _min_distance(res.path, wall) >= 0.3


def test_a_built_world_is_reused_without_rebuilding(wall, monkeypatch):
    world = planner.build_world(wall, "bcc", cell_volume=0.001, radius=0.3, bounds=BOUNDS)
    first = planner.plan(world, START, GOAL)

    def no_rebuild(*a, **k):
        raise AssertionError("the map was built again")

    monkeypatch.setattr("planner.voxels.exact_inflation", no_rebuild)
    monkeypatch.setattr("planner.planning.build_world", no_rebuild)
    again = planner.plan(world, START, GOAL)
    assert again.length == first.length
    other = planner.plan(world, GOAL, START, neighbors="face+1")
    assert other.found


def test_bad_start_and_goal_say_which_and_where(wall):
    world = planner.build_world(wall, "fcc", cell_volume=0.001, radius=0.3, bounds=BOUNDS)
    with pytest.raises(PlanError, match=r"start \(5\.000, 1\.000, 1\.000\) is inside an "
                                        r"obstacle.*nearest free cell centre: \("):
        planner.plan(world, (5.0, 1.0, 1.0), GOAL)
    with pytest.raises(PlanError, match=r"goal \(12\.000, 3\.000, 1\.500\) is outside the map"):
        planner.plan(world, START, (12.0, 3.0, 1.5))
    with pytest.raises(PlanError, match="start must be three"):
        planner.plan(world, (1.0, 2.0), GOAL)


def test_no_path_is_reported_not_raised(wall):
    closed = wall[~((wall[:, 1] > 2) & (wall[:, 1] < 4))]
    shut = np.concatenate([closed, _door_plug()])
    res = planner.plan(shut, START, GOAL, lattice="cubic", cell_volume=0.001, radius=0.3,
                       bounds=BOUNDS)
    assert not res.found and "unreachable" in res.reason and res.status == "unreachable"
    assert res.path.shape == (0, 3) and res.length == np.inf
    assert res.to_dict()["length"] is None
    world = planner.build_world(shut, "cubic", cell_volume=0.001, radius=0.3, bounds=BOUNDS)
    res = planner.plan(world, START, GOAL, max_expansions=100)
    assert not res.found and res.status == "budget" and res.expansions == 100
    assert res.reason.startswith("search budget exhausted after 100 expansions (")


def test_bad_api_arguments_are_plan_errors(wall):
    for radius in ("0.2", -1.0, float("nan")):
        with pytest.raises(PlanError, match="radius must be"):
            planner.build_world(wall, "fcc", cell_volume=0.001, radius=radius, bounds=BOUNDS)
    # None means "the map's radius": points carry none, so a radius must be given
    with pytest.raises(PlanError, match="suggests no robot radius"):
        planner.build_world(wall, "fcc", cell_volume=0.001, radius=None, bounds=BOUNDS)
    with pytest.raises(PlanError, match="suggests no robot radius"):
        planner.plan(wall, START, GOAL, cell_volume=0.001, bounds=BOUNDS)
    with pytest.raises(PlanError, match="method must be a string"):
        planner.plan(wall, START, GOAL, method=None)


def _door_plug() -> np.ndarray:
    y, z = np.meshgrid(np.arange(2.0, 4.0 + 1e-9, 0.05), np.arange(0, 3 + 1e-9, 0.05))
    return np.column_stack([np.full(y.size, 5.0), y.ravel(), z.ravel()])


@pytest.mark.slow
def test_cli_plan_writes_path_json_and_plot(wall_file, tmp_path, capsys):
    out, png = tmp_path / "path.csv", tmp_path / "path.png"
    argv = ["plan", str(wall_file), "--lattice", "bcc", "--cell-volume", "0.002",
            "--radius", "0.3", "--bounds", "0,0,0,10,6,3", "--start", "2,3,1.5",
            "--goal", "8,3,1.5", "--method", "lazy-theta", "--out", str(out),
            "--plot", str(png)]
    assert main(argv) == 0
    assert "bcc" in capsys.readouterr().out
    body = out.read_text().splitlines()
    meta = json.loads(out.with_suffix(".json").read_text())  # the metadata: a sidecar
    assert meta["lattice"] == "bcc" and meta["radius"] == 0.3
    assert body[0] == "x,y,z,yaw" and not any(ln.startswith("#") for ln in body)
    rows = np.loadtxt(body[1:], delimiter=",")
    assert np.allclose(rows[0, :3], START) and np.allclose(rows[-1, :3], GOAL)
    assert png.stat().st_size > 10_000
    assert main([*argv[:-4], "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["found"] and d["method"] == "lazy-theta"


def test_cli_exit_status_and_one_line_errors(wall_file, tmp_path, capsys):
    common = ["--cell-volume", "0.002", "--radius", "0.3", "--bounds", "0,0,0,10,6,3"]
    with pytest.raises(SystemExit) as e:
        main(["plan", str(wall_file), "--start", "1", "--goal", "8,3,1.5"])
    assert e.value.code == 2
    assert capsys.readouterr().err.count("\n") == 1
    # x,y is a 2D map's point: on a 3D map the world refuses it in one line
    assert main(["plan", str(wall_file), *common, "--start", "1,2", "--goal", "8,3,1.5"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--start: expected three finite numbers" in err
    assert main(["plan", str(tmp_path / "missing.ply"), "--start", "2,3,1.5",
                 "--goal", "8,3,1.5"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "missing.ply" in err and "Traceback" not in err
    assert main(["plan", str(wall_file), *common, "--start", "5,1,1", "--goal", "8,3,1.5"]) == 2
    assert "inside an obstacle" in capsys.readouterr().err
    bad_out = tmp_path / "path.txt"
    assert main(["plan", str(wall_file), *common, "--start", "2,3,1.5", "--goal", "8,3,1.5",
                 "--out", str(bad_out)]) == 2
    assert not bad_out.exists()


def test_cli_compare_prints_every_lattice(wall_file, capsys):
    assert main(["compare", str(wall_file), "--lattices", "cubic,fcc", "--cell-volume", "0.002",
                 "--radius", "0.3", "--bounds", "0,0,0,10,6,3", "--start", "2,3,1.5",
                 "--goal", "8,3,1.5"]) == 0
    out = capsys.readouterr().out
    assert "cubic" in out and "fcc" in out and "vs cubic" in out


@pytest.mark.parametrize("lattice", ["cubic", "fcc", "hex"])
def test_radius_guarantee_in_every_mode_that_claims_it(lattice):
    """Every neighbour set x corner cutting x method: a path with guarantee=True keeps the
    radius from every obstacle point (exact segment-point distance); only corner cutting
    over moves that cross other cells drops the guarantee."""
    from planner.search.moves import move_stencils

    rng = np.random.default_rng(7)
    pts = rng.uniform(0.0, 4.0, (60, 3))
    radius = 0.3
    world = planner.build_world(pts, lattice, cell_volume=0.15**3, radius=radius,
                                bounds=[[0, 0, 0], [4, 4, 4]])
    ends = rng.uniform(0.2, 3.8, (400, 3))
    ends = ends[world.points_free(ends)]
    far = np.linalg.norm(ends[:, None] - ends[None], axis=2)
    i, j = np.unravel_index(np.argmax(far), far.shape)
    checked = 0
    for nb in ("face", "full", "face+1", "full+1"):
        for cc in (False, True):
            crossing = any(len(c) > 1 for c in move_stencils(world.lattice, nb, False)[5])
            for method in ("astar", "lazy-theta"):
                res = planner.plan(world, ends[i], ends[j], neighbors=nb, corner_cutting=cc,
                                   method=method)
                assert res.guarantee == (not cc or not crossing), (nb, cc)
                if res.found and res.guarantee:
                    assert _min_distance(res.path, pts) >= radius - 1e-9, (nb, cc, method)
                    checked += 1
    assert checked >= 8
