"""Replanning (D* Lite, and A* re-run only when the changes touch the path): after every
batch of changed cells and start moves, the replanned path costs exactly what a
from-scratch A* finds on the updated world."""

from __future__ import annotations

import math
import zlib

import numpy as np
import pytest

from planner.errors import PlanError
from planner.lattice import NAMED_LATTICES, Lattice
from planner.search import move_stencils, search
from planner.search.dstar import lite as incremental
from planner.search.dstar.lite import DStarLite
from planner.search.replanner import AStarReplanner
from planner.world import World

#: (replanner, renumbered): D* Lite with and without renumbering its nodes (it renumbers
#: whenever their count doubles), and A* re-run when the path is hit
PLANNERS = [pytest.param(DStarLite, False, id="dstar"),
            pytest.param(DStarLite, True, id="dstar-renumbered"),
            pytest.param(AStarReplanner, False, id="astar")]


def _free_cells(world: World) -> np.ndarray:
    return world.free_bits.cells()


def _in_bounds_cells(world: World) -> np.ndarray:
    occ = world.occupancy
    box = np.stack(np.unravel_index(np.arange(int(np.prod(occ.dims))), tuple(occ.dims)),
                   1) + occ.lo
    return box[world.in_bounds(box)]


def _astar_cost(world, start, goal, neighbors) -> float:
    try:
        r = search(world, start, goal, method="astar", neighbors=neighbors)
    except PlanError:  # start or goal blocked
        return math.inf
    return r.cost


def _assert_valid(world, cells, neighbors):
    moves, cost, _, _, _, per_move = move_stencils(world.lattice, neighbors)
    index = {tuple(m): i for i, m in enumerate(moves.tolist())}
    total = 0.0
    assert world.is_free(cells).all()
    for a, b in zip(cells[:-1], cells[1:], strict=True):
        m = index[tuple((b - a).tolist())]  # KeyError: not a move
        assert world.is_free(a + per_move[m]).all(), "a move's safe-rule cell is blocked"
        total += cost[m]
    return total


@pytest.mark.parametrize("planner, renumbered", PLANNERS)
@pytest.mark.parametrize("neighbors", ["face", "full"])
@pytest.mark.parametrize("name", NAMED_LATTICES)
def test_replanner_matches_astar_after_every_batch(name, neighbors, planner, renumbered,
                                                   monkeypatch, seed=0):
    if renumbered:  # the planner renumbers its nodes whenever their count doubles
        monkeypatch.setattr(incremental, "_COMPACT_MIN", 1)
    rng = np.random.default_rng([zlib.crc32(f"{name}/{neighbors}".encode()), seed])
    lat = Lattice.named(name, 1.0)
    world = World(lat, np.zeros((0, 3), np.int64), [[0, 0, 0], [7, 7, 5]])
    cells = _in_bounds_cells(world)
    world.set_cells(cells[rng.random(len(cells)) < 0.18], blocked=True)
    free = _free_cells(world)
    d = np.linalg.norm(lat.to_world(free)[:, None] - lat.to_world(free)[None], axis=2)
    i, j = np.unravel_index(np.argmax(d), d.shape)
    start, goal = free[i], free[j]
    dl = planner(world, start, goal, neighbors=neighbors)
    checked = 0
    for batch in range(8):
        r = dl.plan()
        want = _astar_cost(world, dl.start, goal, neighbors)
        if math.isinf(want):
            assert not r.found and math.isinf(r.cost)
        else:
            assert r.found and abs(r.cost - want) <= 1e-9, (batch, r.cost, want)
            assert abs(_assert_valid(world, r.cells, neighbors) - r.cost) <= 1e-9
            assert np.array_equal(r.cells[0], dl.start) and np.array_equal(r.cells[-1], goal)
            checked += 1
            if len(r.cells) > 3 and batch % 2:
                dl.move_start(r.cells[1])  # the robot takes a step
        # A batch: block some cells on the current path (not its ends), then flip random
        # cells both ways (after a dead end, mostly free cells).
        ends = np.array([dl.start, goal])
        on_path = r.cells[1:-1] if r.found else np.zeros((0, 3), np.int64)
        block = on_path[rng.random(len(on_path)) < 0.3]
        flip = cells[rng.random(len(cells)) < (0.05 if r.found else 0.3)]
        if not r.found:
            flip = flip[~world.is_free(flip) | (rng.random(len(flip)) < 0.1)]
        block, flip = (x[~(x[:, None] == ends[None]).all(2).any(1)] for x in (block, flip))
        now_free = world.is_free(flip)
        # Three ways to report: the new state given (no lookups), or looked up.
        dl.update(world.set_cells(block, True), blocked=True)
        dl.update(world.set_cells(flip[~now_free], False), blocked=False)
        dl.update(world.set_cells(flip[now_free], True))
    assert checked >= 3  # most batches have a path to compare


