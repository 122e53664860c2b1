"""Lattices: exact quantization, adjacency derived from geometry, radii, bad input."""

import itertools

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from planner import Lattice, LatticeError
from planner.lattice import NAMED_LATTICES, PAPER_DELTAS

NAMES = list(NAMED_LATTICES)


def brute_force_nearest(lattice: Lattice, x: np.ndarray) -> np.ndarray:
    """Nearest lattice point by exhaustive search over a box that provably contains it.

    Rounding in the given basis errs by at most half the longest diagonal of its
    parallelepiped, so the nearest point lies within twice that of the rounded one.
    """
    g = lattice.generator
    d = lattice.dim
    signs = np.array(list(itertools.product((-1.0, 1.0), repeat=d)))
    reach = np.linalg.norm(signs @ g.T, axis=1).max()
    k = np.ceil(reach * np.linalg.norm(np.linalg.inv(g), axis=1)).astype(int)
    box = np.stack(
        np.meshgrid(*[np.arange(-b, b + 1) for b in k], indexing="ij"), axis=-1
    ).reshape(-1, d)
    w0 = np.rint(x @ np.linalg.inv(g).T).astype(np.int64)
    best = np.full(len(x), np.inf)
    out = w0.copy()
    for off in box:
        w = w0 + off
        dist = np.sum((w @ g.T - x) ** 2, axis=1)
        better = dist < best
        best[better] = dist[better]
        out[better] = w[better]
    return out


def assert_nearest(lattice: Lattice, x: np.ndarray, w: np.ndarray) -> None:
    """w is a nearest lattice point of x (ties on cell boundaries accepted)."""
    ref = brute_force_nearest(lattice, x)
    g = lattice.generator
    d_got = np.linalg.norm(w @ g.T - x, axis=1)
    d_ref = np.linalg.norm(ref @ g.T - x, axis=1)
    scale = lattice.cell_volume ** (1 / lattice.dim)
    assert np.all(d_got <= d_ref + 1e-9 * scale)
    # Away from ties the answer is the unique nearest point.
    assert np.mean(np.all(w == ref, axis=1)) > 0.999


@pytest.mark.parametrize("name", NAMES)
def test_named_lattices_have_the_requested_cell_volume(name):
    for v in (1.0, 0.125, 1e-3, 7.5):
        lat = Lattice.named(name, cell_volume=v)
        assert lat.cell_volume == pytest.approx(v, rel=1e-12)
        assert lat.dim == 3
        assert lat.name == name


def test_generators_match_the_paper_to_printed_precision():
    paper = {
        "bcc": [[1.2599, 0, 0.6300], [0, 1.2599, 0.6300], [0, 0, 0.6300]],
        "fcc": [[1.5874, 0.7937, 0], [0, -0.7937, 0.7937], [0, 0, -0.7937]],
        "mcc": [[1.0987, -0.4551, -0.1885], [0, 1, -0.5858], [0, 0, 0.9102]],
        "hex": [[1.1776, -0.5888, 0], [0, 1.0198, 0], [0, 0, 0.8327]],
    }
    for name, g in paper.items():
        assert np.allclose(Lattice.named(name).generator, g, atol=1e-4)


@pytest.mark.slow
@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    name=st.sampled_from(NAMES),
    log_volume=st.floats(-9, 6),
    far=st.booleans(),
    seed=st.integers(0, 2**31),
)
def test_quantize_is_exact_for_every_lattice_and_scale(name, log_volume, far, seed):
    lat = Lattice.named(name, cell_volume=10.0**log_volume)
    size = lat.cell_volume ** (1 / 3)
    rng = np.random.default_rng(seed)
    centre = rng.uniform(-1, 1, 3) * (1e4 * size if far else 0.0)
    x = centre + rng.uniform(-5, 5, (2000, 3)) * size
    assert_nearest(lat, x, lat.quantize(x))
    assert_nearest(lat, x, lat.quantize_generic(x))


