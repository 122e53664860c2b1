"""Figures a person reads at a glance: walls drawn solid on every lattice, the 3D panel shows
the obstacle surface beside the path, compare draws every query (or the one asked for) and
says which, explore's log axis keeps zero-check replans, one rotation draws markers."""

import numpy as np
import pytest

from planner import Lattice
from planner.analysis.path_figure import _footprint, _surface
from planner.cli import main
from planner.world import World


def _wall_world(name: str) -> World:
    """A 4 x 4 x 2 m box with a solid wall 0.6 m thick at x 1.7-2.3 m on lattice ``name``."""
    lat = Lattice.named(name, cell_volume=0.001)
    g = np.asarray(lat.generator)
    k = np.linalg.solve(g, np.array([[0, 0, 0], [4, 4, 2], [4, 0, 0], [0, 4, 0], [0, 0, 2],
                                     [4, 4, 0], [4, 0, 2], [0, 4, 2]]).T).T
    lo, hi = np.floor(k.min(0)).astype(int) - 1, np.ceil(k.max(0)).astype(int) + 1
    idx = np.stack(np.meshgrid(*[np.arange(a, b) for a, b in zip(lo, hi, strict=True)],
                               indexing="ij"), -1).reshape(-1, 3)
    c = lat.to_world(idx)
    wall = idx[(c[:, 0] >= 1.7) & (c[:, 0] <= 2.3)]
    return World(lat, wall, [[0, 0, 0], [4, 4, 2]])


@pytest.mark.parametrize("name", ["hex", "fcc", "bcc", "cubic"])
def test_the_top_view_draws_a_wall_solid_on_every_lattice(name):
    world = _wall_world(name)
    xe = np.linspace(0.2, 3.8, 181)
    ye = np.linspace(0.2, 3.8, 181)
    blocked, unknown = _footprint(world, xe, ye, 0.8, 1.2)
    xc = (xe[:-1] + xe[1:]) / 2
    inside = (xc > 1.8) & (xc < 2.2)  # well inside the wall: every pixel fully blocked
    outside = (xc < 1.5) | (xc > 2.5)
    assert blocked[:, inside].min() == 1.0
    assert blocked[:, outside].max() == 0.0
    assert not unknown.any()


def test_the_3d_panel_shows_the_walls_surface_beside_the_path():
    world = _wall_world("fcc")
    path = np.array([[1.0, 0.5, 1.0], [1.0, 3.5, 1.0]])  # along the wall, 0.7 m from it
    dense = np.linspace(path[0], path[1], 100)
    surf, unk = _surface(world, dense, 1.0)
    assert len(surf) and not len(unk)
    assert np.all(world.points_free(surf) == 0)  # blocked cells ...
    cells = world.lattice.quantize(surf)
    nb = world.lattice.neighbors("face")
    assert all(world.is_free(c + nb).any() for c in cells)  # ... on the surface
    assert surf[:, 0].max() < 1.9  # only the face towards the path, not the far one
    d = np.min(np.linalg.norm(surf[:, None] - dense[None], axis=2), axis=1)
    assert d.max() <= 1.0


def _png_shape(path) -> tuple[int, int]:
    from matplotlib.image import imread

    return imread(str(path)).shape[:2]


FAST = ["office", "--cell-volume", "0.004", "--radius", "0.2", "--lattices", "cubic,hex"]


def test_compare_plots_every_query_or_the_one_asked_for(tmp_path, capsys):
    assert main(["compare", *FAST, "--plot", str(tmp_path / "all.png")]) == 0
    assert main(["compare", *FAST, "--plot", str(tmp_path / "q2.png"), "--plot-query",
                 "2"]) == 0
    (h_all, w_all), (h_one, w_one) = _png_shape(tmp_path / "all.png"), _png_shape(
        tmp_path / "q2.png")
    assert h_all / w_all > 2.5 * h_one / w_one  # office has 3 queries: 3 rows of panels
    capsys.readouterr()
    assert main(["compare", *FAST, "--plot", str(tmp_path / "q9.png"), "--plot-query",
                 "9"]) == 2
    assert "there are 3 queries" in capsys.readouterr().err
    assert not (tmp_path / "q9.png").exists()


def test_zero_check_replans_are_drawn_at_a_floor_and_counted(tmp_path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from planner.explore.figures import _log_dots, floor_of

    dstar = np.array([120.0, 0, 0, 3, 0, 1])
    astar = np.array([900.0, 40, 30, 20, 10, 5])
    fig, ax = plt.subplots()
    _log_dots(ax, [(astar, "0.5", "A*"), (dstar, "tab:red", "D* Lite")], "cell checks")
    drawn = sum(len(line.get_xdata()) for line in ax.get_lines())
    assert drawn == len(dstar) + len(astar)  # every replan is on the axis
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert "D* Lite: 3 with 0 cell checks (drawn at the floor)" in labels
    zeros = [line for line in ax.get_lines() if line.get_marker() == "v"]
    assert np.all(zeros[0].get_ydata() == floor_of([astar, dstar])) and floor_of(
        [astar, dstar]) < 1
    plt.close(fig)


def test_a_plan_leaving_the_slice_is_drawn_apart_with_its_heights():
    from planner.explore.figures import split_at_slice

    # flat at z = 1, over a wall at z = 2.4, down again
    plan = np.array([[0, 0, 1.0], [1, 0, 1.0], [2, 0, 2.4], [3, 0, 2.4], [4, 0, 1.0],
                     [5, 0, 1.0]])
    inside, outside, z = split_at_slice(plan, 1.0)
    assert np.isnan(inside[2:4]).all() and not np.isnan(inside[[0, 1, 4, 5]]).any()
    # the dotted part runs from the last waypoint in the slice to the first one back
    np.testing.assert_array_equal(outside[1:5], plan[1:5])
    assert np.isnan(outside[[0, 5]]).all()
    assert z == (1.0, 2.4)
    flat_in, flat_out, _ = split_at_slice(plan[:2], 1.0)
    assert not len(flat_out) and not np.isnan(flat_in).any()


@pytest.mark.parametrize("k", [1, 3])
def test_fig5_draws_markers_for_one_rotation_and_cdfs_for_several(tmp_path, monkeypatch, k):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from planner.analysis import paper

    figs, close = [], plt.close
    monkeypatch.setattr(paper, "save_fig", lambda fig, path: figs.append(fig))
    monkeypatch.setattr(plt, "close", lambda fig=None: None)  # kept open to be inspected
    rows = [{"dataset": "scan", "cell_volume": 0.125, "lattice": name, "rotation": r,
             "distortion": 0.2 + 0.01 * i + 0.001 * r, "voxel_count": 100 + i + r}
            for i, name in enumerate(paper.NAMED) for r in range(k)]
    paper.fig5(tmp_path, plt, rows, {"scan": np.zeros((10, 3))}, [0.125])
    lines = figs[0].axes[0].get_lines()
    assert len(lines) == len(paper.NAMED)
    if k == 1:  # a dot per lattice, not a vertical step
        assert all(line.get_marker() == "o" and line.get_drawstyle() == "default"
                   for line in lines)
        assert "one random rotation" in figs[0]._suptitle.get_text()
    else:
        assert all(line.get_drawstyle() == "steps-post" for line in lines)
    for fig in figs:
        close(fig)