@pytest.mark.parametrize("planner, renumbered", PLANNERS)
@pytest.mark.parametrize("neighbors", ["face", "full"])
@pytest.mark.parametrize("name", NAMED_LATTICES)
def test_walking_robot_with_small_changes_near_and_far_keeps_an_optimal_path(
        name, neighbors, planner, renumbered, monkeypatch):
    if renumbered:
        monkeypatch.setattr(incremental, "_COMPACT_MIN", 1)
    # A robot steps along its plan while a few cells flip per step, on the path, next to
    # it or anywhere: the plan it gets (often the rest of the previous one) is always a
    # valid path from where it stands, as short as A* from scratch.
    rng = np.random.default_rng(zlib.crc32(f"walk/{name}/{neighbors}".encode()))
    lat = Lattice.named(name, 1.0)
    world = World(lat, np.zeros((0, 3), np.int64), [[0, 0, 0], [12, 5, 3]])
    cells = _in_bounds_cells(world)
    world.set_cells(cells[rng.random(len(cells)) < 0.08], blocked=True)
    free = _free_cells(world)
    x = lat.to_world(free)[:, 0]
    start, goal = free[np.argmin(x)], free[np.argmax(x)]
    dl = planner(world, start, goal, neighbors=neighbors)
    compared = 0
    for step in range(30):
        r = dl.plan()
        want = _astar_cost(world, dl.start, goal, neighbors)
        assert (math.isinf(want) and not r.found) or abs(r.cost - want) <= 1e-9, (step, r.cost,
                                                                                 want)
        if not r.found:
            break
        compared += 1
        assert np.array_equal(r.cells[0], dl.start) and np.array_equal(r.cells[-1], goal)
        assert abs(_assert_valid(world, r.cells, neighbors) - r.cost) <= 1e-9
        if len(r.cells) > 2:
            dl.move_start(r.cells[1])
        near = r.cells[1:-1] + rng.integers(-1, 2, (len(r.cells) - 2, 3))
        pool = [cells, near] if len(near) else [cells]
        pick = pool[step % len(pool)]
        flip = pick[rng.integers(0, len(pick), int(rng.integers(0, 4)))]
        flip = flip[world.in_bounds(flip)]
        flip = flip[~((flip == dl.start).all(1) | (flip == goal).all(1))]
        now_free = world.is_free(flip)
        dl.update(world.set_cells(flip[now_free], True), blocked=True)
        if step % 3 == 0:  # sometimes a cell opens up too
            dl.update(world.set_cells(flip[~now_free], False), blocked=False)
    assert compared >= 10


def test_unchanged_world_costs_like_astar_and_counts_checks():
    lat = Lattice.named("fcc", 1.0)
    world = World(lat, [[3, 0, 1], [2, 2, 0]], [[0, 0, 0], [8, 8, 8]])
    s, g = world.lattice.quantize(np.array([[0.5, 0.5, 0.5], [7.5, 7.5, 7.5]]))
    a = search(world, s, g)
    r = DStarLite(world, s, g).plan()
    assert abs(r.cost - a.cost) <= 1e-9 and r.cell_checks > 0 and r.expansions > 0
    assert r.guarantee


def test_blocked_start_is_unreachable_not_an_error_after_an_update():
    world = World(Lattice.named("cubic", 1.0), [], [[0, 0, 0], [4, 4, 4]])
    d = DStarLite(world, [0, 0, 0], [4, 4, 4])
    assert d.plan().found
    d.update(world.set_cells([[0, 0, 0]], True))
    r = d.plan()
    assert not r.found and r.status == "blocked"
    d.update(world.set_cells([[0, 0, 0]], False))
    assert abs(d.plan().cost - 4 * math.sqrt(3)) <= 1e-12


def test_walled_off_goal_is_unreachable_then_reachable_again():
    world = World(Lattice.named("cubic", 1.0), [], [[0, 0, 0], [4, 4, 4]])
    d = DStarLite(world, [0, 0, 0], [4, 4, 4])
    wall = np.array([[2, j, k] for j in range(5) for k in range(5)])
    d.update(world.set_cells(wall, True))
    assert d.plan().status == "unreachable"
    d.update(world.set_cells([[2, 4, 4]], False))
    r = d.plan()
    assert r.found and abs(r.cost - _astar_cost(world, [0, 0, 0], [4, 4, 4], "full")) < 1e-9


def test_bad_input_is_one_clear_error():
    world = World(Lattice.named("cubic", 1.0), [[1, 1, 1]], [[0, 0, 0], [4, 4, 4]])
    with pytest.raises(PlanError, match="start"):
        DStarLite(world, [1, 1, 1], [4, 4, 4])
    with pytest.raises(PlanError, match="dense"):
        DStarLite(World(Lattice.named("cubic", 1.0), [], [[0, 0, 0], [4, 4, 4]],
                        dense_budget=0), [0, 0, 0], [4, 4, 4])


