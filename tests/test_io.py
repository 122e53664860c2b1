"""planner.io: reading maps and point clouds, merging posed scans, writing clouds.

Synthetic files are written to ``tmp_path`` by small independent writers below (PLY through
plyfile, PCD / OctoMap / MovingAI by hand, LZF by a tiny compressor); the real files under
``../shared/data`` are used when present and their tests skip otherwise.
"""

from __future__ import annotations

import bz2
import gzip
import math
import os
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from plyfile import PlyData, PlyElement

from planner.errors import MapError
from planner.io import (
    Obstacles,
    Scenarios,
    load_obstacles,
    load_points,
    load_posed_scans,
    load_scenarios,
    merge_scans,
    save_points,
)

DATA = Path(__file__).resolve().parents[1] / ".." / "shared" / "data"


@pytest.fixture
def data() -> Path:
    if not DATA.is_dir():
        pytest.skip("real data ../shared/data not present")
    return DATA


@pytest.fixture
def cloud() -> np.ndarray:
    """50 random points, metres, none at the origin."""
    return np.random.default_rng(7).uniform(-20, 20, size=(50, 3))


# --------------------------------------------------------------------------------------------
# Independent writers for the test fixtures
# --------------------------------------------------------------------------------------------


def lzf_compress(data: bytes) -> bytes:
    """Greedy LZF compressor (liblzf format): literal runs and back references."""
    out, lit, table = bytearray(), bytearray(), {}

    def flush() -> None:
        for k in range(0, len(lit), 32):
            chunk = lit[k : k + 32]
            out.append(len(chunk) - 1)
            out.extend(chunk)
        lit.clear()

    i, n = 0, len(data)
    while i < n:
        ref = table.get(data[i : i + 3]) if i + 3 <= n else None
        if i + 3 <= n:
            table[data[i : i + 3]] = i
        if ref is not None and i - ref - 1 < 8192:
            length = 3
            while i + length < n and length < 264 and data[ref + length] == data[i + length]:
                length += 1
            flush()
            off, code = i - ref - 1, length - 2
            if code < 7:
                out.append((code << 5) | (off >> 8))
            else:
                out += bytes([(7 << 5) | (off >> 8), code - 7])
            out.append(off & 0xFF)
            i += length
        else:
            lit.append(data[i])
            i += 1
    flush()
    return bytes(out)


def lzf_literals(data: bytes) -> bytes:
    """Valid LZF using literal runs only."""
    out = bytearray()
    for k in range(0, len(data), 32):
        chunk = data[k : k + 32]
        out.append(len(chunk) - 1)
        out.extend(chunk)
    return bytes(out)


# (name, TYPE, SIZE, COUNT): x y z among an intensity, a packed rgb and a 3-wide padding field
PCD_FIELDS = [
    ("intensity", "F", 4, 1),
    ("x", "F", 4, 1),
    ("_", "U", 1, 3),
    ("y", "F", 8, 1),
    ("rgb", "U", 4, 1),
    ("z", "F", 4, 1),
]


def write_pcd(path: Path, pts: np.ndarray, kind: str, fields=PCD_FIELDS, lzf=lzf_compress,
              points_in_header: int | None = None) -> np.ndarray:
    """Write a PCD v0.7 file; return the xyz the reader should see (float32-rounded)."""
    n = len(pts)
    np_types = {("F", 4): "<f4", ("F", 8): "<f8", ("U", 1): "u1", ("U", 4): "<u4"}
    rec = np.zeros(n, dtype=[(f"f{i}", np_types[(t, s)], (c,))
                             for i, (_, t, s, c) in enumerate(fields)])
    rng = np.random.default_rng(1)
    for i, (name, _, _, c) in enumerate(fields):
        if name in "xyz":
            rec[f"f{i}"][:, 0] = pts[:, "xyz".index(name)]
        elif name == "intensity":
            rec[f"f{i}"][:, 0] = rng.uniform(0, 255, n)
        else:
            rec[f"f{i}"] = rng.integers(0, 255, (n, c))
    npts = n if points_in_header is None else points_in_header
    header = "\n".join([
        "# .PCD v0.7 - Point Cloud Data file format",
        "VERSION 0.7",
        "FIELDS " + " ".join(f[0] for f in fields),
        "SIZE " + " ".join(str(f[2]) for f in fields),
        "TYPE " + " ".join(f[1] for f in fields),
        "COUNT " + " ".join(str(f[3]) for f in fields),
        f"WIDTH {npts}",
        "HEIGHT 1",
        "VIEWPOINT 0 0 0 1 0 0 0",
        f"POINTS {npts}",
        f"DATA {kind}",
    ]) + "\n"
    if kind == "ascii":
        lines = [" ".join(" ".join(repr(float(v)) if fields[i][1] == "F" else str(int(v))
                                   for v in rec[f"f{i}"][j]) for i in range(len(fields)))
                 for j in range(n)]
        body = ("\n".join(lines) + "\n").encode()
    elif kind == "binary":
        body = rec.tobytes()
    else:  # binary_compressed: column-major (every point's field 0, then field 1, ...)
        raw = b"".join(np.ascontiguousarray(rec[f"f{i}"]).tobytes() for i in range(len(fields)))
        comp = lzf(raw)
        body = np.array([len(comp), len(raw)], "<u4").tobytes() + comp
    path.write_bytes(header.encode() + body)
    cols = {name: rec[f"f{i}"][:, 0] for i, (name, *_ ) in enumerate(fields)}
    return np.column_stack([cols[c] for c in "xyz"]).astype(np.float64)