@pytest.mark.slow
@settings(max_examples=40, deadline=None)
@given(dim=st.sampled_from([2, 3]), seed=st.integers(0, 2**31))
def test_quantize_is_exact_for_user_generators(dim, seed):
    rng = np.random.default_rng(seed)
    g = rng.normal(size=(dim, dim))
    if np.linalg.cond(g) > 30:  # keep the brute-force box small; exactness is not the issue
        g = g + 3 * np.eye(dim)
    lat = Lattice(g)
    x = rng.uniform(-20, 20, (3000, dim))
    assert_nearest(lat, x, lat.quantize(x))


@pytest.mark.parametrize("name", NAMES)
def test_geometry_at_any_cell_volume_is_the_unit_cell_scaled(name):
    """Neighbours and rounding candidates are the same index offsets at every scale; the
    cell's vertices and radii scale with the cell edge, its second moment not at all."""
    unit = Lattice.named(name, 1.0)
    for volume in (0.02**3, 0.04**3, 0.16**3, 0.32**3, 7.3):
        lat = Lattice.named(name, volume)
        edge = volume ** (1 / 3)
        for kind in ("face", "full"):
            assert np.array_equal(lat.neighbors(kind), unit.neighbors(kind)), (volume, kind)
        assert np.array_equal(lat.rounding_offsets(), unit.rounding_offsets()), volume
        got, want = (np.sort(np.round(v / v.max(), 9), axis=0) for v in
                     (lat.voronoi_vertices, unit.voronoi_vertices * edge))
        np.testing.assert_allclose(got, want, atol=1e-9)
        assert lat.covering_radius == pytest.approx(unit.covering_radius * edge, rel=1e-12)
        assert lat.packing_radius == pytest.approx(unit.packing_radius * edge, rel=1e-12)
        assert lat.normalized_second_moment == pytest.approx(unit.normalized_second_moment,
                                                             rel=1e-12)
        x = np.random.default_rng(3).uniform(-40 * edge, 40 * edge, (2000, 3))
        assert np.array_equal(lat.quantize_generic(x), brute_force_nearest(lat, x)), volume


@pytest.mark.parametrize("name", NAMES)
def test_cell_centres_quantize_to_themselves(name):
    lat = Lattice.named(name, cell_volume=0.01)
    w = np.random.default_rng(1).integers(-10**5, 10**5, (10000, 3))
    assert np.array_equal(lat.quantize(lat.to_world(w)), w)


@pytest.mark.parametrize(
    ("name", "face", "full"),
    [("cubic", 6, 26), ("bcc", 14, 14), ("fcc", 12, 18), ("mcc", 14, 14), ("hex", 8, 20)],
)
def test_neighbour_counts_match_the_known_polyhedra(name, face, full):
    lat = Lattice.named(name)
    assert lat.neighbors("face").shape == (face, 3)
    assert lat.neighbors("full").shape == (full, 3)


@pytest.mark.parametrize("name", NAMES)
def test_neighbours_are_symmetric_and_face_is_a_subset_of_full(name):
    lat = Lattice.named(name)
    face = {tuple(v) for v in lat.neighbors("face")}
    full = {tuple(v) for v in lat.neighbors("full")}
    assert face <= full
    for s in (face, full):
        assert {tuple(-np.array(v)) for v in s} == s


def test_fcc_face_neighbours_are_twelve_equidistant():
    lat = Lattice.named("fcc")
    dist = np.linalg.norm(lat.to_world(lat.neighbors("face")), axis=1)
    assert np.ptp(dist) < 1e-12


@pytest.mark.parametrize("name", NAMES)
def test_neighbours_touch_in_the_way_their_kind_says(name):
    """Full neighbours' cells touch (v/2 on the cell boundary); face neighbours share a
    facet: points just around v/2 in the bisecting plane quantize to 0 or v only."""
    lat = Lattice.named(name)
    g = lat.generator
    for v in lat.neighbors("full"):
        mid = (g @ v) / 2
        w = lat.quantize(np.stack([mid * (1 - 1e-9), mid * (1 + 1e-9)]))
        assert np.array_equal(w[0], [0, 0, 0])
        assert np.array_equal(w[1], v)
    for v in lat.neighbors("face"):
        mid = (g @ v) / 2
        n = g @ v / np.linalg.norm(g @ v)
        t = np.linalg.svd(n[None, :])[2][1:]  # two directions in the bisecting plane
        ring = mid + 1e-3 * lat.packing_radius * np.array(
            [np.cos(a) * t[0] + np.sin(a) * t[1] for a in np.linspace(0, 2 * np.pi, 12)]
        )
        inside = lat.quantize(ring - 1e-6 * n)
        assert np.all(inside == 0)


