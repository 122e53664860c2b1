"""Graph search over lattice cells: A*, Dijkstra, Theta*, Lazy Theta*, path shortcutting.

Nodes are lattice cells, edges the offsets ``lattice.neighbors(neighbors)``, edge cost the
Euclidean distance between cell centres (m).

Movement rule (default, "safe"): a move from ``u`` to ``u + delta`` is allowed only if every
cell whose *closed* Voronoi cell the segment between the two centres touches is free. The
touched offsets are translation invariant, so they are computed once per lattice and
neighbour set with the exact segment walk (:func:`move_stencils`). On the cubic lattice with
26 neighbours this is exactly the MovingAI "no corner cutting" rule (a diagonal move needs
every voxel of its bounding box free). ``corner_cutting=True`` checks the target cell only.

Heuristic (A*): the exact obstacle-free cost with the given move set, the LP value
``h(x) = min {sum l_i |s_i| : sum l_i s_i = x, l >= 0}``, i.e. the gauge of the polytope
``conv{s_i / |s_i|}``: ``h(x) = max_f n_f . x`` over its facets ``{y : n_f . y <= 1}``.
It is a norm (so consistent) and the tightest move-set-only bound; on cubic-26 it equals the
octile distance. Any-angle searches use the Euclidean distance.
"""

from __future__ import annotations

import itertools
import math
import time
from dataclasses import dataclass, field
from functools import lru_cache

import numpy as np
from scipy.spatial import ConvexHull

from planner import _search_kernels as sk
from planner.errors import PlanError
from planner.keys import unpack
from planner.lattice import Lattice
from planner.world import World, _cells, _walk_data

__all__ = ["SearchResult", "search", "shortcut", "move_stencils", "move_heuristic", "METHODS"]

METHODS = ("astar", "dijkstra", "theta", "lazy-theta")
_ANYANGLE = {"astar": 0, "dijkstra": 0, "theta": 1, "lazy-theta": 2}
NX_NODE_CAP = 1_000_000
_NO_FACETS = np.zeros((1, 3))
_NO_FACETS.setflags(write=False)  # same numba type as the cached facets: one compilation


@dataclass
class SearchResult:
    """Outcome of one search.

    Attributes
    ----------
    found : bool
    cells : ndarray, shape (K, 3), int64
        Path cells from start to goal (any-angle methods: only the turning cells).
        Empty when not found.
    cost : float
        Path length between cell centres (m); ``inf`` when not found.
    cell_checks : int
        Occupancy lookups made by this search (each actual lookup counted once).
    expansions : int
        Nodes removed from the open list (the goal included).
    generated : int
        Distinct nodes created (start included).
    seconds : float
        Wall time of the search (numba backend: the kernel call; networkx: build + search).
    peak_bytes : int
        Peak size of the search's own arrays (node table, heap, hash table).
    reason : str
        Why no path was found ("" when found).
    """

    found: bool
    cells: np.ndarray
    cost: float
    cell_checks: int
    expansions: int
    generated: int
    seconds: float
    peak_bytes: int
    reason: str = ""
    extra: dict = field(default_factory=dict)