def test_blocked_cells_off_the_path_keep_it_until_one_lands_on_it():
    # Cells blocked away from the stored path leave it a shortest path: the replan keeps
    # it without repairing (no lookup, no expansion); the first change under the path
    # repairs every pending cell at once and the cost is A*'s again.
    world = World(Lattice.named("cubic", 1.0), [], [[0, 0, 0], [12, 6, 2]])
    d = DStarLite(world, [0, 3, 1], [12, 3, 1])
    r = d.plan()
    assert abs(r.cost - 12.0) <= 1e-12
    d.move_start(r.cells[1])
    d.update(world.set_cells([[6, 0, 0], [6, 6, 2], [9, 0, 1]], True), blocked=True)
    kept = d.plan()
    assert kept.expansions == 0 and kept.cell_checks == 0
    assert np.array_equal(kept.cells, r.cells[1:]) and abs(kept.cost - 11.0) <= 1e-12
    d.update(world.set_cells([[6, 3, 1]], True), blocked=True)  # on the path
    again = d.plan()
    assert abs(again.cost - _astar_cost(world, d.start, [12, 3, 1], "full")) <= 1e-9
    assert world.is_free(again.cells).all() and not (again.cells == [6, 3, 1]).all(1).any()
    d.update(world.set_cells([[6, 0, 0]], False), blocked=False)  # a freed cell repairs
    assert abs(d.plan().cost - _astar_cost(world, d.start, [12, 3, 1], "full")) <= 1e-9


def test_plan_phases_plans_as_plan_does_and_times_each_phase_it_ran():
    """plan_phases() runs each phase of a replan as its own call: the same paths, costs
    and counts as plan() on the same changes, a time for each phase that ran, NaN for the
    others, and all NaN for the plan whose search had to grow the node table."""
    rng = np.random.default_rng(3)
    lat = Lattice.named("bcc", 1.0)
    worlds = [World(lat, np.zeros((0, 3), np.int64), [[0, 0, 0], [30, 30, 6]])
              for _ in range(2)]
    cells = _in_bounds_cells(worlds[0])
    assert len(cells) > 4096  # more than the planner's first node table
    walls = cells[rng.random(len(cells)) < 0.1]
    for w in worlds:
        w.set_cells(walls, blocked=True)
    free = _free_cells(worlds[0])
    start, goal = free[0], free[-1]
    ends = np.array([start, goal])
    # the start walled in: the first search (from the goal) floods the whole world, past
    # 4096 nodes
    d = np.linalg.norm(lat.to_world(cells) - lat.to_world(start[None]), axis=1)
    shell = cells[(d > 0) & (d < 2.5)]
    for w in worlds:
        w.set_cells(shell, blocked=True)
    plain, phased = (DStarLite(w, start, goal) for w in worlds)
    ran = {"grew": 0, "repair": 0, "kept": 0}
    for batch in range(10):
        want = plain.plan()
        got, secs = phased.plan_phases()
        assert np.array_equal(got.cells, want.cells) and got.cost == want.cost, batch
        assert (got.cell_checks, got.expansions) == (want.cell_checks, want.expansions)
        assert secs.shape == (4,)
        if batch == 0:  # nothing to repair; the flood grew the node table
            assert not got.found and phased.nodes > 4096
        if np.isnan(secs).all():  # kept the stored path (no check), or grew its arrays
            ran["kept" if want.cell_checks == 0 else "grew"] += 1
        else:
            assert (secs > 0).all(), (batch, secs)
            ran["repair"] += 1
        on_path = want.cells[1:-1]
        far = cells[rng.random(len(cells)) < 0.01]
        far = far[~(far[:, None] == ends[None]).all(2).any(1)]
        block = on_path[rng.random(len(on_path)) < 0.2] if batch % 3 else on_path[:0]
        for w, p in zip(worlds, (plain, phased), strict=True):
            if batch == 0:
                p.update(w.set_cells(shell, False), blocked=False)
            p.update(w.set_cells(block, True), blocked=True)
            if batch % 3 == 0:
                p.update(w.set_cells(far, True), blocked=True)
            elif batch % 3 == 1:
                p.update(w.set_cells(far, False), blocked=False)
    assert ran["repair"] >= 3 and ran["grew"] >= 1, ran


def test_profiling_counters_say_what_a_replan_read_and_repaired():
    # pending_check_lines: the cache lines a kept replan's check of the pending cells
    # reads, with the per-cell rest map alone and with the 4x4x4 block map first (one
    # line of blocks, plus the cell line of a cell whose block holds the path).
    # last_repair: the nodes the last plan collected and those that lost every edge.
    world = World(Lattice.named("cubic", 1.0), [], [[0, 0, 0], [12, 6, 2]])
    d = DStarLite(world, [0, 3, 1], [12, 3, 1])
    assert d.pending_check_lines() == (0, 0) and d.last_repair == (0, 0)
    d.plan()
    d.update(world.set_cells([[12, 6, 2]], True), blocked=True)  # far from the path
    assert d.pending_check_lines() == (1, 1)
    d.plan()
    assert d.last_repair == (0, 0)  # kept the stored path: nothing repaired
    d.update(world.set_cells([[6, 3, 1]], True), blocked=True)  # under the path
    assert d.pending_check_lines() == (1, 2)
    d.plan()
    rep = d.last_repair
    assert rep.collected >= 2 and 1 <= rep.died <= rep.collected  # the cell's own node
    d.update(np.array([[100, 100, 100]]), blocked=True)  # outside the box: reads nothing
    assert d.pending_check_lines() == (0, 0)