def test_2d_square_and_hexagonal_lattices():
    square = Lattice(np.eye(2))
    assert len(square.neighbors("face")) == 4
    assert len(square.neighbors("full")) == 8
    hexa = Lattice([[1.0, 0.5], [0.0, np.sqrt(3) / 2]], name="hex2d")
    assert len(hexa.neighbors("face")) == 6
    assert len(hexa.neighbors("full")) == 6
    assert hexa.covering_radius == pytest.approx(1 / np.sqrt(3))
    assert square.normalized_second_moment == pytest.approx(1 / 12)
    assert hexa.normalized_second_moment == pytest.approx(5 / (36 * np.sqrt(3)))


@pytest.mark.parametrize("name", NAMES)
def test_covering_and_packing_radius_bound_the_cell(name):
    lat = Lattice.named(name, cell_volume=0.3)
    x = np.random.default_rng(2).uniform(-3, 3, (200000, 3))
    err = np.linalg.norm(lat.to_world(lat.quantize(x)) - x, axis=1)
    assert err.max() <= lat.covering_radius + 1e-12
    assert err.max() > 0.95 * lat.covering_radius
    verts = lat.voronoi_vertices
    assert np.allclose(np.linalg.norm(verts, axis=1).max(), lat.covering_radius)
    nearest = np.linalg.norm(lat.to_world(lat.neighbors("face")), axis=1).min()
    assert lat.packing_radius == pytest.approx(nearest / 2)


def test_exact_second_moments_match_known_values():
    known = {"cubic": 1 / 12, "bcc": 0.0785433, "fcc": 0.0787451, "mcc": 0.0786696}
    for name, value in known.items():
        assert Lattice.named(name).normalized_second_moment == pytest.approx(value, abs=2e-7)


def test_the_papers_off_by_one_sets_miss_offsets_for_fcc_and_hex():
    """Eq. (2) with the paper's Delta sets is exact only where they contain every needed
    offset; FCC and hex lack +-(1,0,0), and a point exists where eq. (2) is then wrong."""
    for name in NAMES:
        lat = Lattice.named(name)
        needed = {tuple(v) for v in lat.rounding_offsets("given")}
        paper = {tuple(v) for v in PAPER_DELTAS[name]} | {(0, 0, 0)}
        missing = needed - paper
        if name in ("fcc", "hex"):
            assert missing == {(1, 0, 0), (-1, 0, 0)}
        else:
            assert not missing
    fcc = Lattice.named("fcc")
    x = np.random.default_rng(3).uniform(-5, 5, (200000, 3))
    g = fcc.generator
    w0 = np.rint(x @ np.linalg.inv(g).T).astype(np.int64)
    cand = np.concatenate([np.zeros((1, 3), np.int64), PAPER_DELTAS["fcc"]])
    dist = np.stack([np.linalg.norm((w0 + c) @ g.T - x, axis=1) for c in cand])
    paper_w = w0 + cand[np.argmin(dist, axis=0)]
    wrong = np.any(paper_w != fcc.quantize(x), axis=1)
    assert wrong.any()


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (([[1, 0], [0, 1], [0, 0]],), "square"),
        (([[1, 2], [2, 4]],), "singular"),
        (([[1, np.nan], [0, 1]],), "NaN"),
        ((np.eye(4),), "2D and 3D"),
        (("abc",), "numeric"),
    ],
)
def test_bad_generators_raise_lattice_error(args, message):
    with pytest.raises(LatticeError, match=message):
        Lattice(*args)