def write_ply(path: Path, pts: np.ndarray, text: bool, byte_order: str = "<") -> None:
    """PLY with float32 x, y, z plus an extra per-vertex property and a face element."""
    vert = np.zeros(len(pts), dtype=[("x", "f4"), ("y", "f4"), ("z", "f4"), ("quality", "u1")])
    for i, c in enumerate("xyz"):
        vert[c] = pts[:, i]
    faces = np.array([([0, 1, 2],)], dtype=[("vertex_indices", "i4", (3,))])
    PlyData([PlyElement.describe(vert, "vertex"), PlyElement.describe(faces, "face")],
            text=text, byte_order=byte_order).write(str(path))


BT_DEPTH = 16


def write_bt(path: Path, occupied: list[tuple[int, tuple[int, int, int]]],
             free: list[tuple[int, tuple[int, int, int]]] = (), res: float = 0.1,
             size: int | None = None, cut: int = 0) -> None:
    """OctoMap .bt with the given leaves, each ``(depth, min_corner_key)``.

    Encodes the README layout: each inner node is 2 bytes, child i's 2-bit state at bits
    2*(i%4) of byte i//4 (1 free, 2 occupied, 3 inner, 0 unknown), children depth-first in
    order 0..7; child i's key offset is bit 0 -> x, bit 1 -> y, bit 2 -> z.
    """
    occ, fre = set(occupied), set(free)
    leaves = occ | fre
    n_nodes = 1

    def inside(depth, key, leaf):
        d, k = leaf
        s = 1 << (BT_DEPTH - depth)
        return d > depth and all(key[a] <= k[a] < key[a] + s for a in range(3))

    def encode(depth, key) -> bytes:
        nonlocal n_nodes
        half = 1 << (BT_DEPTH - depth - 1)
        states, tail = 0, b""
        for i in range(8):
            ck = (key[0] + (i & 1) * half, key[1] + (i >> 1 & 1) * half,
                  key[2] + (i >> 2 & 1) * half)
            if (depth + 1, ck) in occ:
                st = 2
            elif (depth + 1, ck) in fre:
                st = 1
            elif any(inside(depth + 1, ck, leaf) for leaf in leaves):
                st = 3
                tail += encode(depth + 1, ck)
            else:
                st = 0
            n_nodes += st != 0
            states |= st << (2 * i)
        return bytes([states & 0xFF, states >> 8]) + tail

    stream = encode(0, (0, 0, 0))
    if cut:
        stream = stream[:-cut]
    header = (f"# Octomap OcTree binary file\n# written by test_io\nid OcTree\n"
              f"size {n_nodes if size is None else size}\nres {res}\ndata\n")
    path.write_bytes(header.encode() + stream)


def write_3dmap(path: Path, dims, voxels, header: str | None = None) -> None:
    head = header if header is not None else "voxel {} {} {}".format(*dims)
    path.write_text(head + "\n" + "".join(f"{x} {y} {z}\n" for x, y, z in voxels))


# --------------------------------------------------------------------------------------------
# Round trips
# --------------------------------------------------------------------------------------------


@pytest.mark.parametrize("name", ["c.ply", "c.npy", "c.xyz", "c.txt", "c.dat", "c.xyz.gz",
                                  "c.txt.bz2", "C.PLY"])
def test_save_then_load_round_trips_exactly(tmp_path, cloud, name):
    save_points(tmp_path / name, cloud)
    back = load_points(tmp_path / name)
    assert back.dtype == np.float64 and back.shape == cloud.shape
    np.testing.assert_array_equal(back, cloud)


@pytest.mark.parametrize("name", ["c.ply", "c.npy"])
def test_save_float32_stores_single_precision(tmp_path, cloud, name):
    save_points(tmp_path / name, cloud, dtype=np.float32)
    np.testing.assert_array_equal(load_points(tmp_path / name),
                                  cloud.astype(np.float32).astype(np.float64))


def test_saved_ply_is_binary_little_endian_vertex_xyz(tmp_path, cloud):
    save_points(tmp_path / "c.ply", cloud)
    ply = PlyData.read(str(tmp_path / "c.ply"))
    assert not ply.text and ply.byte_order == "<"
    assert ply["vertex"].data.dtype.names == ("x", "y", "z")


def test_save_is_atomic_and_overwrites(tmp_path, cloud):
    target = tmp_path / "out" / "c.ply"
    save_points(target, cloud)
    save_points(target, cloud[:10])
    assert len(load_points(target)) == 10
    assert os.listdir(target.parent) == ["c.ply"]  # no temporary left behind
    with pytest.raises(MapError, match="c.ply"):
        save_points(target, np.full((3, 3), np.nan))
    assert len(load_points(target)) == 10  # a failed save leaves the old file untouched


