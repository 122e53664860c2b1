"""The explorer's default replanner: A* again only when a newly blocked cell touches the rest
of the path (its cells from the robot's on, and its moves' safe-rule cells); every plan
costs what A* from scratch finds."""

from __future__ import annotations

import numpy as np
import pytest

from planner.lattice import Lattice
from planner.search import move_stencils, search
from planner.search.replanner import AStarReplanner
from planner.world import World


def _cost_from_scratch(world, start, goal, neighbors="full") -> float:
    return search(world, start, goal, neighbors=neighbors).cost


def _valid_cost(world, cells, neighbors="full") -> float:
    """The path's cost, asserting each of its moves is allowed under the safe rule."""
    moves, cost, _, _, _, per_move = move_stencils(world.lattice, neighbors)
    index = {tuple(m): i for i, m in enumerate(moves.tolist())}
    assert world.is_free(cells).all()
    total = 0.0
    for a, b in zip(cells[:-1], cells[1:], strict=True):
        m = index[tuple((b - a).tolist())]
        assert world.is_free(a + per_move[m]).all(), "a move's safe-rule cell is blocked"
        total += cost[m]
    return total


def _corridor() -> tuple[World, np.ndarray, np.ndarray]:
    w = World(Lattice.named("cubic", 1.0), [], [[0, 0, 0], [12, 4, 2]])
    return w, np.array([0, 2, 1]), np.array([12, 2, 1])


def test_cells_off_the_path_or_behind_the_robot_keep_it_without_a_search():
    w, s, g = _corridor()
    p = AStarReplanner(w, s, g)
    first = p.plan()
    assert first.found and p.searches == 1
    for c in first.cells[1:4]:
        p.move_start(c)
    behind = first.cells[1:2]  # walked: nothing ahead rests on it
    p.update(w.set_cells(np.vstack([behind, [[6, 0, 0]]]), True), blocked=True)
    r = p.plan()
    assert p.searches == 1 and r.expansions == 0 and r.cell_checks == 0
    assert np.array_equal(r.cells, first.cells[3:])
    assert abs(r.cost - _cost_from_scratch(w, p.start, g)) <= 1e-9


def test_a_blocked_safe_rule_cell_ahead_forces_a_replan_to_a_valid_path():
    # A diagonal move's safe rule checks the cells beside the segment, off the path: a
    # check of the path's cells alone would keep a path through a blocked move.
    lat = Lattice.named("cubic", 1.0)
    w = World(lat, [], [[0, 0, 0], [10, 6, 2]])
    s, g = np.array([0, 0, 1]), np.array([10, 5, 1])
    p = AStarReplanner(w, s, g)
    path = p.plan().cells
    moves, _, _, _, _, per_move = move_stencils(lat, "full")
    index = {tuple(m): i for i, m in enumerate(moves.tolist())}
    on_path = {tuple(c) for c in path.tolist()}
    side = None
    for a, b in zip(path[2:-1], path[3:], strict=True):
        extra = [c for c in (a + per_move[index[tuple((b - a).tolist())]]).tolist()
                 if tuple(c) not in on_path]
        if extra:
            side = np.array(extra[:1])
            break
    assert side is not None, "the test needs a move with a safe-rule cell off the path"
    p.update(w.set_cells(side, True), blocked=True)
    r = p.plan()
    assert p.searches == 2 and r.expansions > 0
    assert abs(_valid_cost(w, r.cells) - r.cost) <= 1e-9
    assert abs(r.cost - _cost_from_scratch(w, s, g)) <= 1e-9


def test_a_blocked_robot_cell_is_blocked_and_a_blocked_goal_unreachable():
    w, s, g = _corridor()
    p = AStarReplanner(w, s, g)
    p.plan()
    p.update(w.set_cells(g[None], True), blocked=True)
    r = p.plan()
    assert r.status == "unreachable" and not r.found and r.cost == np.inf
    p.update(w.set_cells(s[None], True), blocked=True)
    assert p.plan().status == "blocked"


def test_freed_cells_search_again_and_find_the_shorter_path():
    w, s, g = _corridor()
    wall = np.array([[6, y, z] for y in range(4) for z in range(3) if (y, z) != (0, 0)])
    w.set_cells(wall, True)
    p = AStarReplanner(w, s, g)
    around = p.plan().cost
    p.update(w.set_cells(wall, False), blocked=False)
    r = p.plan()
    assert r.cost < around and abs(r.cost - _cost_from_scratch(w, s, g)) <= 1e-9


@pytest.mark.parametrize("bad", [dict(world="w"), dict(start=[0, 9, 9])])
def test_bad_arguments_are_one_clear_error(bad):
    from planner.errors import PlanError

    w, s, g = _corridor()
    args = {"world": w, "start": s, "goal": g, **bad}
    with pytest.raises(PlanError):
        AStarReplanner(args["world"], args["start"], args["goal"])
