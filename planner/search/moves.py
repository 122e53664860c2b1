"""Move sets of the lattice search: moves, the cells each needs free, and the A* heuristic.

Movement rule (default, "safe"): a move from ``u`` to ``u + delta`` is allowed only if every
cell whose *closed* Voronoi cell the segment between the two centres touches is free. The
touched offsets are translation invariant, so they are computed once per lattice and
neighbour set with the exact segment walk (:func:`move_stencils`). On the cubic lattice with
26 neighbours this is exactly the MovingAI "no corner cutting" rule (a diagonal move needs
every voxel of its bounding box free). ``corner_cutting=True`` checks the target cell only.

Radius guarantee (:func:`carries_guarantee`): on a world whose blocked cells are the exact
inflation by the robot radius r, a path whose every segment touches only free cells keeps
distance >= r from every obstacle point. The safe rule checks exactly those cells, for every
neighbour set (``face``, ``full``, ``face+k``, ``full+k``) and every method (any-angle
parents are accepted by the same exact walk), so the guarantee holds whenever
``corner_cutting`` is False. With ``corner_cutting=True`` it holds only for move sets whose
segments touch no cell but their two end cells (then both rules coincide; e.g. ``face`` on
the cubic lattice); otherwise results carry ``guarantee=False``.

Heuristic (A*): the exact obstacle-free cost with the given move set, the LP value
``h(x) = min {sum l_i |s_i| : sum l_i s_i = x, l >= 0}``, i.e. the gauge of the polytope
``conv{s_i / |s_i|}``: ``h(x) = max_f n_f . x`` over its facets ``{y : n_f . y <= 1}``.
It is a norm (so consistent) and the tightest move-set-only bound; on cubic-26 it equals the
octile distance. Any-angle searches use the Euclidean distance.
"""

from __future__ import annotations

from functools import lru_cache
from typing import NamedTuple

import numpy as np

from planner._numba import njit_cached
from planner.lattice import Lattice
from planner.occupancy.grid import Occupancy
from planner.occupancy.walk import segment_walk, walk_of
from planner.search.heuristic import H_GAUGE

__all__ = ["MoveSet", "move_allowed", "move_set", "move_stencils", "move_heuristic",
           "path_excess", "carries_guarantee"]



class MoveSet(NamedTuple):
    """Kernel view of a move set with its heuristic. Arrays C-contiguous and writable (one
    numba type for every lattice); shared between searches, never written."""

    moves: np.ndarray  # (M, 3) int64 index offsets
    cost: np.ndarray  # (M,) float64 move lengths (m)
    union: np.ndarray  # (U, 3) int64 every offset some move needs free
    ptr: np.ndarray  # (M + 1,) int64 CSR: move m needs union[idx[ptr[m]:ptr[m + 1]]] free
    idx: np.ndarray  # (nnz,) int64
    hmat: np.ndarray  # (F, 3) float64 heuristic facets in index coordinates
    hkind: int  # H_ZERO (Dijkstra), H_GAUGE (A*) or H_EUCLID (any-angle)
    need: np.ndarray  # (M,) int64 bit u set iff move m needs union[u] free (U <= 63)
    octile: float  # > 0: H_GAUGE in closed form, the octile distance of this cell size (m)


@njit_cached(_nrt=False)
def move_allowed(ufree, ptr, idx, m):  # pragma: no cover - compiled
    """Move ``m`` is allowed: every cell it needs is free (``ufree``: the union stencil's
    lookups around the expanded cell)."""
    for e in range(ptr[m], ptr[m + 1]):
        if not ufree[idx[e]]:
            return False
    return True


@njit_cached(_nrt=False, inline="always")
def move_open(bits, need, blocked, ufree, ptr, idx, m):  # pragma: no cover - compiled
    """Move ``m`` is allowed, read from the expanded cell's stencil lookups: with the union
    stencil as a bit mask (``bits``; at most :data:`MAX_BITS` cells) one test of
    ``need[m]`` against the ``blocked`` mask, else :func:`move_allowed` on ``ufree``.
    Inlined: in a loop compiled with ``bits`` constant, one of the two tests is left."""
    if bits:
        return need[m] & blocked == 0
    return move_allowed(ufree, ptr, idx, m)