@pytest.mark.parametrize("text", [True, False])
@pytest.mark.parametrize("byte_order", ["<", ">"])
def test_ply_ascii_and_binary_with_extra_properties(tmp_path, cloud, text, byte_order):
    write_ply(tmp_path / "m.ply", cloud, text=text, byte_order=byte_order)
    np.testing.assert_array_equal(load_points(tmp_path / "m.ply"),
                                  cloud.astype(np.float32).astype(np.float64))


@pytest.mark.parametrize("kind", ["ascii", "binary", "binary_compressed"])
def test_pcd_reads_xyz_among_other_fields(tmp_path, cloud, kind):
    expected = write_pcd(tmp_path / "c.pcd", cloud, kind)
    got = load_points(tmp_path / "c.pcd")
    np.testing.assert_array_equal(got, expected)
    np.testing.assert_allclose(got, cloud, atol=1e-5)


def test_pcd_binary_compressed_with_literal_only_lzf(tmp_path, cloud):
    expected = write_pcd(tmp_path / "c.pcd", cloud, "binary_compressed", lzf=lzf_literals)
    np.testing.assert_array_equal(load_points(tmp_path / "c.pcd"), expected)


def test_pcd_binary_compressed_with_long_back_references(tmp_path):
    # Highly repetitive data makes the compressor emit long and overlapping back references.
    pts = np.tile([[1.0, 2.0, 3.0], [1.0, 2.0, 3.5]], (2000, 1))
    fields = [("x", "F", 4, 1), ("y", "F", 4, 1), ("z", "F", 4, 1)]
    write_pcd(tmp_path / "r.pcd", pts, "binary_compressed", fields=fields)
    assert (tmp_path / "r.pcd").stat().st_size < 1000
    np.testing.assert_array_equal(load_points(tmp_path / "r.pcd"), pts)


@settings(max_examples=40, deadline=None)
@given(st.lists(st.tuples(*[st.sampled_from([0.5, -1.25, 3.0, 1e6, 7.0])] * 3), min_size=1,
                max_size=300))
def test_pcd_binary_compressed_round_trips_any_cloud(tmp_path_factory, rows):
    pts = np.array(rows, dtype=np.float64)
    fields = [("x", "F", 4, 1), ("y", "F", 4, 1), ("z", "F", 4, 1)]
    path = tmp_path_factory.mktemp("lzf") / "h.pcd"
    write_pcd(path, pts, "binary_compressed", fields=fields)
    np.testing.assert_array_equal(load_points(path), pts)

def test_text_xyz_ignores_comments_and_extra_columns_and_accepts_commas(tmp_path):
    (tmp_path / "a.xyz").write_text("# x y z intensity\n1 2 3 0.5\n\n4 5 6 0.7  # tail\n")
    (tmp_path / "b.txt").write_text("1.5,2,3\n-4, 5e-1, 6\n")
    np.testing.assert_array_equal(load_points(tmp_path / "a.xyz"), [[1, 2, 3], [4, 5, 6]])
    np.testing.assert_array_equal(load_points(tmp_path / "b.txt"), [[1.5, 2, 3], [-4, 0.5, 6]])


def test_explicit_format_overrides_extension(tmp_path, cloud):
    save_points(tmp_path / "c.xyz", cloud)
    os.rename(tmp_path / "c.xyz", tmp_path / "scan.points")
    np.testing.assert_array_equal(load_points(tmp_path / "scan.points", format="xyz"), cloud)
    save_points(tmp_path / "c.ply", cloud)
    np.testing.assert_array_equal(load_points(tmp_path / "c.ply", format="PLY"), cloud)


@pytest.mark.parametrize("fmt", ["ply", "pcd", "xyz", "npy"])
def test_point_clouds_drop_no_return_origin_points(tmp_path, cloud, fmt):
    pts = cloud.copy()
    pts[::5] = 0.0  # no-returns
    pts[1] = (0.0, 0.0, 1.0)  # a single zero coordinate is a real point
    path = tmp_path / f"c.{fmt}"
    if fmt == "pcd":
        write_pcd(path, pts, "binary")
    elif fmt == "ply":
        write_ply(path, pts, text=False)
    else:
        save_points(path, pts)
    got = load_points(path)
    assert len(got) == len(pts) - len(pts[::5])
    assert not (got == 0).all(axis=1).any()
    assert ((got == (0.0, 0.0, 1.0)).all(axis=1)).sum() == 1


def test_point_cloud_obstacles_have_points_only(tmp_path, cloud):
    save_points(tmp_path / "c.npy", cloud)
    obst = load_obstacles(tmp_path / "c.npy")
    assert isinstance(obst, Obstacles)
    assert obst.points.shape == (50, 3) and obst.boxes.shape == (0, 3)
    assert obst.box_size == 0.0 and obst.bounds is None and obst.resolution is None
    assert obst.source == "c.npy"


# --------------------------------------------------------------------------------------------
# Voxel maps: MovingAI .3dmap / .3dscen, OctoMap .bt
# --------------------------------------------------------------------------------------------


