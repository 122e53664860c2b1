"""A thread's search arrays between searches (``planner.search.astar._context``): a query
loop on one dense grid grows them once, not on every long query; elsewhere a long search's
arrays are dropped afterwards. A query loop that takes turns between worlds finds each
world's context as it left it."""

from __future__ import annotations

import numpy as np

from planner import search as S
from planner.lattice import Lattice
from planner.search.astar import _context as C
from planner.world import World


def _open_box(dims):
    lat = Lattice.named("cubic", 1.0)
    return World(lat, np.empty((0, 3), np.int64), np.array([[0.0] * 3, np.subtract(dims, 1.0)]))


def _arrays(world):
    """The node keys and heap slots of the context holding ``world``'s grid (the one that
    searched it: a thread keeps several contexts)."""
    grid = world.checker.occupancy.grid
    ctx = next(c for c in C._CONTEXTS if c.held is not None and c.held.grid is grid)
    return ctx.nodes.key, ctx.heap.slot


def test_a_query_loop_on_a_dense_grid_keeps_its_grown_arrays():
    # 2.56 M cells: a 10 MB dense slot array, room for the node table and heap that a
    # search of 70,000 expansions grows (131,072 slots, 8.4 MB)
    w = _open_box((160, 160, 100))
    s, g = np.array([80, 80, 50]), np.array([159, 159, 99])
    first = S.search(w, s, g, method="dijkstra", max_expansions=70_000)
    assert first.generated > C.KEEP_NODES
    nodes, heap = _arrays(w)
    assert len(nodes) > C.KEEP_NODES  # kept: their bytes fit in the dense slot array's
    again = S.search(w, s, g, method="dijkstra", max_expansions=70_000)
    assert again.generated == first.generated and again.expansions == first.expansions
    assert _arrays(w)[0] is nodes and _arrays(w)[1] is heap  # not grown again


def test_long_search_arrays_are_dropped_without_room():
    ctx = C._Context()
    ctx.nodes, ctx.heap = C.new_nodes(4 * C.KEEP_NODES), C.new_heap(4 * C.KEEP_NODES)
    ctx.keep(10**6)  # fewer bytes than the grown arrays: they go
    assert len(ctx.nodes.key) <= C.KEEP_NODES and len(ctx.heap.slot) <= C.KEEP_NODES
    big = C.new_nodes(4 * C.KEEP_NODES)
    ctx.nodes = big
    ctx.keep(10**9)  # room enough: kept
    assert ctx.nodes is big


def _last_context():
    """The context the thread's last search ran in (released last)."""
    return C._LOCAL.free[-1]


def test_taking_turns_between_worlds_finds_each_worlds_context_as_it_left_it():
    """Lattices compared query by query: each world's searches run in a context of its own,
    on the bound made for it once, with the answers of a lone search."""
    worlds = [_open_box((12, 10, 8)), _open_box((9, 9, 9)),
              World(Lattice.named("bcc", 1.0), np.empty((0, 3), np.int64), [[0, 0, 0], [8] * 3])]
    ends = [w.lattice.quantize([[1.0, 1, 1], [6.0, 5, 6]]) for w in worlds]
    alone, ctx, bound = [], [], []
    for w, (s, g) in zip(worlds, ends, strict=True):
        alone.append(S.search(w, s, g).cost)
        ctx.append(_last_context())
        bound.append(ctx[-1].fast.bound)
    assert len({id(c) for c in ctx}) == len(worlds)
    for _ in range(3):
        for i, (w, (s, g)) in enumerate(zip(worlds, ends, strict=True)):
            assert S.search(w, s, g).cost == alone[i]
            assert _last_context() is ctx[i] and ctx[i].fast.bound is bound[i]
    assert len(C._LOCAL.free) <= C.CONTEXTS_KEPT


def test_taking_turns_between_move_sets_on_one_world_makes_each_bound_once():
    """One grid's dense slot array stays with one context: searches with another move set
    on the same world run there and find their bound among the context's kept ones."""
    w = _open_box((12, 10, 8))
    s, g = np.array([1, 1, 1]), np.array([7, 7, 7])
    for nb in ("full", "face"):
        S.search(w, s, g, neighbors=nb)
    ctx = _last_context()
    made = {}
    for nb in ("full", "face"):
        S.search(w, s, g, neighbors=nb)
        made[nb] = ctx.bound.bound
    assert made["full"] is not made["face"]
    for _ in range(3):
        for nb in ("full", "face"):
            assert S.search(w, s, g, neighbors=nb).found
            assert _last_context() is ctx and ctx.bound.bound is made[nb]


def test_more_worlds_than_the_thread_keeps_contexts_for():
    """A thread keeps at most CONTEXTS_KEPT free contexts; past that the least recently
    used is taken over, with the same answers."""
    worlds = [_open_box((8 + k, 9, 9)) for k in range(C.CONTEXTS_KEPT + 3)]
    s, g = np.array([1, 1, 1]), np.array([6, 7, 5])
    want = [S.search(w, s, g).cost for w in worlds]
    for _ in range(2):
        assert [S.search(w, s, g).cost for w in worlds] == want
        assert len(C._LOCAL.free) <= C.CONTEXTS_KEPT


def test_reported_memory_does_not_depend_on_the_searches_before(monkeypatch):
    """A search's peak bytes are what it alone would grow: not the larger sight scratch its
    context kept from a Lazy Theta* search with longer sight lines before."""
    monkeypatch.setattr(C, "CONTEXTS_KEPT", 1)  # one context: it carries the history
    monkeypatch.setattr(C._LOCAL, "free", [])
    lat = Lattice.named("bcc", 1.0)

    def box(n):
        return World(lat, np.empty((0, 3), np.int64), [[0, 0, 0], [n, n, n]])

    ends = lat.quantize([[1.0, 1, 1], [5.0, 4, 3]])
    first = S.search(box(6), *ends, method="lazy-theta").peak_bytes
    S.search(box(60), *lat.quantize([[1.0, 1, 1], [55.0, 50, 40]]), method="lazy-theta")
    assert S.search(box(6), *ends, method="lazy-theta").peak_bytes == first
