"""The blocked cells of a cubic world as an OctoMap binary tree (``.bt``).

An octree can hold only cubes on its own grid, so only a cubic lattice (generator ``h I``)
is written; any other lattice is refused with a one-line error. Leaves are occupied only
(space without a leaf is unknown to OctoMap); eight occupied siblings are pruned into their
parent, as OctoMap itself does.

Alignment: OctoMap puts the centre of the voxel with key ``K`` at ``(K - 32768 + 1/2) res``,
ours put cell ``k`` at ``k h``. The tree uses ``res = h`` and ``K = k + 32768``, so each of
its voxels is exactly one of our cells, and OctoMap's frame is ours shifted by half a cell:
a point ``p`` in the world is at ``p + h/2 (1, 1, 1)`` in the tree (publish that static
transform beside the map). The header says so in a comment line,
``# planner_shift -h/2 -h/2 -h/2`` (OctoMap skips comment lines), which
:func:`planner.io.octomap.read_octomap` applies, so reading the file back gives the cells'
own centres.
"""

from __future__ import annotations

import os

import numpy as np

from planner.errors import MapError
from planner.fsutil import atomic_path

__all__ = ["check_cubic", "check_cubic_name", "octree_stream", "write_octomap"]

_DEPTH = 16
_CENTER = 32768
HEADER = "# Octomap OcTree binary file"


def check_cubic(generator: np.ndarray, what: str = "the world") -> float:
    """The cell edge ``h`` (m) of a cubic generator ``h I`` (3, 3); MapError otherwise."""
    g = np.asarray(generator, dtype=float)
    h = float(g[0, 0]) if g.shape == (3, 3) else 0.0
    if not (h > 0 and np.allclose(g, h * np.eye(3), rtol=0, atol=1e-12 * h)):
        raise MapError(f"{what}: an OctoMap .bt holds cubic cells only; build the world with "
                       f"--lattice cubic")
    return h


def check_cubic_name(lattice, map_path: str) -> None:
    """Refuse a non-cubic ``--lattice`` (a name or a Lattice) before a map is built; a saved
    world is checked once loaded."""
    from planner.world.file import is_world_file  # lazy: numba, scipy

    if is_world_file(map_path):
        return
    if isinstance(lattice, str):
        if lattice != "cubic":
            raise MapError(f"{lattice} lattice: an OctoMap .bt holds cubic cells only; use "
                           f"--lattice cubic")
        return
    check_cubic(lattice.generator, f"{lattice.name or 'custom'} lattice")


def _morton(keys: np.ndarray) -> np.ndarray:
    """(N,) uint64 depth-first order codes of (N, 3) 16-bit keys: at each level the child
    index is x | y << 1 | z << 2, as in OctoMap."""
    k = keys.astype(np.uint64)
    code = np.zeros(len(k), dtype=np.uint64)
    for b in range(_DEPTH):
        for axis in range(3):
            code |= ((k[:, axis] >> np.uint64(b)) & np.uint64(1)) << np.uint64(3 * b + axis)
    return code


def octree_stream(keys: np.ndarray) -> tuple[bytes, int]:
    """OctoMap's depth-first bit stream of occupied voxels ``keys`` (N, 3) in 0..65535, and
    the node count (root included) for the header's ``size``."""
    codes = np.unique(_morton(keys))
    present = {_DEPTH: codes}
    full = {_DEPTH: codes}
    for d in range(_DEPTH - 1, -1, -1):
        parents, counts = np.unique(full[d + 1] >> np.uint64(3), return_counts=True)
        full[d] = parents[counts == 8] if d > 0 else parents[:0]  # the root stays a node
        present[d] = np.unique(present[d + 1] >> np.uint64(3))
    starts, depths, bits = [], [], []
    n_leaves = 0
    for d in range(_DEPTH):
        inner = present[d][~np.isin(present[d], full[d])]
        kids = present[d + 1]
        kids = kids[np.isin(kids >> np.uint64(3), inner)]
        state = np.where(np.isin(kids, full[d + 1]), 2, 3).astype(np.int64)
        n_leaves += int((state == 2).sum())
        slot = (kids & np.uint64(7)).astype(np.int64)
        owner = np.searchsorted(inner, kids >> np.uint64(3))
        b = np.zeros(len(inner), dtype=np.int64)
        np.add.at(b, owner, state << (2 * slot))
        starts.append(inner << np.uint64(3 * (_DEPTH - d)))
        depths.append(np.full(len(inner), d))
        bits.append(b)
    start, depth, b = (np.concatenate(x) for x in (starts, depths, bits))
    order = np.lexsort((depth, start))  # pre-order: a node before its first child
    b = b[order]
    stream = np.empty(2 * len(b), dtype=np.uint8)
    stream[0::2] = b & 0xFF  # children 0-3
    stream[1::2] = b >> 8  # children 4-7
    return stream.tobytes(), len(b) + n_leaves


def write_octomap(out: str | os.PathLike, world) -> int:
    """Write the blocked cells of a cubic ``world`` as an OctoMap ``.bt`` (module docstring),
    atomically; returns the number of cells written."""
    h = check_cubic(world.lattice.generator, str(out))
    cells = np.unique(np.asarray(world.blocked, dtype=np.int64), axis=0)
    if not len(cells):
        raise MapError(f"{out}: the world has no blocked cell to write")
    if cells.min() < -_CENTER or cells.max() >= _CENTER:
        raise MapError(f"{out}: cells beyond +-{_CENTER} cells from the origin do not fit an "
                       f"OctoMap tree; use a larger cell volume")
    stream, size = octree_stream(cells + _CENTER)
    shift = " ".join([repr(-h / 2)] * 3)
    head = (f"{HEADER}\n# cubic cells of edge res, centres at key * res in the world\n"
            f"# planner_shift {shift}\nid OcTree\nsize {size}\nres {h!r}\ndata\n")
    with atomic_path(out) as tmp:
        tmp.write_bytes(head.encode("ascii") + stream)
    return len(cells)