def _empty_occupancy(g: np.ndarray) -> Occupancy:
    """Everything free (the hash mode with an empty set and unbounded box): the walk then
    only enumerates touched cells."""
    big = np.full(3, np.inf)
    return Occupancy(mode=1, grid=np.zeros(1, np.uint8), lo=np.zeros(3, np.int64),
                     dims=np.zeros(3, np.int64), table=np.full(16, -1, np.int64), tmask=15,
                     gmat=g, blo=-big, bhi=big.copy())


@lru_cache(maxsize=64)
def _stencils_cached(gen: bytes, neighbors: str, corner_cutting: bool, lat: Lattice):
    moves = np.ascontiguousarray(lat.neighbors(neighbors), dtype=np.int64)
    walk = walk_of(lat)
    occ = _empty_occupancy(walk.g)
    per_move = []
    for d in moves:
        if corner_cutting:
            per_move.append(d[None].copy())
            continue
        cells, _, _ = segment_walk(occ, walk, np.zeros(3), walk.g @ d.astype(float),
                                   np.zeros(3, np.int64), False)
        cells = cells[np.any(cells != 0, axis=1)]  # the current cell is known free
        per_move.append(cells[np.lexsort(cells.T[::-1])])
    union = np.unique(np.concatenate(per_move), axis=0)
    # Order the union by length so that lookups walk outward (cache friendly on dense grids).
    union = union[np.argsort(np.linalg.norm(union @ walk.g.T, axis=1), kind="stable")]
    index = {tuple(u): i for i, u in enumerate(union.tolist())}
    ptr = np.zeros(len(moves) + 1, dtype=np.int64)
    idx = []
    for m, cells in enumerate(per_move):
        idx.extend(index[tuple(c)] for c in cells.tolist())
        ptr[m + 1] = len(idx)
    cost = np.linalg.norm(moves @ walk.g.T, axis=1)
    return (moves, cost, np.ascontiguousarray(union), ptr, np.array(idx, dtype=np.int64),
            per_move)


def _readonly(a: np.ndarray) -> np.ndarray:
    v = a.view()
    v.setflags(write=False)
    return v


def move_stencils(lattice: Lattice, neighbors: str = "full", corner_cutting: bool = False):
    """Moves and the cells each needs free.

    Returns
    -------
    moves : ndarray (M, 3) int64
        Index offsets.
    cost : ndarray (M,) float64
        Move lengths (m).
    union : ndarray (U, 3) int64
        Every offset some move needs (the per-expansion lookup stencil).
    ptr, idx : ndarray int64
        CSR: move ``m`` needs ``union[idx[ptr[m]:ptr[m + 1]]]`` free.
    per_move : list of ndarray (k_m, 3) int64
        The same offsets per move (the start cell excluded, the target included).

    All arrays are read-only views of cached data.
    """
    got = _stencils_cached(lattice.generator.tobytes(), neighbors, bool(corner_cutting),
                           lattice)
    *arrays, per_move = got
    return (*(_readonly(a) for a in arrays), [_readonly(p) for p in per_move])


@lru_cache(maxsize=64)
def _facets_cached(gen: bytes, neighbors: str, lat: Lattice) -> np.ndarray:
    from scipy.spatial import ConvexHull

    moves = lat.neighbors(neighbors)
    s = moves @ lat.generator.T
    u = s / np.linalg.norm(s, axis=1, keepdims=True)
    if np.allclose(s[:, 2], 0):  # planar moves (2D map on a prism): the bipyramid with
        u = np.concatenate([u, [[0, 0, 1], [0, 0, -1]]])  # +-z has the polygon's in-plane gauge
    hull = ConvexHull(u)
    eq = hull.equations  # n . y + off <= 0 inside, |n| = 1
    n = eq[:, :3] / (-eq[:, 3:4])
    n = np.unique(np.round(n, 12), axis=0)  # merge coplanar triangles
    return np.array(n @ lat.generator, dtype=float, order="C")  # h(w) = max hm . w


def move_heuristic(lattice: Lattice, neighbors: str = "full") -> np.ndarray:
    """Facets of the move-set gauge in index coordinates.

    Returns
    -------
    ndarray, shape (F, 3)
        ``h(w) = max(0, max_f F[f] . w)`` (m) for an index difference ``w`` is the
        obstacle-free shortest path length with these moves. Read-only.
    """
    return _readonly(_facets_cached(lattice.generator.tobytes(), neighbors, lattice))