def test_3dmap_gives_unit_boxes_and_bounds(tmp_path):
    write_3dmap(tmp_path / "m.3dmap", (4, 5, 6), [(0, 0, 0), (3, 4, 5), (1, 2, 3)])
    obst = load_obstacles(tmp_path / "m.3dmap")
    np.testing.assert_array_equal(obst.boxes, [[0, 0, 0], [3, 4, 5], [1, 2, 3]])
    assert obst.points.shape == (0, 3)
    assert obst.box_size == 1.0 and obst.resolution == 1.0
    np.testing.assert_array_equal(obst.bounds, [[-0.5, -0.5, -0.5], [3.5, 4.5, 5.5]])
    np.testing.assert_array_equal(load_points(tmp_path / "m.3dmap"), obst.boxes)


def test_3dscen_reads_starts_goals_costs(tmp_path):
    (tmp_path / "m.3dscen").write_text(
        "version 1\nm.3dmap\n1 2 3 4 5 6 7.5 1.01\n0 0 0 1 1 1 1.73205081 1\n")
    sc = load_scenarios(tmp_path / "m.3dscen")
    assert isinstance(sc, Scenarios) and len(sc) == 2 and sc.map_name == "m.3dmap"
    assert sc.starts.dtype == np.int64 and sc.goals.dtype == np.int64
    np.testing.assert_array_equal(sc.starts, [[1, 2, 3], [0, 0, 0]])
    np.testing.assert_array_equal(sc.goals, [[4, 5, 6], [1, 1, 1]])
    np.testing.assert_array_equal(sc.costs, [7.5, 1.73205081])


def test_octomap_voxel_centres_follow_the_key_convention(tmp_path):
    # Key 32768 is the origin; finest voxel k has its centre at (k - 32768 + 0.5) * res.
    res = 0.25
    write_bt(tmp_path / "m.bt", res=res,
             occupied=[(16, (32768, 32768, 32768)), (16, (32767, 32767, 32767)),
                       (16, (32769, 32768, 32770))],
             free=[(16, (32768, 32769, 32768))])
    obst = load_obstacles(tmp_path / "m.bt")
    # An occupied leaf is a box, not also a point; free leaves are kept as free boxes.
    assert obst.points.shape == (0, 3)
    got = sorted(map(tuple, obst.boxes))
    assert got == sorted([(0.125, 0.125, 0.125), (-0.125, -0.125, -0.125),
                          (0.375, 0.125, 0.625)])
    np.testing.assert_array_equal(obst.box_sizes, [res] * 3)
    np.testing.assert_array_equal(obst.free_boxes, [(0.125, 0.375, 0.125)])
    np.testing.assert_array_equal(obst.free_box_sizes, [res])
    assert obst.box_size == res and obst.resolution == res and obst.bounds is None
    assert obst.unknown_default == "blocked" and obst.has_free_space


def test_octomap_pruned_leaves_expand_to_finest_voxels(tmp_path):
    # A depth-14 leaf spans 4 keys per axis -> 64 finest voxels; plus one depth-16 voxel.
    write_bt(tmp_path / "m.bt", res=1.0,
             occupied=[(14, (32768, 32768, 32768)), (16, (32760, 32760, 32760))],
             free=[(15, (32764, 32764, 32764))])
    obst = load_obstacles(tmp_path / "m.bt")
    # Leaves keep their own size: the depth-14 leaf is one 4 m box centred at (2, 2, 2).
    order = np.argsort(obst.box_sizes)
    np.testing.assert_array_equal(obst.box_sizes[order], [1.0, 4.0])
    np.testing.assert_array_equal(obst.boxes[order], [[-7.5] * 3, [2.0] * 3])
    np.testing.assert_array_equal(obst.free_boxes, [[-3.0] * 3])
    np.testing.assert_array_equal(obst.free_box_sizes, [2.0])
    assert obst.box_size == 4.0  # the largest: conservative for single-size consumers
    pts = load_points(tmp_path / "m.bt")
    assert len(pts) == 65
    cube = pts[(pts >= 0).all(axis=1)]
    assert len(np.unique(cube, axis=0)) == 64
    np.testing.assert_array_equal(cube.min(axis=0), [0.5] * 3)
    np.testing.assert_array_equal(cube.max(axis=0), [3.5] * 3)
    assert ((pts == -7.5).all(axis=1)).sum() == 1


# --------------------------------------------------------------------------------------------
# Posed scans
# --------------------------------------------------------------------------------------------


def test_merge_scans_applies_poses_and_drops_no_returns():
    a = np.array([[1.0, 0, 0], [0, 0, 0]])
    b = np.array([[1.0, 2, 3]])
    rz90 = np.array([[0, -1, 0, 10], [1, 0, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1.0]])
    merged = merge_scans([a, b], [np.eye(4), rz90])
    np.testing.assert_allclose(merged, [[1, 0, 0], [8, 1, 3]])


