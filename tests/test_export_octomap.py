"""A `.bt` export means what OctoMap means: the map's obstacles as occupied voxels, observed
free space as free voxels, unknown space left out, on OctoMap's own voxel centres
``(key - 32768 + 1/2) * res``. Checked with the project's reader and, where it installs, with
OctoMap itself (the octomap-python binding, in the ``dev`` extra)."""

from pathlib import Path

import numpy as np
import pytest

from planner.cli import main
from planner.errors import MapError
from planner.export import write_octomap
from planner.io import Obstacles, load_obstacles
from planner.maps import load_map_points

RES = 0.1
OFFICE = ["office", "--cell-volume", f"{RES ** 3!r}", "--radius", "0.1"]


def _voxels(points: np.ndarray, res: float) -> np.ndarray:
    """Sorted unique OctoMap voxel indices (key - 32768) of points: floor(p / res)."""
    return np.unique(np.floor(points / res).astype(np.int64), axis=0)


def _leaf_voxels(centres: np.ndarray, sizes: np.ndarray, res: float) -> np.ndarray:
    """Every finest voxel (index key - 32768) inside cube leaves (centre, edge)."""
    out = [np.zeros((0, 3), np.int64)]
    n_of = np.rint(np.asarray(sizes) / res).astype(np.int64)
    for n in np.unique(n_of):
        c, s = centres[n_of == n], sizes[n_of == n]
        lo = np.rint((c - s[:, None] / 2) / res).astype(np.int64)
        g = np.stack(np.meshgrid(*[np.arange(n)] * 3, indexing="ij"), -1).reshape(-1, 3)
        out.append((lo[:, None, :] + g).reshape(-1, 3))
    return np.unique(np.concatenate(out), axis=0)


def _octomap_voxels(path: Path):
    """(res, occupied, free) finest voxels as OctoMap itself reads the file."""
    octomap = pytest.importorskip("octomap", reason="octomap-python (dev extra) not installed")
    tree = octomap.OcTree(str(path).encode())
    res = tree.getResolution()
    occ, free = [], []
    for leaf in tree.begin_leafs():
        (occ if tree.isNodeOccupied(leaf) else free).append(
            (np.array(leaf.getCoordinate()), leaf.getSize()))

    def cells(leaves):
        return _leaf_voxels(np.array([c for c, _ in leaves]).reshape(-1, 3),
                            np.array([s for _, s in leaves]), res)
    return res, cells(occ), cells(free)


@pytest.fixture(scope="module")
def office_bt(tmp_path_factory):
    """The office map's obstacles written by `planner world` on a cubic world."""
    d = tmp_path_factory.mktemp("bt")
    assert main(["world", *OFFICE, "--lattice", "cubic", "--out", str(d / "o.bt")]) == 0
    return d / "o.bt", load_map_points("office")


def test_bt_holds_the_obstacle_points_voxels_not_the_inflated_cells(office_bt):
    path, pts = office_bt
    obst = load_obstacles(path)
    assert obst.resolution == pytest.approx(RES)
    assert not len(obst.free_boxes)  # a plain cloud observed no free space: none written
    assert path.read_bytes().count(b"planner_shift") == 0  # OctoMap's own frame
    np.testing.assert_array_equal(_leaf_voxels(obst.boxes, obst.box_sizes, RES),
                                  _voxels(pts, RES))