def test_bad_names_volumes_and_points_raise_lattice_error():
    with pytest.raises(LatticeError, match="unknown lattice"):
        Lattice.named("diamond")
    for v in (0, -1, float("nan"), float("inf"), "big"):
        with pytest.raises(LatticeError, match="cell_volume"):
            Lattice.named("fcc", cell_volume=v)
    lat = Lattice.named("bcc")
    with pytest.raises(LatticeError, match="shape"):
        lat.quantize(np.zeros((4, 2)))
    with pytest.raises(LatticeError, match="NaN or infinite"):
        lat.quantize(np.array([[0, 0, 0], [np.inf, 0, 0]]))
    with pytest.raises(LatticeError, match="neighbour kind"):
        lat.neighbors("diagonal")
    assert issubclass(LatticeError, ValueError)


def test_extended_neighbour_shells_add_the_next_ring():
    cubic = Lattice.named("cubic")
    assert len(cubic.neighbors("face+1")) == 6 + 12
    assert len(cubic.neighbors("full+1")) == 26 + 6  # the (2,0,0) ring
    fcc = Lattice.named("fcc")
    assert len(fcc.neighbors("face+1")) == 12 + 6


# -- guards: ill-conditioned generators, far points, huge shells -----------------------------
@pytest.mark.parametrize("generator", [np.diag([1, 1, 1e-12]), np.diag([1, 1, 1e-6])])
def test_ill_conditioned_generators_are_refused_before_enumerating(generator):
    with pytest.raises(LatticeError, match=r"ill-conditioned.*enumerate ~[0-9.e+]+ lattice "
                                           r"vectors \(limit"):
        Lattice(generator).neighbors("full")


def test_unimodular_skewed_generator_is_reduced_not_called_singular():
    skew = Lattice([[1, 1e9, 0], [0, 1, 0], [0, 0, 1]])
    # The same lattice as Z^3: 6 face and 26 full neighbours, unit cells.
    assert len(skew.neighbors("face")) == 6
    assert len(skew.neighbors("full")) == 26
    assert skew.covering_radius == pytest.approx(np.sqrt(3) / 2)
    x = np.random.default_rng(4).uniform(-50, 50, (2000, 3))
    np.testing.assert_allclose(skew.to_world(skew.quantize(x)), np.rint(x), atol=1e-6)
    with pytest.raises(LatticeError, match="singular"):
        Lattice([[1, 1, 0], [1, 1 + 1e-15, 0], [0, 0, 1]])


@pytest.mark.parametrize("name", NAMES)
def test_points_too_far_for_exact_indices_raise(name):
    lat = Lattice.named(name)
    with pytest.raises(LatticeError, match=r"point 1 has a coordinate of 1e\+20 m"):
        lat.quantize([[0, 0, 0], [1e20, 3.3, 0]])
    with pytest.raises(LatticeError, match="indices stay exact"):
        lat.quantize_generic([[-1e20, 3.3, 0]])
    far = lat.quantize([[1e12, -1e12, 5e11]])  # far but representable: exact, not INT64_MIN
    assert np.abs(lat.to_world(far) - [1e12, -1e12, 5e11]).max() < 1e-3 * 1e12


def test_huge_neighbour_shell_requests_are_refused():
    with pytest.raises(LatticeError, match="shells would enumerate"):
        Lattice.named("fcc").neighbors("face+1000")


# -- the Voronoi cell as one object ------------------------------------------------------------
@pytest.mark.parametrize("name", NAMES)
def test_voronoi_cell_describes_the_cell(name):
    lat = Lattice.named(name, 0.3)
    cell = lat.voronoi
    assert cell.packing_radius == lat.packing_radius
    assert cell.covering_radius == lat.covering_radius
    np.testing.assert_allclose(np.linalg.norm(cell.normals, axis=1), 1)
    # Every vertex lies on >= 3 facets; each edge's end points share 2 facets.
    on = np.abs(cell.vertices @ cell.normals.T - cell.offsets) < 1e-9
    assert (on.sum(axis=1) >= 3).all()
    e0, e1 = cell.edges
    assert len(e0) == len(cell.vertices) + len(cell.normals) - 2  # Euler: V - E + F = 2
    shared = (np.abs(e0 @ cell.normals.T - cell.offsets) < 1e-9) & (
        np.abs(e1 @ cell.normals.T - cell.offsets) < 1e-9)
    assert (shared.sum(axis=1) == 2).all()
    with pytest.raises(ValueError):
        cell.vertices[0, 0] = 1.0  # read-only