def test_load_posed_scans_matrix_and_quaternion_lines(tmp_path, cloud):
    (tmp_path / "scans").mkdir()
    save_points(tmp_path / "scans" / "a.npy", cloud)
    save_points(tmp_path / "scans" / "b.xyz", cloud[:5])
    s = math.sqrt(0.5)
    (tmp_path / "poses.txt").write_text(
        "# scan  pose\n"
        "scans/a.npy 1 0 0 1  0 1 0 2  0 0 1 3  0 0 0 1\n"
        "\n"
        f"scans/b.xyz, 0, 0, 5, 0, 0, {s}, {s}   # 90 deg about z, raised 5 m\n")
    merged = load_posed_scans(tmp_path / "poses.txt")
    assert merged.shape == (55, 3)
    np.testing.assert_allclose(merged[:50], cloud + [1, 2, 3])
    expected_b = np.column_stack([-cloud[:5, 1], cloud[:5, 0], cloud[:5, 2] + 5])
    np.testing.assert_allclose(merged[50:], expected_b, atol=1e-12)


# --------------------------------------------------------------------------------------------
# Bad input: always MapError naming the file
# --------------------------------------------------------------------------------------------


def _raises(path: Path, match: str, **kw) -> None:
    with pytest.raises(MapError, match=match) as info:
        load_obstacles(path, **kw)
    msg = str(info.value)
    assert path.name in msg and "\n" not in msg


@pytest.mark.parametrize("name", ["gone.ply", "gone.pcd", "gone.xyz.gz", "gone.npy", "gone.bt",
                                  "gone.3dmap"])
def test_missing_file(tmp_path, name):
    _raises(tmp_path / name, "not found")


def test_unknown_extension_or_format(tmp_path):
    (tmp_path / "m.obj").write_text("v 1 2 3\n")
    _raises(tmp_path / "m.obj", "unknown file extension")
    _raises(tmp_path / "m.obj", "unknown format", format="obj")
    (tmp_path / "m.ply.gz").write_bytes(gzip.compress(b"ply\n"))
    _raises(tmp_path / "m.ply.gz", "only supported for text")


@pytest.mark.parametrize("text", [True, False])
def test_ply_promising_more_vertices_than_present(tmp_path, cloud, text):
    path = tmp_path / "t.ply"
    write_ply(path, cloud, text=text)
    raw = path.read_bytes().replace(b"element vertex 50", b"element vertex 99")
    path.write_bytes(raw)
    _raises(path, "PLY")


def test_ply_without_vertex_xyz(tmp_path):
    el = PlyElement.describe(np.zeros(3, dtype=[("u", "f4"), ("v", "f4")]), "vertex")
    PlyData([el]).write(str(tmp_path / "uv.ply"))
    _raises(tmp_path / "uv.ply", "lacks")
    (tmp_path / "junk.ply").write_bytes(b"not a ply file at all")
    _raises(tmp_path / "junk.ply", "corrupt")


@pytest.mark.parametrize("kind", ["ascii", "binary", "binary_compressed"])
def test_pcd_promising_more_points_than_present(tmp_path, cloud, kind):
    write_pcd(tmp_path / "t.pcd", cloud, kind, points_in_header=60)
    _raises(tmp_path / "t.pcd", "60")


def test_pcd_truncated_compressed_block(tmp_path, cloud):
    path = tmp_path / "t.pcd"
    write_pcd(path, cloud, "binary_compressed")
    path.write_bytes(path.read_bytes()[:-10])
    _raises(path, "truncated")


def test_pcd_corrupt_lzf(tmp_path, cloud):
    path = tmp_path / "t.pcd"
    write_pcd(path, cloud, "binary_compressed", lzf=lzf_literals)
    raw = bytearray(path.read_bytes())
    start = raw.index(b"DATA binary_compressed\n") + len("DATA binary_compressed\n") + 8
    raw[start] = 0xE0  # a back reference before any output exists
    path.write_bytes(bytes(raw))
    _raises(path, "corrupt LZF")


@pytest.mark.parametrize(("edit", "match"), [
    ((b"FIELDS intensity x _ y rgb z", b"FIELDS intensity x _ y rgb w"), "no 'z' field"),
    ((b"DATA binary", b"DATA packed"), "unknown PCD DATA"),
    ((b"DATA binary\n", b"DADA binary\n"), "no 'DATA' line"),
    ((b"SIZE 4 4 1 8 4 4", b"SIZE 4 4 1 8 4"), "lengths differ"),
    ((b"TYPE F F U F U F", b"TYPE F F U F U Q"), "unsupported TYPE"),
])
def test_pcd_bad_header(tmp_path, cloud, edit, match):
    path = tmp_path / "h.pcd"
    write_pcd(path, cloud, "binary")
    path.write_bytes(path.read_bytes().replace(*edit))
    _raises(path, match)


def test_octomap_stream_ending_early(tmp_path):
    write_bt(tmp_path / "t.bt", occupied=[(16, (32768, 32768, 32768))], cut=3)
    _raises(tmp_path / "t.bt", "truncated")


def test_octomap_node_count_mismatch(tmp_path):
    write_bt(tmp_path / "n.bt", occupied=[(16, (32768, 32768, 32768))], size=7)
    _raises(tmp_path / "n.bt", "7 nodes")


