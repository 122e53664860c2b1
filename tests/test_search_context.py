"""A thread's search arrays between searches (``planner.search.astar._context``): a query
loop on one dense grid grows them once, not on every long query; elsewhere a long search's
arrays are dropped afterwards. A query loop that takes turns between worlds makes each
world's bound once."""

from __future__ import annotations

import numpy as np

from planner import search as S
from planner.lattice import Lattice
from planner.search.astar import _context as C
from planner.world import World


def _open_box(dims):
    lat = Lattice.named("cubic", 1.0)
    return World(lat, np.empty((0, 3), np.int64), np.array([[0.0] * 3, np.subtract(dims, 1.0)]))


def _arrays():
    """The node keys and heap slots of the context holding a grid (the one that searched)."""
    ctx = next(c for c in C._CONTEXTS if c.held is not None)
    return ctx.nodes.key, ctx.heap.slot


def test_a_query_loop_on_a_dense_grid_keeps_its_grown_arrays():
    # 2.56 M cells: a 10 MB dense slot array, room for the node table and heap that a
    # search of 70,000 expansions grows (131,072 slots, 8.4 MB)
    w = _open_box((160, 160, 100))
    s, g = np.array([80, 80, 50]), np.array([159, 159, 99])
    first = S.search(w, s, g, method="dijkstra", max_expansions=70_000)
    assert first.generated > C.KEEP_NODES
    nodes, heap = _arrays()
    assert len(nodes) > C.KEEP_NODES  # kept: their bytes fit in the dense slot array's
    again = S.search(w, s, g, method="dijkstra", max_expansions=70_000)
    assert again.generated == first.generated and again.expansions == first.expansions
    assert _arrays()[0] is nodes and _arrays()[1] is heap  # not grown again


def test_long_search_arrays_are_dropped_without_room():
    ctx = C._Context()
    ctx.nodes, ctx.heap = C.new_nodes(4 * C.KEEP_NODES), C.new_heap(4 * C.KEEP_NODES)
    ctx.keep(10**6)  # fewer bytes than the grown arrays: they go
    assert len(ctx.nodes.key) <= C.KEEP_NODES and len(ctx.heap.slot) <= C.KEEP_NODES
    big = C.new_nodes(4 * C.KEEP_NODES)
    ctx.nodes = big
    ctx.keep(10**9)  # room enough: kept
    assert ctx.nodes is big


def test_taking_turns_between_worlds_makes_each_bound_once():
    worlds = [_open_box((12, 10, 8)), _open_box((9, 9, 9))]
    s, g = np.array([1, 1, 1]), np.array([7, 7, 7])
    for w in worlds:  # (a context that held grown arrays drops them, and its bounds, once)
        S.search(w, s, g)
        S.search(w, s, g)
    ctx = next(c for c in C._CONTEXTS if c.held is not None and c.bound.occ is
               worlds[-1].checker.occupancy)
    made = {id(m.occ): m.bound for m in ctx.bounds.values()}
    assert {id(w.checker.occupancy) for w in worlds} <= made.keys()
    for _ in range(3):
        for w in worlds:
            assert S.search(w, s, g).found
            assert ctx.bound.bound is made[id(w.checker.occupancy)]  # the kept one