@pytest.mark.parametrize("name", NAMES)
def test_offsets_within_is_every_centre_in_the_ball(name):
    lat = Lattice.named(name, 1.0)
    r = 2.7
    got = {tuple(w) for w in lat.voronoi.offsets_within(r).tolist()}
    box = np.array(list(itertools.product(range(-8, 9), repeat=3)))
    want = {tuple(w) for w in box[np.linalg.norm(lat.to_world(box), axis=1) <= r].tolist()}
    assert got == want
    with pytest.raises(LatticeError, match="budget"):
        lat.voronoi.offsets_within(1e4)


@pytest.mark.parametrize("name", NAMES)
def test_separating_axes_include_box_and_facet_normals(name):
    cell = Lattice.named(name).voronoi
    rot = np.linalg.qr(np.random.default_rng(1).normal(size=(3, 3)))[0]
    for r in (np.eye(3), rot):
        axes = cell.separating_axes(r)
        np.testing.assert_allclose(np.linalg.norm(axes, axis=1), 1)
        for n in np.concatenate([r.T, cell.normals]):
            assert np.abs(np.abs(axes @ n) - 1).min() < 1e-9


def test_quantizer_tables_reproduce_quantize():
    lat = Lattice.named("mcc", 0.2)
    q = lat.quantizer()
    assert q.cand.shape[0] == 8 and q.counts.shape == (8,)
    from planner.lattice.quantize import run_generic

    x = np.random.default_rng(2).uniform(-5, 5, (5000, 3))
    out = np.empty(x.shape, dtype=np.int64)
    run_generic(q, x, out)
    np.testing.assert_array_equal(out, lat.quantize(x))


# -- read-only install --------------------------------------------------------------------------
@pytest.mark.slow
def test_import_and_quantize_from_a_read_only_install(tmp_path):
    """No writable package folder, HOME unset, no numba cache dir: kernels compile in memory.

    Tests often run as root, for whom file modes do not bind: a regular file named
    ``__pycache__`` in every package folder and an impossible XDG cache path leave numba
    no writable cache location either way."""
    import os
    import shutil
    import subprocess
    import sys
    from pathlib import Path

    import planner

    site = tmp_path / "site"
    shutil.copytree(Path(planner.__file__).parent, site / "planner",
                    ignore=shutil.ignore_patterns("__pycache__"))
    for d in [p for p in (site / "planner").rglob("*") if p.is_dir()] + [site / "planner"]:
        (d / "__pycache__").write_text("")
    for p in sorted((site / "planner").rglob("*"), reverse=True):
        p.chmod(p.stat().st_mode & 0o555)
    env = {k: v for k, v in os.environ.items() if k not in ("HOME", "NUMBA_CACHE_DIR")}
    env.update(PYTHONPATH=str(site), XDG_CACHE_HOME="/proc/no-such-cache")
    code = ("import numpy as np, planner\n"
            "print(planner.Lattice.named('fcc').quantize([[1.0, 2.0, 3.3]]).tolist())\n"
            "print(planner.Lattice.named('mcc').quantize([[1.0, 2.0, 3.3]]).tolist())\n"
            "from planner.voxels import exact_box_inflation\n"
            "z = np.zeros((1, 3))\n"
            "print(len(exact_box_inflation(z, z + 1, planner.Lattice.named('bcc'), 0.3)))\n")
    try:
        res = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, env=env,
                             capture_output=True, text=True, timeout=600)
    finally:
        for p in (site / "planner").rglob("*"):
            p.chmod(p.stat().st_mode | 0o200)
    assert res.returncode == 0, res.stderr[-2000:]
    fcc, mcc = (Lattice.named(n).quantize([[1.0, 2.0, 3.3]]).tolist() for n in ("fcc", "mcc"))
    assert res.stdout.split("\n")[:2] == [str(fcc), str(mcc)]