@pytest.mark.parametrize(("header", "match"), [
    (b"# not an octomap\nid OcTree\nsize 1\nres 0.1\ndata\n", "not an OctoMap"),
    (b"# Octomap OcTree binary file\nid ColorOcTree\nsize 1\nres 0.1\ndata\n", "tree id"),
    (b"# Octomap OcTree binary file\nid OcTree\nsize 1\ndata\n", "lacks"),
    (b"# Octomap OcTree binary file\nid OcTree\nsize 1\nres -1\ndata\n", "positive"),
    (b"# Octomap OcTree binary file\nid OcTree\nsize x\nres 0.1\ndata\n", "bad OctoMap header"),
    (b"# Octomap OcTree binary file\nid OcTree\nsize 1\nres 0.1\n", "no 'data' line"),
])
def test_octomap_bad_header(tmp_path, header, match):
    (tmp_path / "h.bt").write_bytes(header + b"\x00\x00")
    _raises(tmp_path / "h.bt", match)


def test_octomap_with_absurdly_coarse_leaf(tmp_path):
    write_bt(tmp_path / "c.bt", occupied=[(1, (32768, 32768, 32768))])
    obst = load_obstacles(tmp_path / "c.bt")  # one box is cheap ...
    np.testing.assert_allclose(obst.box_sizes, [2**15 * 0.1])
    with pytest.raises(MapError, match="c.bt.*limit"):  # ... its 2**45 finest voxels are not
        load_points(tmp_path / "c.bt")


@settings(max_examples=60, deadline=None)
@given(st.data())
def test_corrupted_binary_files_raise_map_error_or_load(tmp_path_factory, data):
    # Flipped bytes inside compressed PCD / OctoMap streams: a clean MapError or a valid
    # cloud, never a crash or another exception type.
    folder = tmp_path_factory.mktemp("fuzz")
    pts = np.random.default_rng(3).uniform(-5, 5, (40, 3))
    write_pcd(folder / "f.pcd", pts, "binary_compressed")
    write_bt(folder / "f.bt", occupied=[(16, (32768, 32768, 32768)), (15, (32770, 32770, 32770)),
                                        (16, (32767, 32760, 32769))])
    for path in (folder / "f.pcd", folder / "f.bt"):
        raw = bytearray(path.read_bytes())
        body = raw.index(b"DATA binary_compressed\n" if path.suffix == ".pcd" else b"data\n")
        for _ in range(data.draw(st.integers(1, 4))):
            i = data.draw(st.integers(body + 6, len(raw) - 1))
            raw[i] = data.draw(st.integers(0, 255))
        path.write_bytes(bytes(raw))
        try:
            got = load_points(path)
        except MapError as exc:
            assert path.name in str(exc)
        else:
            assert got.ndim == 2 and got.shape[1] == 3 and np.isfinite(got).all()

@pytest.mark.parametrize(("text", "match"), [
    ("1 2 3\n4 5\n", "line 2"),
    ("# header\n1 2 3\n4 x 6\n", "line 3"),
    ("1 2 inf\n", "NaN or infinite"),
    ("nan 1 2\n-inf 0 0\n", "every point"),
    ("", "empty"),
    ("# only a comment\n", "empty"),
    ("0 0 0\n0 0 0\n", "no-return"),
])
def test_bad_text_clouds(tmp_path, text, match):
    (tmp_path / "t.xyz").write_text(text)
    _raises(tmp_path / "t.xyz", match)


def test_corrupt_compressed_text(tmp_path):
    (tmp_path / "t.xyz.gz").write_bytes(gzip.compress(b"1 2 3\n" * 100)[:-20])
    _raises(tmp_path / "t.xyz.gz", "corrupt or truncated")
    (tmp_path / "t.xyz.bz2").write_bytes(b"BZh9 garbage")
    _raises(tmp_path / "t.xyz.bz2", "corrupt or truncated")
    (tmp_path / "b.xyz").write_bytes(b"\xff\xfe\x00binary")
    _raises(tmp_path / "b.xyz", "not a text file")


@pytest.mark.parametrize(("array", "match"), [
    (np.zeros((4, 2)), "shape"),
    (np.zeros((0, 3)), "empty"),
    (np.array([[1.0, np.inf, 0]]), "NaN or infinite"),
    (np.array([["a", "b", "c"]]), "numeric"),
])
def test_bad_npy(tmp_path, array, match):
    np.save(tmp_path / "a.npy", array)
    _raises(tmp_path / "a.npy", match)


def test_npy_that_is_not_npy(tmp_path):
    (tmp_path / "n.npy").write_bytes(b"\x93NUMPY garbage")
    _raises(tmp_path / "n.npy", "not a valid .npy")


def test_pcd_with_nan_points_drops_and_counts_them(tmp_path, cloud):
    pts = cloud.copy()
    pts[3, 1] = np.nan
    want = write_pcd(tmp_path / "n.pcd", pts, "binary")
    obst = load_obstacles(tmp_path / "n.pcd")
    assert obst.dropped_nonfinite == 1
    np.testing.assert_array_equal(obst.points, np.delete(want, 3, axis=0))
    write_pcd(tmp_path / "all.pcd", np.full((4, 3), np.nan), "binary")
    _raises(tmp_path / "all.pcd", "every point")


