"""OctoMap binary OcTree (``.bt``): occupied and free leaves as boxes, each with its own size.

A leaf at depth ``d`` of the 16-level tree is a cube of ``2**(16 - d)`` finest voxels per side;
pruned trees store large uniform regions (mostly free space) as a few coarse leaves.  An
occupied leaf is a solid box (not a point at its centre): that is what the map says.  Space no
leaf covers is unknown, so the result's ``unknown_default`` is ``"blocked"``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from planner._numba import njit_cached
from planner.errors import MapError
from planner.io._files import header_lines, read_bytes
from planner.io.obstacles import Obstacles

_MAGIC = "# Octomap OcTree binary file"
_DEPTH = 16
_CENTER = 32768
# Resolutions outside this range are corrupt headers (1e300 overflows cell volumes, 1e-300
# collapses every voxel onto the origin); real maps use 1 mm .. 10 m.
_RES_RANGE = (1e-6, 1e4)


def read_octomap(p: Path) -> Obstacles:
    """Occupied leaves as ``boxes`` and free leaves as ``free_boxes`` (see module doc)."""
    data = read_bytes(p)
    if not data.startswith(_MAGIC.encode()):
        raise MapError(f"{p.name}: not an OctoMap .bt file (first line must be '{_MAGIC}')")
    lines, pos = header_lines(data, p.name, "OctoMap", "data")
    tree_id = size = res = None
    shift = np.zeros(3)
    for line in lines[1:-1]:
        if line.startswith("# planner_shift "):  # planner.export.octomap: tree frame -> ours
            try:
                shift = np.array([float(v) for v in line.split()[2:5]])
            except ValueError:
                raise MapError(f"{p.name}: bad planner_shift line {line[:60]!r}") from None
            if shift.shape != (3,) or not np.isfinite(shift).all():
                raise MapError(f"{p.name}: bad planner_shift line {line[:60]!r}")
            continue
        if not line or line.startswith("#"):
            continue
        key, _, val = line.partition(" ")
        val = val.strip()
        try:
            if key == "id":
                tree_id = val
            elif key == "size":
                size = int(val)
            elif key == "res":
                res = float(val)
            else:
                raise MapError(f"{p.name}: unknown OctoMap header line {line[:40]!r}")
        except ValueError:
            raise MapError(f"{p.name}: bad OctoMap header value {line[:40]!r}") from None
    if tree_id != "OcTree":
        raise MapError(f"{p.name}: unsupported OctoMap tree id {tree_id!r} (need 'OcTree')")
    if size is None or res is None:
        raise MapError(f"{p.name}: OctoMap header lacks 'size' or 'res'")
    if not (_RES_RANGE[0] <= res <= _RES_RANGE[1]):
        raise MapError(f"{p.name}: OctoMap resolution must be positive, between "
                       f"{_RES_RANGE[0]:g} and {_RES_RANGE[1]:g} m, got {res:g}")
    if size <= 0:
        raise MapError(f"{p.name}: OctoMap tree is empty (size {size})")

    stream = np.frombuffer(data, dtype=np.uint8, offset=pos)
    keys, depths, occupied, n_nodes, err, used = _walk(stream)
    if err == 1:
        raise MapError(f"{p.name}: truncated OctoMap: bit stream ends inside the tree")
    if err == 2:
        raise MapError(f"{p.name}: corrupt OctoMap: tree deeper than {_DEPTH} levels")
    if n_nodes != size:
        # OctoMap's own reader rejects this too ("Tree size mismatch").
        raise MapError(f"{p.name}: corrupt OctoMap: header says {size} nodes, stream has "
                       f"{n_nodes}")
    if used != len(stream):  # e.g. a second tree appended: OctoMap files hold one
        raise MapError(f"{p.name}: {len(stream) - used} bytes of trailing data after the "
                       f"OctoMap tree")
    if not occupied.any():
        raise MapError(f"{p.name}: OctoMap has no occupied voxels")
    side = (np.int64(1) << (_DEPTH - depths)).astype(np.float64)
    centres = (keys - _CENTER + side[:, None] / 2) * res + shift  # min-corner key -> centre
    edges = side * res
    return Obstacles(points=np.zeros((0, 3)), boxes=centres[occupied], box_size=res,
                     box_sizes=edges[occupied], free_boxes=centres[~occupied],
                     free_box_sizes=edges[~occupied], bounds=None, resolution=res,
                     source=p.name, unknown_default="blocked")


@njit_cached
def _walk(stream):  # pragma: no cover - compiled
    """Depth-first walk of an OctoMap binary stream with an explicit stack.

    Returns (keys (L, 3) int64 min-corner keys of the leaves, depths (L,) int64, occupied
    (L,) bool, number of tree nodes incl. the root, error: 0 ok, 1 stream ended early,
    2 too deep, bytes of the stream the tree used).  Child states: 0 unknown, 1 free
    leaf, 2 occupied leaf, 3 inner node.
    """
    n = stream.shape[0]
    # Each 2-byte node holds at most 8 leaves, so 4 per byte bounds the leaf count.
    cap = max(8, 4 * n)
    keys = np.empty((cap, 3), np.int64)
    depths = np.empty(cap, np.int64)
    occ = np.empty(cap, np.bool_)
    n_leaves = 0
    # Stack frame: node min-corner key, depth, 16 child-state bits, next child to visit.
    st_key = np.empty((_DEPTH + 1, 3), np.int64)
    st_depth = np.empty(_DEPTH + 1, np.int64)
    st_bits = np.empty(_DEPTH + 1, np.int64)
    st_child = np.empty(_DEPTH + 1, np.int64)
    if n < 2:
        return keys[:0], depths[:0], occ[:0], 0, 1, 0
    top = 0
    st_key[0, 0] = 0
    st_key[0, 1] = 0
    st_key[0, 2] = 0
    st_depth[0] = 0
    st_bits[0] = np.int64(stream[0]) | (np.int64(stream[1]) << 8)
    st_child[0] = 0
    pos = 2
    n_nodes = 1
    while top >= 0:
        i = st_child[top]
        if i == 8:
            top -= 1
            continue
        st_child[top] = i + 1
        state = (st_bits[top] >> (2 * i)) & 3
        if state == 0:  # unknown: no node stored
            continue
        n_nodes += 1
        d = st_depth[top] + 1
        half = np.int64(1) << (_DEPTH - d)
        kx = st_key[top, 0] + (i & 1) * half
        ky = st_key[top, 1] + ((i >> 1) & 1) * half
        kz = st_key[top, 2] + ((i >> 2) & 1) * half
        if state == 3:  # inner node: its 2 bytes come next in the stream
            if d >= _DEPTH:
                return keys[:0], depths[:0], occ[:0], n_nodes, 2, pos
            if pos + 2 > n:
                return keys[:0], depths[:0], occ[:0], n_nodes, 1, pos
            top += 1
            st_key[top, 0] = kx
            st_key[top, 1] = ky
            st_key[top, 2] = kz
            st_depth[top] = d
            st_bits[top] = np.int64(stream[pos]) | (np.int64(stream[pos + 1]) << 8)
            st_child[top] = 0
            pos += 2
        else:  # leaf: 1 free, 2 occupied
            keys[n_leaves, 0] = kx
            keys[n_leaves, 1] = ky
            keys[n_leaves, 2] = kz
            depths[n_leaves] = d
            occ[n_leaves] = state == 2
            n_leaves += 1
    return keys[:n_leaves], depths[:n_leaves], occ[:n_leaves], n_nodes, 0, pos
