"""Exact box inflation: the cells closer than r to (rotated) boxes, against an independent
reference (convex hull of the Minkowski difference, exact point-triangle distances)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from scipy.spatial import ConvexHull

from planner import Lattice, MapError, PlanError
from planner.lattice import NAMED_LATTICES
from planner.voxels import box_keys, exact_box_inflation

GEB079 = Path(__file__).resolve().parents[1] / ".." / "shared" / "data" / "octomap" / "geb079.bt"


def _point_triangles_distance(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> float:
    """Smallest distance from the origin to triangles (a[i], b[i], c[i]), each (n, 3)."""
    ab, ac = b - a, c - a
    n = np.cross(ab, ac)
    nn = np.einsum("ij,ij->i", n, n)
    t = -np.einsum("ij,ij->i", a, n) / nn  # origin projected on the plane: q = t n
    q = t[:, None] * n
    d00, d01, d11 = (np.einsum("ij,ij->i", x, y) for x, y in ((ab, ab), (ab, ac), (ac, ac)))
    d20, d21 = np.einsum("ij,ij->i", q - a, ab), np.einsum("ij,ij->i", q - a, ac)
    den = d00 * d11 - d01 * d01
    v, w = (d11 * d20 - d01 * d21) / den, (d00 * d21 - d01 * d20) / den
    inside = (v >= 0) & (w >= 0) & (v + w <= 1)
    best = np.where(inside, np.abs(t) * np.sqrt(nn), np.inf)
    for s, e in ((a, b), (b, c), (c, a)):
        u = e - s
        tt = np.clip(-np.einsum("ij,ij->i", s, u) / np.einsum("ij,ij->i", u, u), 0, 1)
        best = np.minimum(best, np.linalg.norm(s + tt[:, None] * u, axis=1))
    return float(best.min())


def _reference(cell_verts: np.ndarray, box_verts: np.ndarray) -> tuple[float, float]:
    """(distance between the two convex hulls, depth of the origin inside their Minkowski
    difference): the cell and box overlap with positive volume iff depth > 0."""
    hull = ConvexHull((cell_verts[:, None, :] - box_verts[None, :, :]).reshape(-1, 3))
    off = hull.equations[:, 3]  # normal . 0 + offset <= 0 inside
    if off.max() <= 0:
        return 0.0, float(-off.max())
    p = hull.points[hull.simplices]
    return _point_triangles_distance(p[:, 0], p[:, 1], p[:, 2]), 0.0


def _rotation(rng) -> np.ndarray:
    q, r = np.linalg.qr(rng.normal(size=(3, 3)))
    q = q * np.sign(np.diag(r))
    return q if np.linalg.det(q) > 0 else -q


def _corners(lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    sel = np.array(np.meshgrid([0, 1], [0, 1], [0, 1], indexing="ij")).reshape(3, -1).T
    return np.where(sel == 1, hi, lo)


@pytest.mark.parametrize("radius", [0.0, 0.45, pytest.param(1.3, marks=pytest.mark.slow)])
@pytest.mark.parametrize("rotated", [False, True], ids=["aligned", "rotated"])
@pytest.mark.parametrize("name", NAMED_LATTICES)
def test_exact_box_inflation_matches_reference(name, rotated, radius):
    rng = np.random.default_rng([NAMED_LATTICES.index(name), int(rotated), int(radius * 100)])
    lat = Lattice.named(name, 1.0)
    lo = rng.uniform(-2, 2, size=(3, 3))
    hi = lo + rng.uniform(0.0, 1.8, size=(3, 3))
    hi[0, 2] = lo[0, 2]  # one flat box: a rectangle
    rot = _rotation(rng) if rotated else np.eye(3)
    t = rng.uniform(-1, 1, 3) if rotated else np.zeros(3)
    got = exact_box_inflation(lo, hi, lat, radius, rotation=rot if rotated else None,
                              translation=t if rotated else None)
    got_set = {tuple(w) for w in got.indices.tolist()}
    boxes = [_corners(a, b) @ rot.T + t for a, b in zip(lo, hi, strict=True)]
    # Every cell whose centre lies within r + covering of some box vertex hull: a superset.
    reach = radius + 2 * lat.covering_radius + np.linalg.norm(hi - lo, axis=1).max()
    offs = lat.voronoi.offsets_within(reach)
    centres = lat.quantize(np.array([b.mean(axis=0) for b in boxes]))
    cand = np.unique((centres[:, None, :] + offs[None, :, :]).reshape(-1, 3), axis=0)
    assert got_set <= {tuple(w) for w in cand.tolist()}
    verts = lat.voronoi_vertices
    decided = 0
    for w, c in zip(cand.tolist(), lat.to_world(cand), strict=True):
        refs = [_reference(verts + c, b) for b in boxes]
        dist = min(r[0] for r in refs)
        depth = max(r[1] for r in refs)
        inside = tuple(w) in got_set
        if radius > 0:
            if not inside:  # the guarantee: every cell left out is at least r away
                assert dist >= radius - 1e-9, (w, dist)
            if abs(dist - radius) > 1e-7:
                assert inside == (dist < radius), (w, dist)
                decided += 1
        elif dist > 1e-7 or depth > 1e-7:
            assert inside == (depth > 1e-7), (w, dist, depth)
            decided += 1
    assert decided > 0.9 * len(cand)


@pytest.mark.parametrize("name", NAMED_LATTICES)
def test_radius_zero_is_box_keys_and_radius_grows_the_set(name):
    rng = np.random.default_rng(NAMED_LATTICES.index(name))
    lat = Lattice.named(name, 0.05**3)
    centres = rng.uniform(0, 1, size=(200, 3))
    size = 0.05
    half = np.full(3, size / 2)
    zero = exact_box_inflation(centres - half, centres + half, lat, 0.0)
    np.testing.assert_array_equal(zero.keys, box_keys(centres, size, lat))
    grown = exact_box_inflation(centres - half, centres + half, lat, 0.1)
    assert set(zero.keys.tolist()) < set(grown.keys.tolist())
    rot = _rotation(rng)
    t = rng.uniform(-3, 3, 3)
    moved = exact_box_inflation(centres - half, centres + half, lat, 0.1, rotation=rot,
                                translation=t)
    # A rigid motion of the boxes keeps the number of cells about the same.
    assert abs(len(moved) - len(grown)) < 0.05 * len(grown)


def test_large_boxes_equal_their_pieces():
    """A slab much larger than the radius is cut into pieces internally; the result is
    the same as for the pieces given explicitly, and both match the reference."""
    lat = Lattice.named("bcc", 0.1**3)
    rot = _rotation(np.random.default_rng(5))
    lo, hi = np.array([[0.0, 0.0, 0.0]]), np.array([[3.0, 2.0, 0.05]])
    whole = exact_box_inflation(lo, hi, lat, 0.15, rotation=rot)
    xs = np.linspace(0, 3, 4)
    parts_lo = np.array([[a, 0.0, 0.0] for a in xs[:-1]])
    parts_hi = np.array([[b, 2.0, 0.05] for b in xs[1:]])
    np.testing.assert_array_equal(
        whole.keys, exact_box_inflation(parts_lo, parts_hi, lat, 0.15, rotation=rot).keys)
    corners = _corners(lo[0], hi[0]) @ rot.T
    verts = lat.voronoi_vertices
    rng = np.random.default_rng(6)
    for w in rng.choice(whole.indices, 60, replace=False):  # blocked cells are within r
        assert _reference(verts + lat.to_world(w)[0], corners)[0] < 0.15 + 1e-9


def _children(centres: np.ndarray, sizes: np.ndarray, unit: float) -> np.ndarray:
    """Centres of the unit cubes that tile each cube (OctoMap children of pruned leaves)."""
    out = []
    for c, s in zip(centres, sizes, strict=True):
        n = int(round(s / unit))
        g = np.stack(np.meshgrid(*[np.arange(n)] * 3, indexing="ij"), -1).reshape(-1, 3)
        out.append(c + (g + 0.5) * unit - s / 2)
    return np.concatenate(out)


@pytest.mark.parametrize("name", ["cubic", "fcc"])
def test_aligned_ties_do_not_depend_on_how_boxes_are_cut(name):
    """Boxes on the cubic lattice's own grid put many cells at exactly the radius; a tie
    counts as blocked whichever bound decides it, so big boxes and their children agree."""
    rng = np.random.default_rng(8)
    lat = Lattice.named(name, 1.0)
    sizes = rng.choice([1.0, 2.0, 4.0], size=40)
    centres = rng.integers(-10, 10, size=(40, 3)) * 4.0 + sizes[:, None] / 2
    kids = _children(centres, sizes, 1.0)
    for r in (1.0, 1.5):
        whole = exact_box_inflation(centres - sizes[:, None] / 2, centres + sizes[:, None] / 2,
                                    lat, r)
        assert whole == exact_box_inflation(kids - 0.5, kids + 0.5, lat, r)


@pytest.mark.slow
@pytest.mark.skipif(not GEB079.exists(), reason="shared OctoMap data not present")
def test_geb079_pruned_leaves_block_what_their_children_block():
    from planner.io import load_obstacles

    ob = load_obstacles(GEB079)
    kids = _children(ob.boxes, ob.box_sizes, ob.resolution)
    assert len(kids) == 185_673
    lat = Lattice.named("cubic", ob.resolution**3)
    half = ob.box_sizes[:, None] / 2
    leaves = exact_box_inflation(ob.boxes - half, ob.boxes + half, lat, 0.2)
    assert leaves == exact_box_inflation(kids - ob.resolution / 2, kids + ob.resolution / 2,
                                         lat, 0.2)


def test_bad_boxes_raise_map_error():
    lat = Lattice.named("fcc", 1.0)
    z = np.zeros((1, 3))
    with pytest.raises(MapError, match="below the lower corner"):
        exact_box_inflation(z, z - 1, lat, 0.5)
    with pytest.raises(MapError, match="differ in shape"):
        exact_box_inflation(np.zeros((2, 3)), z, lat, 0.5)
    with pytest.raises(MapError, match="rotation"):
        exact_box_inflation(z, z + 1, lat, 0.5, rotation=2 * np.eye(3))
    with pytest.raises(MapError, match="translation"):
        exact_box_inflation(z, z + 1, lat, 0.5, translation=[1, 2])
    with pytest.raises(PlanError, match="radius"):
        exact_box_inflation(z, z + 1, lat, -1)
    with pytest.raises(MapError, match="budget"):
        exact_box_inflation(z, z + 1, lat, 30.0, memory_budget=10**5)
    assert len(exact_box_inflation(np.zeros((0, 3)), np.zeros((0, 3)), lat, 0.5)) == 0