@pytest.mark.parametrize(("header", "voxels", "match"), [
    ("voxels 4 4 4", [(1, 1, 1)], "bad .3dmap header"),
    ("voxel 4 4", [(1, 1, 1)], "bad .3dmap header"),
    ("voxel 4 0 4", [(1, 1, 1)], "positive"),
    ("voxel 4 4 4", [(1, 1, 1), (1, 4, 1)], "outside"),
    ("voxel 4 4 4", [(1, 1, 1), (-1, 2, 2)], "outside"),
    ("voxel 4 4 4", [], "no blocked voxels"),
])
def test_bad_3dmap(tmp_path, header, voxels, match):
    write_3dmap(tmp_path / "b.3dmap", None, voxels, header=header)
    _raises(tmp_path / "b.3dmap", match)


def test_3dmap_malformed_line(tmp_path):
    (tmp_path / "b.3dmap").write_text("voxel 4 4 4\n1 1 1\n1 2\n")
    _raises(tmp_path / "b.3dmap", "line 3")
    (tmp_path / "f.3dmap").write_text("voxel 4 4 4\n1 1 1.5\n")
    _raises(tmp_path / "f.3dmap", "integers")


@pytest.mark.parametrize(("text", "match"), [
    ("version 1\nm.3dmap\n1 2 3 4 5 6 7\n", "line 3"),
    ("m.3dmap\n1 2 3 4 5 6 7 1\n", "version"),
    ("version 1\nm.3dmap\n", "no queries"),
    ("version 1\nm.3dmap\n1 2 3 4 5 6.5 7 1\n", "integers"),
])
def test_bad_3dscen(tmp_path, text, match):
    (tmp_path / "s.3dscen").write_text(text)
    with pytest.raises(MapError, match=match) as info:
        load_scenarios(tmp_path / "s.3dscen")
    assert "s.3dscen" in str(info.value)


@pytest.mark.parametrize(("line", "match"), [
    ("a.npy 1 2 3\n", "poses.txt:1"),
    ("a.npy 1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 2\n", "last row"),
    ("a.npy 2 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1\n", "rotation"),
    ("a.npy 0 0 0 0 0 0 0\n", "quaternion"),
    ("a.npy 0 0 0 0 0 0 one\n", "numbers"),
    ("missing.npy 0 0 0 0 0 0 1\n", "missing.npy"),
    ("# nothing\n", "no scans"),
])
def test_bad_pose_files(tmp_path, cloud, line, match):
    save_points(tmp_path / "a.npy", cloud)
    (tmp_path / "poses.txt").write_text(line)
    with pytest.raises(MapError, match=match):
        load_posed_scans(tmp_path / "poses.txt")


def test_bad_merge_arguments(cloud):
    with pytest.raises(MapError, match="2 scans but 1 poses"):
        merge_scans([cloud, cloud], [np.eye(4)])
    with pytest.raises(MapError, match="4x4"):
        merge_scans([cloud], [np.eye(3)])
    with pytest.raises(MapError, match="no points"):
        merge_scans([np.zeros((2, 3))], [np.eye(4)])


@pytest.mark.parametrize(("name", "points", "match"), [
    ("a.obj", np.ones((2, 3)), "unknown file extension"),
    ("a.pcd", np.ones((2, 3)), "cannot write"),
    ("a.ply", np.ones((2, 2)), "shape"),
    ("a.ply", np.zeros((0, 3)), "empty"),
])
def test_bad_save(tmp_path, name, points, match):
    with pytest.raises(MapError, match=match):
        save_points(tmp_path / name, points)
    assert not (tmp_path / name).exists()


# --------------------------------------------------------------------------------------------
# Real data (../shared/data)
# --------------------------------------------------------------------------------------------


def test_real_octomap_geb079(data):
    obst = load_obstacles(data / "octomap" / "geb079.bt")
    # 143,729 occupied leaves: 137,745 of 0.08 m, 5,983 of 0.16 m and one of 0.32 m.
    sizes, counts = np.unique(np.round(obst.box_sizes / 0.08).astype(int), return_counts=True)
    assert sizes.tolist() == [1, 2, 4] and counts.tolist() == [137_745, 5_983, 1]
    assert len(obst.points) == 0 and len(obst.free_boxes) > 0
    assert obst.resolution == 0.08 and obst.bounds is None and obst.unknown_default == "blocked"
    pts = load_points(data / "octomap" / "geb079.bt")  # leaves filled with 0.08 m centres
    assert len(pts) == 185_673
    assert len(np.unique(pts, axis=0)) == 185_673
    # Centres sit on the 0.08 m grid offset by half a cell.
    k = pts / 0.08 - 0.5
    np.testing.assert_allclose(k, np.round(k), atol=1e-6)
    extent = pts.max(axis=0) - pts.min(axis=0)  # "about 39 x 15 x 3 m"
    np.testing.assert_allclose(extent, [39, 15, 3], atol=1.0)