# -- per (lattice, neighbour set) precomputation -------------------------------------------
@lru_cache(maxsize=64)
def _stencils_cached(gen: bytes, neighbors: str, corner_cutting: bool, lat: Lattice):
    moves = lat.neighbors(neighbors)
    g, rel, rhs, full = _walk_data(lat)
    occ = World(lat, np.zeros((0, 3), np.int64), np.zeros((2, 3)), dense_budget=0).occupancy
    per_move = []
    for d in moves:
        if corner_cutting:
            per_move.append(d[None].copy())
            continue
        cells, _, _ = sk.segment_walk(occ, np.zeros(3), g @ d.astype(float),
                                      np.zeros(3, np.int64), g, rel, rhs, full, False)
        cells = cells[np.any(cells != 0, axis=1)]  # the current cell is known free
        per_move.append(cells[np.lexsort(cells.T[::-1])])
    union = np.unique(np.concatenate(per_move), axis=0)
    # Order the union by length so that lookups walk outward (cache friendly on dense grids).
    union = union[np.argsort(np.linalg.norm(union @ g.T, axis=1), kind="stable")]
    index = {tuple(u): i for i, u in enumerate(union.tolist())}
    ptr = np.zeros(len(moves) + 1, dtype=np.int64)
    idx = []
    for m, cells in enumerate(per_move):
        idx.extend(index[tuple(c)] for c in cells.tolist())
        ptr[m + 1] = len(idx)
    cost = np.linalg.norm(moves @ g.T, axis=1)
    out = (moves, cost, union, ptr, np.array(idx, dtype=np.int64), per_move)
    for a in out[:5]:
        a.setflags(write=False)
    return out


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
    """
    return _stencils_cached(lattice.generator.tobytes(), neighbors, bool(corner_cutting),
                            lattice)


@lru_cache(maxsize=64)
def _facets_cached(gen: bytes, neighbors: str, lat: Lattice) -> np.ndarray:
    moves = lat.neighbors(neighbors)
    s = moves @ lat.generator.T
    u = s / np.linalg.norm(s, axis=1, keepdims=True)
    hull = ConvexHull(u)
    eq = hull.equations  # n . y + off <= 0 inside, |n| = 1
    n = eq[:, :3] / (-eq[:, 3:4])
    n = np.unique(np.round(n, 12), axis=0)  # merge coplanar triangles
    hm = np.ascontiguousarray(n @ lat.generator)  # index coordinates: h(w) = max hm . w
    hm.setflags(write=False)
    return hm


def move_heuristic(lattice: Lattice, neighbors: str = "full") -> np.ndarray:
    """Facets of the move-set gauge in index coordinates.

    Returns
    -------
    ndarray, shape (F, 3)
        ``h(w) = max(0, max_f F[f] . w)`` (m) for an index difference ``w`` is the
        obstacle-free shortest path length with these moves.
    """
    return _facets_cached(lattice.generator.tobytes(), neighbors, lattice)


# -- search --------------------------------------------------------------------------------
def _check_endpoint(world: World, cell: np.ndarray, what: str) -> None:
    if world.is_free(cell[None])[0]:
        return
    lat = world.lattice
    where = "blocked" if world.in_bounds(cell[None])[0] else "outside the bounds"
    near = world.nearest_free(cell)
    c = np.round(lat.to_world(cell[None])[0], 6).tolist()
    hint = "no free cell nearby"
    if near is not None:
        hint = (f"nearest free cell {near.tolist()} at "
                f"{np.round(lat.to_world(near[None])[0], 6).tolist()}")
    raise PlanError(f"{what} cell {cell.tolist()} (centre {c} m) is {where}; {hint}")


def search(
    world: World,
    start_cell: np.ndarray,
    goal_cell: np.ndarray,
    *,
    method: str = "astar",
    neighbors: str = "full",
    corner_cutting: bool = False,
    backend: str = "numba",
    max_nodes: int | None = None,
) -> SearchResult:
    """Shortest path between two cells.

    Parameters
    ----------
    world : World
    start_cell, goal_cell : array_like of int, shape (3,)
        Lattice indices; both must be free (else PlanError naming which, where, and the
        nearest free cell).
    method : {"astar", "dijkstra", "theta", "lazy-theta"}
    neighbors : str
        ``lattice.neighbors`` kind: ``face``, ``full``, ``face+k``, ``full+k``.
    corner_cutting : bool
        False: the safe rule (module docstring); True: only the target cell is checked.
    backend : {"numba", "networkx"}
        ``networkx`` (A*/Dijkstra only) builds the explicit free-cell graph of the start's
        component (at most ``max_nodes`` or 1,000,000 cells) and runs
        ``networkx.astar_path``: a slow readable reference.
    max_nodes : int, optional
        Give up (found=False) after creating this many nodes.

    Returns
    -------
    SearchResult
        Lookups are also added to ``world.cell_checks``.
    """
    if method not in METHODS:
        raise PlanError(f"unknown method {method!r}; expected one of {', '.join(METHODS)}")
    if backend not in ("numba", "networkx"):
        raise PlanError(f"unknown backend {backend!r}; expected numba or networkx")
    s = _cells(start_cell)[0]
    gl = _cells(goal_cell)[0]
    _check_endpoint(world, s, "start")
    _check_endpoint(world, gl, "goal")
    lat = world.lattice
    moves, mcost, union, ptr, idx, _ = move_stencils(lat, neighbors, corner_cutting)
    anyangle = _ANYANGLE[method]
    if method == "dijkstra":
        hkind, hmat = 0, _NO_FACETS
    elif anyangle:
        hkind, hmat = 2, _NO_FACETS
    else:
        hkind, hmat = 1, move_heuristic(lat, neighbors)
    if backend == "networkx":
        if anyangle:
            raise PlanError("the networkx backend supports astar and dijkstra only")
        return _search_networkx(world, s, gl, moves, mcost, union, ptr, idx, hkind, hmat,
                                max_nodes or NX_NODE_CAP)
    g, rel, rhs, full = _walk_data(lat)
    occ = world.occupancy
    t0 = time.perf_counter()
    status, keys, cost, st, peak = _run(occ, s, gl, moves, mcost, union, ptr, idx, hmat, hkind,
                                        anyangle, g, rel, rhs, full, int(max_nodes or 0),
                                        _span(world) if anyangle else 0.0)
    secs = time.perf_counter() - t0
    exp, gen, look = int(st[sk.ST_EXP]), int(st[sk.ST_N]), int(st[sk.ST_LOOK])
    world.cell_checks += look
    checks = look + 2  # and the two endpoint checks
    if status == sk.RUN_FOUND:
        return SearchResult(True, unpack(keys, 3), float(cost), checks, exp, gen, secs, peak)
    reason = (f"goal unreachable: explored {gen} cells" if status == sk.RUN_EXHAUSTED
              else f"node limit {max_nodes} reached after {exp} expansions")
    return SearchResult(False, np.zeros((0, 3), np.int64), math.inf, checks, exp, gen, secs,
                        peak, reason)


_F8 = ("ng", "nf", "nh", "hf", "hg")


def _span(world: World) -> float:
    """Longest line of sight inside the world (m): sizes the any-angle walk scratch."""
    return float(np.linalg.norm(world.bounds[1] - world.bounds[0]))


def _run(occ, s, gl, moves, mcost, union, ptr, idx, hmat, hkind, anyangle, g, rel, rhs, full,
         max_nodes, span, cap=4096):
    """Drive the resumable kernel, doubling the node arrays / hash table when it asks."""
    arrs = {k: np.empty(cap, np.float64 if k in _F8 else np.int64)
            for k in ("nkey", "ng", "nf", "nh", "npar", "npos", "heap", "hf", "hg")}
    pcap = 64  # pages (sk.PAGE slots each) of the cell -> node slot map
    pages = np.empty(pcap * sk.PAGE, np.int32)
    bkeys = np.empty(pcap, np.int64)
    btab = np.full(2 * pcap, -1, np.int64)
    st = np.zeros(7, np.int64)
    wvis, wgen, wq = sk.walk_scratch(span, math.sqrt(2.0 * rhs.min()), len(full))
    wv = rel @ g
    ufree = np.empty(len(union), np.bool_)
    sk.search_init(s, gl, arrs["nkey"], arrs["ng"], arrs["nf"], arrs["nh"], arrs["npar"],
                   arrs["npos"], arrs["heap"], arrs["hf"], arrs["hg"], pages, btab, bkeys,
                   hmat, hkind, g, st)
    while True:
        status = sk.search_run(
            occ, gl, st, arrs["nkey"], arrs["ng"], arrs["nf"], arrs["nh"], arrs["npar"],
            arrs["npos"], arrs["heap"], arrs["hf"], arrs["hg"], pages, btab, bkeys, ufree,
            moves, mcost, union, ptr, idx, hmat, hkind, anyangle, g, rel, rhs, full, max_nodes,
            wv, wvis, wgen, wq,
        )
        if status != sk.RUN_GROW:
            break
        n, npg = int(st[sk.ST_N]), int(st[sk.ST_NP])
        if n + len(moves) > cap:
            cap *= 2
            for k, a in arrs.items():
                b = np.empty(cap, a.dtype)
                b[:n] = a[:n]
                arrs[k] = b
        if npg + len(moves) > pcap or 2 * (npg + len(moves)) > len(btab):
            pcap *= 2
            b = np.empty(pcap * sk.PAGE, np.int32)
            b[: npg * sk.PAGE] = pages[: npg * sk.PAGE]
            pages = b
            b = np.empty(pcap, np.int64)
            b[:npg] = bkeys[:npg]
            bkeys = b
            btab = np.full(2 * pcap, -1, np.int64)
            sk.rehash(btab, bkeys, npg)
    peak = (sum(a.nbytes for a in arrs.values()) + pages.nbytes + bkeys.nbytes + btab.nbytes
            + ufree.nbytes + st.nbytes + wvis.nbytes + wgen.nbytes + wq.nbytes)
    if status != sk.RUN_FOUND:
        return status, None, math.inf, st, peak
    gs = int(st[sk.ST_GOAL])
    return status, sk.trace_path(arrs["nkey"], arrs["npar"], gs), arrs["ng"][gs], st, peak


def shortcut(world: World, cells: np.ndarray) -> np.ndarray:
    """Greedy line-of-sight shortcutting of a cell path.

    From each kept cell, jump to the farthest later cell that is still in sight (every cell
    the centre-to-centre segment touches is free, the safe rule), scanning forward until
    the first cell out of sight. The result keeps the first and last cell, is a
    subsequence of the input, and each consecutive pair is in sight (or was consecutive in
    the input). Lookups are added to ``world.cell_checks``.

    Parameters
    ----------
    cells : array_like of int, shape (K, 3)

    Returns
    -------
    ndarray, shape (K', 3), int64
    """
    c = _cells(cells)
    if len(c) <= 2:
        return c.copy()
    g, rel, rhs, full = _walk_data(world.lattice)
    keep, n = sk.shortcut_kernel(world.occupancy, c, g, rel, rhs, full)
    world.cell_checks += int(n)
    return c[keep]


# -- networkx reference --------------------------------------------------------------------
def _search_networkx(world, s, gl, moves, mcost, union, ptr, idx, hkind, hmat, cap):
    """Explicit graph of the start's free component (BFS over allowed moves), then
    networkx A*. Readable and slow; for cross-checking the numba kernel."""
    import networkx as nx

    t0 = time.perf_counter()
    before = world.cell_checks
    graph = nx.Graph()
    start, goal = tuple(s.tolist()), tuple(gl.tolist())
    graph.add_node(start)
    seen = {start}
    queue = [start]
    needs = [idx[ptr[m]:ptr[m + 1]] for m in range(len(moves))]
    moves_l = moves.tolist()
    while queue:
        if len(seen) > cap:
            raise PlanError(f"networkx backend: the start's component exceeds {cap} cells; "
                            "use backend='numba'")
        u = queue.pop()
        free = world.is_free(np.asarray(u) + union)
        for m, d in enumerate(moves_l):
            if not free[needs[m]].all():
                continue
            v = (u[0] + d[0], u[1] + d[1], u[2] + d[2])
            graph.add_edge(u, v, weight=float(mcost[m]))
            if v not in seen:
                seen.add(v)
                queue.append(v)
    checks = world.cell_checks - before + 2

    def h(a, b):
        if hkind == 0:
            return 0.0
        d = np.subtract(b, a)
        return max(0.0, float((hmat @ d).max()))

    if goal not in graph:
        return SearchResult(False, np.zeros((0, 3), np.int64), math.inf, checks, 0,
                            graph.number_of_nodes(), time.perf_counter() - t0, 0,
                            f"goal unreachable: explored {graph.number_of_nodes()} cells")
    path = nx.astar_path(graph, start, goal, heuristic=h, weight="weight")
    cost = float(sum(graph[a][b]["weight"] for a, b in itertools.pairwise(path)))
    return SearchResult(True, np.array(path, dtype=np.int64).reshape(-1, 3), cost, checks,
                        0, graph.number_of_nodes(), time.perf_counter() - t0, 0)