def test_octomap_itself_reads_the_obstacles_on_its_voxel_centres(office_bt):
    path, pts = office_bt
    res, occ, free = _octomap_voxels(path)
    assert res == pytest.approx(RES)
    np.testing.assert_array_equal(occ, _voxels(pts, RES))
    assert not len(free)
    # OctoMap's own point lookup finds every obstacle point in an occupied voxel
    import octomap

    tree = octomap.OcTree(str(path).encode())
    for p in pts[:: max(1, len(pts) // 500)]:
        node = tree.search(p)
        assert node is not None and tree.isNodeOccupied(node)


def test_any_lattice_writes_the_obstacle_map(tmp_path):
    """The obstacle map does not depend on the planner's lattice; only its voxel edge
    follows the cell volume."""
    assert main(["world", *OFFICE, "--lattice", "fcc", "--out", str(tmp_path / "f.bt")]) == 0
    obst = load_obstacles(tmp_path / "f.bt")
    assert obst.resolution == pytest.approx(0.1)
    assert len(obst.boxes)


def _scan():
    """A sensor at (0.05, 0.05, 1.05) m seeing a wall at x = 2 m and a floor at z = 0."""
    rng = np.random.default_rng(3)
    wall = np.column_stack([np.full(150, 2.0), rng.uniform(-1, 1, 150), rng.uniform(0, 2, 150)])
    floor = np.column_stack([rng.uniform(0.3, 1.9, 150), rng.uniform(-1, 1, 150),
                             np.zeros(150)])
    pts = np.concatenate([wall, floor]) + 1e-4 * rng.standard_normal((300, 3))
    origin = np.array([[0.05, 0.05, 1.05]])
    return Obstacles(points=pts, boxes=np.zeros((0, 3)), box_size=0.0, bounds=None,
                     resolution=None, source="scan", origins=origin,
                     point_origin=np.zeros(len(pts), np.int64))


def _segment_distance(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(P,) distance of points p (P, 3) to the nearest of segments a[i] -> b[i] (S, 3)."""
    ab = b - a
    t = np.clip(np.einsum("psk,sk->ps", p[:, None, :] - a[None], ab) /
                np.einsum("sk,sk->s", ab, ab), 0, 1)
    near = a[None] + t[..., None] * ab[None]
    return np.linalg.norm(p[:, None, :] - near, axis=2).min(axis=1)


def test_a_scan_with_its_origin_writes_the_rays_free_space(tmp_path):
    scan = _scan()
    got = write_octomap(tmp_path / "s.bt", scan, RES)
    obst = load_obstacles(tmp_path / "s.bt")
    occ = _leaf_voxels(obst.boxes, obst.box_sizes, RES)
    free = _leaf_voxels(obst.free_boxes, obst.free_box_sizes, RES)
    assert (got.occupied, got.free) == (len(occ), len(free))
    np.testing.assert_array_equal(occ, _voxels(scan.points, RES))
    # every free voxel is touched by a ray (its centre within half a voxel diagonal) ...
    d = _segment_distance((free + 0.5) * RES, scan.origins[scan.point_origin], scan.points)
    assert d.max() <= np.sqrt(3) / 2 * RES + 1e-9
    # ... and every voxel a ray runs through (samples along it) is free or an end voxel
    t = np.linspace(0, 1, 200)[:-1, None, None]
    a = scan.origins[scan.point_origin]
    samples = (a + t * (scan.points - a)).reshape(-1, 3)
    seen = _voxels(samples, RES)
    known = np.concatenate([occ, free])
    assert len(np.unique(np.concatenate([known, seen]), axis=0)) == len(known)
    # space behind the wall (x > 2.1 m) was never seen: left out
    assert not np.any((free[:, 0] + 0.5) * RES > 2.1)


def test_octomaps_own_ray_cast_agrees(tmp_path):
    """OctoMap's insertPointCloud on the same scan: the same occupied voxels, and every
    voxel it marks free is free in the export (ours also keeps voxels a ray only grazes)."""
    octomap = pytest.importorskip("octomap", reason="octomap-python (dev extra) not installed")
    scan = _scan()
    write_octomap(tmp_path / "s.bt", scan, RES)
    _, occ, free = _octomap_voxels(tmp_path / "s.bt")
    tree = octomap.OcTree(RES)
    tree.insertPointCloud(scan.points, scan.origins[0])
    tree.writeBinary(str(tmp_path / "ref.bt").encode())
    _, ref_occ, ref_free = _octomap_voxels(tmp_path / "ref.bt")
    np.testing.assert_array_equal(occ, ref_occ)
    both = np.unique(np.concatenate([free, ref_free]), axis=0)
    assert len(both) == len(free)
    assert len(ref_free) > 0.8 * len(free)


@pytest.mark.real_data
def test_geb079_round_trips_leaf_for_leaf(real_data, tmp_path):
    """A real OctoMap read and written again at its own resolution: the same tree."""
    octomap = pytest.importorskip("octomap", reason="octomap-python (dev extra) not installed")
    src = real_data / "octomap" / "geb079.bt"
    got = write_octomap(tmp_path / "g.bt", load_obstacles(src))
    assert got.occupied == 185_673  # data README: occupied 0.08 m voxels once expanded

    def leaves(path):
        t = octomap.OcTree(str(path).encode())
        rows = np.array([(*leaf.getCoordinate(), leaf.getSize(), t.isNodeOccupied(leaf))
                         for leaf in t.begin_leafs()])
        return rows[np.lexsort(rows.T[::-1])]
    a, b = leaves(tmp_path / "g.bt"), leaves(src)
    assert a.shape == b.shape
    np.testing.assert_allclose(a, b, rtol=0, atol=1e-9)


def test_a_saved_world_or_a_2d_map_is_refused_in_one_line(tmp_path, capsys):
    npz = tmp_path / "w.npz"
    assert main(["world", *OFFICE, "--out", str(npz)]) == 0
    capsys.readouterr()
    assert main(["world", str(npz), "--out", str(tmp_path / "w.bt")]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "--bt-cspace" in err
    assert main(["world", *OFFICE, "--out", str(tmp_path / "w.ply"), "--bt-cspace"]) == 2
    assert "--bt-cspace" in capsys.readouterr().err
    with pytest.raises(MapError, match="2D map"):
        write_octomap(tmp_path / "p.bt", Obstacles(
            points=np.zeros((1, 2)), boxes=np.zeros((0, 2)), box_size=0.0, bounds=None,
            resolution=None, source="plan", dim=2), 0.1)
    assert not list(tmp_path.glob("*.bt"))


@pytest.mark.real_data
def test_geb079_written_again_is_the_same_bit_stream(real_data, tmp_path):
    """OctoMap's own file and ours, after their headers: byte for byte (same pruning, same
    depth-first order, same node count)."""
    src = real_data / "octomap" / "geb079.bt"
    write_octomap(tmp_path / "g.bt", load_obstacles(src))
    a, b = (tmp_path / "g.bt").read_bytes(), src.read_bytes()

    def split(data: bytes) -> tuple[dict, bytes]:
        head, _, body = data.partition(b"\ndata\n")
        fields = dict(line.split(" ", 1) for line in head.decode().splitlines()
                      if line and not line.startswith("#"))
        return fields, body
    (ha, sa), (hb, sb) = split(a), split(b)
    assert ha == hb  # id, size, res
    assert sa == sb