def test_real_laser_scan_dat_bz2(data):
    pts = load_points(data / "octomap" / "scan.dat.bz2")
    assert pts.shape == (88_206, 3)
    r = np.linalg.norm(pts, axis=1)
    assert 0.4 < r.min() and r.max() < 30  # "range 0.47-29 m"


@pytest.mark.parametrize("name", ["room_scan1.pcd", "room_scan2.pcd"])
def test_real_room_scans_lzf(data, name):
    pts = load_points(data / "pcl_room" / name)
    assert 112_500 < len(pts) < 112_700
    assert np.isfinite(pts).all()
    assert (np.ptp(pts, axis=0) < 40).all()  # one indoor room


def test_real_velodyne_scans_merge_with_relative_transform(data):
    from scipy.spatial import cKDTree

    d = data / "velodyne"
    a, b = load_points(d / "251370668.pcd"), load_points(d / "251371071.pcd")
    for pts in (a, b):
        assert 60_000 < len(pts) < 69_088
        assert not (pts == 0).all(axis=1).any()
    rel = np.loadtxt(d / "relative.txt")
    merged = merge_scans([a, b], [np.eye(4), rel])
    assert merged.shape == (len(a) + len(b), 3)
    np.testing.assert_array_equal(merged[: len(a)], a)
    # The transform maps the second sweep onto the first: alignment beats the raw frames.
    tree = cKDTree(a)
    aligned = np.median(tree.query(merged[len(a):])[0])
    raw = np.median(tree.query(b)[0])
    assert aligned < 0.75 * raw


def test_real_velodyne_via_pose_file(data, tmp_path):
    d = (data / "velodyne").resolve()
    rel = np.loadtxt(d / "relative.txt")
    (tmp_path / "poses.csv").write_text(
        f"{d / '251370668.pcd'},0,0,0,0,0,0,1\n"
        f"{d / '251371071.pcd'}," + ",".join(repr(float(v)) for v in rel.ravel()) + "\n")
    merged = load_posed_scans(tmp_path / "poses.csv")
    expected = merge_scans([load_points(d / "251370668.pcd"), load_points(d / "251371071.pcd")],
                           [np.eye(4), rel])
    np.testing.assert_allclose(merged, expected)


@pytest.mark.parametrize(("name", "dims"), [
    ("Simple", (105, 132, 105)), ("Complex", (246, 154, 205)), ("DA1", (389, 313, 511))])
def test_real_warframe_maps_and_scenarios(data, name, dims):
    obst = load_obstacles(data / "warframe" / f"{name}.3dmap")
    np.testing.assert_array_equal(obst.bounds, [[-0.5] * 3, np.array(dims) - 0.5])
    assert len(obst.boxes) > 0 and obst.box_size == 1.0
    assert (obst.boxes >= 0).all() and (obst.boxes <= np.array(dims) - 1).all()
    assert len(np.unique(obst.boxes, axis=0)) == len(obst.boxes)
    sc = load_scenarios(data / "warframe" / f"{name}.3dmap.3dscen")
    assert len(sc) == 10_000 and sc.map_name == f"{name}.3dmap"
    for ends in (sc.starts, sc.goals):
        assert (ends >= 0).all() and (ends < np.array(dims)).all()
    assert (sc.costs >= 0).all()
    # Queries start and end in free voxels.
    blocked = set(map(tuple, obst.boxes.astype(np.int64)))
    assert not any(tuple(s) in blocked for s in sc.starts[:500])


def test_real_text_written_back_compressed(data, tmp_path):
    pts = load_points(data / "octomap" / "scan.dat.bz2")
    save_points(tmp_path / "scan.xyz.bz2", pts)
    np.testing.assert_array_equal(load_points(tmp_path / "scan.xyz.bz2"), pts)
    assert bz2.decompress((tmp_path / "scan.xyz.bz2").read_bytes()).count(b"\n") == len(pts)


def test_the_ply_writer_writes_what_plyfile_writes(tmp_path, cloud):
    from planner.io.ply import write_ply as io_write_ply

    vert = np.empty(len(cloud), dtype=[("x", "<f4"), ("y", "<f4"), ("z", "<f4")])
    for i, c in enumerate("xyz"):
        vert[c] = cloud[:, i]
    PlyData([PlyElement.describe(vert, "vertex")], text=False, byte_order="<",
            comments=["made by a test"]).write(str(tmp_path / "a.ply"))
    io_write_ply(tmp_path / "b.ply", cloud, np.float32, ("made by a test",))
    assert (tmp_path / "a.ply").read_bytes() == (tmp_path / "b.ply").read_bytes()


def test_obstacles_from_points_keeps_the_origin_and_drops_nan():
    from planner.io import obstacles_from_points

    ob = obstacles_from_points([[0.0, 0, 0], [1, np.nan, 2], [3, 4, 5]])
    np.testing.assert_array_equal(ob.points, [[0, 0, 0], [3, 4, 5]])
    assert ob.dropped_nonfinite == 1 and ob.source == "<array>" and ob.unknown_default == "free"
    with pytest.raises(MapError, match="every point"):
        obstacles_from_points([[np.nan, 0, 0]])