def path_excess(lattice: Lattice, neighbors: str = "full") -> float:
    """The most an obstacle-free shortest path with these moves is longer than the straight
    line, as a ratio over every direction (1 would be the straight line itself): the
    largest facet normal of the move-set gauge in world coordinates, ``max_f |F[f] G^-1|``
    with ``F`` :func:`move_heuristic`'s facets and ``G`` the generator (the gauge of a
    direction along that normal is its length times the normal's length). Cubic with 26
    neighbours: sqrt(1 + (sqrt 2 - 1)^2 + (sqrt 3 - sqrt 2)^2), about 1.13."""
    normals = move_heuristic(lattice, neighbors) @ np.linalg.inv(lattice.generator)
    return float(np.linalg.norm(normals, axis=1).max())


_NO_FACETS = np.zeros((1, 3))
MAX_BITS = 63  # union stencils up to this size get one bitmask test per move


def _need_bits(ptr: np.ndarray, idx: np.ndarray, nu: int) -> np.ndarray:
    """Per move, the bitmask of the union cells it needs (zeros when U > MAX_BITS: the
    kernel then tests the CSR lists)."""
    need = np.zeros(len(ptr) - 1, dtype=np.int64)
    if nu <= MAX_BITS:
        for m in range(len(need)):
            for u in idx[ptr[m]:ptr[m + 1]]:
                need[m] |= 1 << int(u)
    return need


def _octile_step(lat: Lattice, moves: np.ndarray) -> float:
    """Cell size when the move-set gauge is the octile distance (cubic, 26 neighbours):
    the kernel then evaluates it in closed form instead of the facet maximum."""
    g = lat.generator
    s = float(g[0, 0])
    cube = {(i, j, k) for i in (-1, 0, 1) for j in (-1, 0, 1) for k in (-1, 0, 1)} - {(0, 0, 0)}
    if np.array_equal(g, s * np.eye(3)) and {tuple(m) for m in moves.tolist()} == cube:
        return s
    return 0.0


@lru_cache(maxsize=256)
def _move_set_cached(gen: bytes, neighbors: str, corner_cutting: bool, hkind: int,
                     lat: Lattice) -> MoveSet:
    moves, cost, union, ptr, idx, _ = _stencils_cached(gen, neighbors, corner_cutting, lat)
    hmat = _facets_cached(gen, neighbors, lat) if hkind == H_GAUGE else _NO_FACETS
    octile = _octile_step(lat, moves) if hkind == H_GAUGE else 0.0
    return MoveSet(moves=moves, cost=cost, union=union, ptr=ptr, idx=idx, hmat=hmat,
                   hkind=hkind, need=_need_bits(ptr, idx, len(union)), octile=octile)


_BY_ID: dict[tuple, tuple[Lattice, MoveSet]] = {}  # lattice identity -> (lattice, move set)


def move_set(lattice: Lattice, neighbors: str, corner_cutting: bool, hkind: int) -> MoveSet:
    """The kernel's :class:`MoveSet` (cached per lattice, neighbour set, rule, heuristic)."""
    key = (id(lattice), neighbors, bool(corner_cutting), int(hkind))
    hit = _BY_ID.get(key)
    if hit is not None:
        held, ms = hit
        if held is lattice:  # a search's common case, without hashing
            return ms
    ms = _move_set_cached(lattice.generator.tobytes(), neighbors, bool(corner_cutting),
                          int(hkind), lattice)
    if len(_BY_ID) >= 256:
        _BY_ID.clear()
    _BY_ID[key] = (lattice, ms)
    return ms


def carries_guarantee(lattice: Lattice, neighbors: str, corner_cutting: bool) -> bool:
    """Does a search with these moves keep the radius guarantee (module docstring)?

    True with the safe rule; with corner cutting only if every move's segment touches no
    cell but its end cells (the safe rule then checks the same single cell).
    """
    if not corner_cutting:
        return True
    safe = _stencils_cached(lattice.generator.tobytes(), neighbors, False, lattice)[5]
    return all(len(c) == 1 for c in safe)
