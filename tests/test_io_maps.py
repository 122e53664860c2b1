"""planner.io: map meaning (free / unknown space, 2D ROS maps, sensor origins) and inputs that
used to be mis-read (header lies, BOMs, long headers, decompression bombs, absurd values)."""

from __future__ import annotations

import gzip
import json
from pathlib import Path

import numpy as np
import pytest

from planner.errors import MapError
from planner.io import (
    Obstacles,
    load_obstacles,
    load_points,
    load_sidecar,
    robust_extent,
    save_points,
)


def _raises(path: Path, match: str, **kw) -> MapError:
    with pytest.raises(MapError, match=match) as info:
        load_obstacles(path, **kw)
    msg = str(info.value)
    assert "\n" not in msg and Path(path).name in msg
    return info.value


def write_organized_pcd(path: Path, grid: np.ndarray, extra_header: list[str] = ()) -> None:
    """Binary PCD of an organized (H, W, 3) float32 cloud, as RGB-D drivers write it."""
    h, w, _ = grid.shape
    header = ["# .PCD v0.7", *extra_header, "VERSION 0.7", "FIELDS x y z", "SIZE 4 4 4",
              "TYPE F F F", "COUNT 1 1 1", f"WIDTH {w}", f"HEIGHT {h}",
              "VIEWPOINT 0 0 0 1 0 0 0", f"POINTS {h * w}", "DATA binary"]
    path.write_bytes(("\n".join(header) + "\n").encode() + grid.astype("<f4").tobytes())


# -- NaN points --------------------------------------------------------------------------------
def test_organized_pcd_with_nan_holes_keeps_the_finite_points(tmp_path):
    grid = np.random.default_rng(0).uniform(1, 5, (3, 4, 3)).astype(np.float32)
    grid[0, 1] = np.nan  # a missing return
    grid[2, :, 2] = np.inf  # a whole row half-missing
    write_organized_pcd(tmp_path / "o.pcd", grid)
    obst = load_obstacles(tmp_path / "o.pcd")
    assert obst.dropped_nonfinite == 5 and len(obst.points) == 7
    flat = grid.reshape(-1, 3).astype(np.float64)
    np.testing.assert_array_equal(obst.points, flat[np.isfinite(flat).all(axis=1)])
    write_organized_pcd(tmp_path / "nan.pcd", np.full((2, 2, 3), np.nan, np.float32))
    _raises(tmp_path / "nan.pcd", "every point")


@pytest.mark.parametrize("name", ["c.ply", "c.npy", "c.xyz"])
def test_nan_rows_are_dropped_and_counted_in_every_cloud_format(tmp_path, name):
    pts = np.array([[1.0, 2, 3], [np.nan, 0, 1], [4, 5, np.inf], [7, 8, 9]])
    path = tmp_path / name
    if name.endswith(".npy"):
        np.save(path, pts)
    elif name.endswith(".xyz"):
        path.write_text("1 2 3\nnan 0 1\n4 5 inf\n7 8 9\n")
    else:
        save_points(tmp_path / "ok.ply", pts[[0, 3]])
        raw = (tmp_path / "ok.ply").read_bytes()
        head, body = raw.split(b"end_header\n")
        nan_rows = np.array([[np.nan, 0, 1], [4, 5, np.inf]], "<f8").tobytes()
        path.write_bytes(head.replace(b"vertex 2", b"vertex 4") + b"end_header\n" + body
                         + nan_rows)
    obst = load_obstacles(path)
    assert obst.dropped_nonfinite == 2
    assert sorted(map(tuple, obst.points)) == [(1, 2, 3), (7, 8, 9)]


# -- free and unknown space ----------------------------------------------------------------------
def test_plain_clouds_say_unknown_space_is_free_and_posed_scans_keep_origins(tmp_path):
    save_points(tmp_path / "a.npy", np.array([[1.0, 0, 0], [2.0, 0, 0]]))
    cloud = load_obstacles(tmp_path / "a.npy")
    assert cloud.unknown_default == "free" and not cloud.has_free_space
    assert cloud.origins is None and cloud.free_boxes.shape == (0, 3)
    (tmp_path / "poses.txt").write_text("a.npy 0 0 0 0 0 0 1\na.npy 5 0 1 0 0 0 1\n")
    posed = load_obstacles(tmp_path / "poses.txt", "poses")
    np.testing.assert_array_equal(posed.origins, [[0, 0, 0], [5, 0, 1]])
    assert posed.point_origin.tolist() == [0, 0, 1, 1]
    np.testing.assert_array_equal(posed.points[2:], [[6, 0, 1], [7, 0, 1]])
    assert posed.unknown_default == "blocked"


def test_obstacles_validates_its_map_fields():
    with pytest.raises(MapError, match="box_sizes"):
        Obstacles(points=np.zeros((0, 3)), boxes=np.zeros((2, 3)), box_size=1.0, bounds=None,
                  resolution=None, source="m", box_sizes=[1.0])
    with pytest.raises(MapError, match="go together"):
        Obstacles(points=np.ones((1, 3)), boxes=np.zeros((0, 3)), box_size=0.0, bounds=None,
                  resolution=None, source="m", origins=np.zeros((1, 3)))
    with pytest.raises(MapError, match="unknown_default"):
        Obstacles(points=np.ones((1, 3)), boxes=np.zeros((0, 3)), box_size=0.0, bounds=None,
                  resolution=None, source="m", unknown_default="maybe")
    ob = Obstacles(points=np.zeros((0, 3)), boxes=np.zeros((2, 3)), box_size=0.0, bounds=None,
                   resolution=0.5, source="m", box_sizes=[0.5, 1.0])
    assert ob.box_size == 1.0 and len(ob.box_centre_points()) == 1 + 8


# -- ROS map_server maps -------------------------------------------------------------------------
def write_rosmap(folder: Path, pixels: np.ndarray, *, binary: bool = True, negate: int = 0,
                 extra: str = "") -> Path:
    h, w = pixels.shape
    if binary:
        (folder / "map.pgm").write_bytes(f"P5\n# CREATOR: test\n{w} {h}\n255\n".encode()
                                         + pixels.astype(np.uint8).tobytes())
    else:
        rows = "\n".join(" ".join(str(v) for v in row) for row in pixels)
        (folder / "map.pgm").write_text(f"P2\n{w} {h}\n255\n{rows}\n")
    (folder / "map.yaml").write_text(
        "image: map.pgm\nresolution: 0.5\norigin: [-1.0, 2.0, 0.0]\n"
        f"negate: {negate}\noccupied_thresh: 0.65\nfree_thresh: 0.196\n{extra}")
    return folder / "map.yaml"


@pytest.mark.parametrize("binary", [True, False], ids=["P5", "P2"])
def test_ros_map_is_a_2d_tri_state_map(tmp_path, binary):
    # map_server's colours: 0 black = occupied, 254 white = free, 205 grey = unknown.
    pix = np.array([[0, 254, 205],
                    [254, 254, 0]])
    obst = load_obstacles(write_rosmap(tmp_path, pix, binary=binary))
    assert obst.dim == 2 and obst.resolution == 0.5 and obst.unknown_default == "blocked"
    np.testing.assert_array_equal(obst.bounds, [[-1.0, 2.0], [0.5, 3.0]])
    # Row 0 of the image is the top (largest y); centres at origin + (col + .5, row' + .5) res.
    assert sorted(map(tuple, obst.boxes)) == [(-0.75, 2.75), (0.25, 2.25)]
    assert sorted(map(tuple, obst.free_boxes)) == [(-0.75, 2.25), (-0.25, 2.25), (-0.25, 2.75)]
    np.testing.assert_array_equal(obst.box_sizes, [0.5, 0.5])
    np.testing.assert_array_equal(obst.free_box_sizes, [0.5] * 3)
    assert load_points(tmp_path / "map.yaml").shape == (2, 2)


def test_ros_map_negate_and_raw_mode(tmp_path):
    pix = np.array([[0, 255, 100]])
    neg = load_obstacles(write_rosmap(tmp_path, pix, negate=1))
    assert neg.boxes.tolist() == [[-0.25, 2.25]] and neg.free_boxes.tolist() == [[-0.75, 2.25]]
    raw = load_obstacles(write_rosmap(tmp_path, pix, extra="mode: raw\n"))
    # raw: the value is the occupancy in percent; above 100 it is unknown.
    assert raw.boxes.tolist() == [[0.25, 2.25]] and raw.free_boxes.tolist() == [[-0.75, 2.25]]


@pytest.mark.parametrize(("edit", "match"), [
    (("resolution: 0.5", "resolution: fine"), "'resolution' must be a number"),
    (("resolution: 0.5", "resolution: 1e300"), "between"),
    (("origin: [-1.0, 2.0, 0.0]", "origin: [1, 2]"), "origin"),
    (("origin: [-1.0, 2.0, 0.0]", "origin: [1, 2, 0.5]"), "rotated"),
    (("image: map.pgm", "image: none.pgm"), "none.pgm: file not found"),
    (("image: map.pgm\n", ""), "lacks 'image'"),
    (("mode: trinary", "mode: fancy"), "mode"),
    (("free_thresh: 0.196", "free_thresh: 0.9"), "free_thresh"),
])
def test_bad_ros_maps(tmp_path, edit, match):
    path = write_rosmap(tmp_path, np.array([[0, 254]]), extra="mode: trinary\n")
    path.write_text(path.read_text().replace(*edit))
    with pytest.raises(MapError, match=match):
        load_obstacles(path)


def test_truncated_or_lying_pgm(tmp_path):
    path = write_rosmap(tmp_path, np.array([[0, 254], [0, 254]]))
    raw = (tmp_path / "map.pgm").read_bytes()
    for data, match in ((raw[:-1], "map.pgm: truncated PGM"),
                        (b"P2\n2 2\n255\n1 2 3\n", "map.pgm: PGM declares 2x2"),
                        (b"P5\n2 2\n70000\n", "maxval"), (b"P5\n-2 2\n255\n", "header")):
        (tmp_path / "map.pgm").write_bytes(data)
        with pytest.raises(MapError, match=match):
            load_obstacles(path)


# -- header lies and valid input that used to be refused -------------------------------------------
@pytest.mark.parametrize("text", [True, False], ids=["ascii", "binary"])
def test_ply_declaring_fewer_points_than_it_holds(tmp_path, text):
    from plyfile import PlyData, PlyElement

    vert = np.array([(1.0, 2.0, 3.0)] * 5, dtype=[("x", "f4"), ("y", "f4"), ("z", "f4")])
    PlyData([PlyElement.describe(vert, "vertex")], text=text).write(str(tmp_path / "p.ply"))
    path = tmp_path / "p.ply"
    path.write_bytes(path.read_bytes().replace(b"element vertex 5", b"element vertex 3"))
    _raises(path, "declares 3 points, has more data")


@pytest.mark.parametrize("kind", ["binary", "ascii"])
def test_pcd_declaring_fewer_points_than_it_holds(tmp_path, kind):
    grid = np.arange(18, dtype=np.float32).reshape(1, 6, 3) + 1
    write_organized_pcd(tmp_path / "p.pcd", grid)
    raw = (tmp_path / "p.pcd").read_bytes().replace(b"WIDTH 6", b"WIDTH 4").replace(
        b"POINTS 6", b"POINTS 4")
    if kind == "ascii":
        head = raw[:raw.index(b"DATA binary")]
        rows = "\n".join(" ".join(str(v) for v in r) for r in grid.reshape(-1, 3))
        raw = head + b"DATA ascii\n" + rows.encode() + b"\n"
    (tmp_path / "p.pcd").write_bytes(raw)
    _raises(tmp_path / "p.pcd", "declares 4 points, has more data")


def test_pcd_with_a_long_comment_header_loads(tmp_path):
    grid = np.ones((1, 2, 3), np.float32)
    write_organized_pcd(tmp_path / "c.pcd", grid, [f"# comment {i}" for i in range(200)])
    assert len(load_points(tmp_path / "c.pcd")) == 2


def test_text_with_utf8_bom_loads(tmp_path):
    (tmp_path / "b.xyz").write_bytes(b"\xef\xbb\xbf1 2 3\n4 5 6\n")
    np.testing.assert_array_equal(load_points(tmp_path / "b.xyz"), [[1, 2, 3], [4, 5, 6]])


def test_gzip_bomb_is_refused_while_streaming(tmp_path):
    # 64 MiB of zeros compress to ~64 KiB; a 1 MiB budget stops after the first chunks.
    with gzip.open(tmp_path / "bomb.xyz.gz", "wb", compresslevel=9) as f:
        for _ in range(64):
            f.write(b"0" * (1 << 20))
    assert (tmp_path / "bomb.xyz.gz").stat().st_size < 1 << 20
    _raises(tmp_path / "bomb.xyz.gz", "decompression budget", max_decompressed=1 << 20)
    (tmp_path / "ok.xyz.gz").write_bytes(gzip.compress(b"1 2 3\n"))
    assert load_points(tmp_path / "ok.xyz.gz", max_decompressed=6).tolist() == [[1, 2, 3]]


@pytest.mark.parametrize("res", ["1e300", "1e-300", "inf", "nan", "0"])
def test_octomap_absurd_resolution(tmp_path, res):
    (tmp_path / "r.bt").write_bytes(b"# Octomap OcTree binary file\nid OcTree\nsize 2\n"
                                    b"res " + res.encode() + b"\ndata\n\x02\x00")
    _raises(tmp_path / "r.bt", "resolution")


def test_3dmap_dimensions_beyond_int64(tmp_path):
    (tmp_path / "h.3dmap").write_text("voxel 99999999999999999999999 4 4\n1 1 1\n")
    _raises(tmp_path / "h.3dmap", "dimensions")


def test_one_far_outlier_does_not_ruin_the_robust_extent(tmp_path):
    pts = np.vstack([np.random.default_rng(1).uniform(0, 10, (5000, 3)), [[1e6, 5, 5]]])
    save_points(tmp_path / "o.npy", pts)
    obst = load_obstacles(tmp_path / "o.npy")
    box, n_out = obst.robust_bounds()
    assert n_out == 1 and (box[1] < 10.001).all() and (box[0] > -0.001).all()
    box, n_out = robust_extent(pts[:-1])
    assert n_out == 0
    np.testing.assert_array_equal(box, [pts[:-1].min(axis=0), pts[:-1].max(axis=0)])


# -- sidecars --------------------------------------------------------------------------------------
GOOD_SIDECAR = {"bounds": [[0, 0, 0], [10, 10, 3]], "robot_radius": 0.3, "cell_volume": 0.008,
                "queries": [{"start": [1, 1, 1], "goal": [9, 9, 1], "note": "across"}]}


def test_sidecar_reads_and_normalises(tmp_path):
    (tmp_path / "m.json").write_text(json.dumps(GOOD_SIDECAR))
    info = load_sidecar(tmp_path / "m.ply")
    assert info["robot_radius"] == 0.3 and info["queries"][0]["goal"] == [9.0, 9.0, 1.0]
    assert load_sidecar(tmp_path / "none.ply") == {}


@pytest.mark.parametrize(("change", "match"), [
    ({"robot_radius": "x"}, "'robot_radius' must be a number"),
    ({"robot_radius": -1}, "'robot_radius' must be >= 0"),
    ({"cell_volume": 0}, "'cell_volume' must be > 0"),
    ({"bounds": "abc"}, "'bounds' must be 2 list"),
    ({"bounds": [[0, 0, 0], [1, 1, None]]}, "'bounds' must be a number"),
    ({"bounds": [[5, 0, 0], [1, 1, 1]]}, "min corner"),
    ({"queries": {"start": [1, 1, 1]}}, "'queries' must be a list"),
    ({"queries": [{"start": [1, 1, 1]}]}, r"'queries'\[0\] lacks 'goal'"),
    ({"queries": [{"start": [1, 1], "goal": [1, 1, 1]}]}, r"'queries'\[0\].start"),
    ({"queries": [7]}, "must be an object"),
    ({"file": 3}, "'file' must be a string"),
])
def test_bad_sidecars_name_file_and_key(tmp_path, change, match):
    (tmp_path / "m.json").write_text(json.dumps({**GOOD_SIDECAR, **change}))
    with pytest.raises(MapError, match=match) as info:
        load_sidecar(tmp_path / "m.ply")
    assert str(info.value).startswith("m.json") and "\n" not in str(info.value)


@pytest.mark.parametrize(("text", "match"), [("[1, 2]", "JSON object"), ("{", "not valid JSON"),
                                             ("{}", "lacks the key 'queries'")])
def test_sidecar_not_an_object_or_missing_required(tmp_path, text, match):
    (tmp_path / "m.json").write_text(text)
    with pytest.raises(MapError, match=match):
        load_sidecar(tmp_path / "m.json", required=("queries",))


def test_absurd_finite_coordinates_are_refused(tmp_path):
    (tmp_path / "far.xyz").write_text("1 2 3\n1e300 0 0\n")
    _raises(tmp_path / "far.xyz", "1 points have coordinates beyond 1e\\+09 m")


# -- map_server descriptions written by PyYAML's own writer ----------------------------------------
def _description(**extra) -> dict:
    return {"image": "map.pgm", "resolution": 0.5, "origin": [-1.0, 2.0, 0.0], "negate": 0,
            "occupied_thresh": 0.65, "free_thresh": 0.196, **extra}


@pytest.mark.parametrize("flow", [False, True], ids=["block", "flow"])
def test_ros_map_described_in_any_yaml_style(tmp_path, flow):
    import yaml

    pix = np.array([[0, 254, 205], [254, 254, 0]])
    (tmp_path / "ref").mkdir()
    reference = load_obstacles(write_rosmap(tmp_path / "ref", pix))  # the hand-written one
    path = write_rosmap(tmp_path, pix)
    text = yaml.safe_dump(_description(mode="trinary"), default_flow_style=flow)
    # block style writes origin as a block list ("origin:\n- -1.0\n..."), flow style the
    # whole description as one mapping ("{free_thresh: 0.196, image: map.pgm, ...}")
    assert ("\n- -1.0" in text) != flow and text.startswith("{") == flow
    path.write_text(text)
    obst = load_obstacles(path)
    np.testing.assert_array_equal(obst.bounds, reference.bounds)
    assert sorted(map(tuple, obst.boxes)) == sorted(map(tuple, reference.boxes))
    assert sorted(map(tuple, obst.free_boxes)) == sorted(map(tuple, reference.free_boxes))


@pytest.mark.parametrize(("negate", "mode", "occupied", "free"), [
    (True, "trinary", [[-0.25, 2.25]], [[-0.75, 2.25]]),
    (False, "raw", [[0.25, 2.25]], [[-0.75, 2.25]]),
    (False, "scale", [[-0.75, 2.25]], [[-0.25, 2.25]]),
])
def test_ros_map_modes_and_negate_as_yaml_booleans(tmp_path, negate, mode, occupied, free):
    import yaml

    # 0 black, 255 white, 100 dark grey: occupancy 1, 0, 0.61 (unknown between the thresholds)
    path = write_rosmap(tmp_path, np.array([[0, 255, 100]]))
    path.write_text(yaml.safe_dump(_description(negate=negate, mode=mode)))
    obst = load_obstacles(path)
    assert obst.boxes.tolist() == occupied and obst.free_boxes.tolist() == free


def test_ros_map_integers_and_exponents_are_numbers(tmp_path):
    import yaml

    path = write_rosmap(tmp_path, np.array([[0, 254]]))
    # PyYAML reads 5e-1 as a string (YAML 1.1); map_server reads it as a number
    path.write_text(yaml.safe_dump(_description(origin=[-1, 2, 0])).replace(
        "resolution: 0.5", "resolution: 5e-1"))
    obst = load_obstacles(path)
    assert obst.resolution == 0.5 and obst.bounds.tolist() == [[-1.0, 2.0], [0.0, 2.5]]


@pytest.mark.parametrize(("text", "match"), [
    ("image: map.pgm\nresolution: [0.5\n", r"map.yaml:\d+: not valid YAML"),
    ("- image\n- map.pgm\n", "a YAML mapping"),
    ("image: map.pgm\nresolution: 0.5\norigin: {x: 1}\nnegate: 0\n", "'origin' must be"),
    ("image: !!python/object:os.system x\n", "not valid YAML"),
])
def test_bad_yaml_is_one_line(tmp_path, text, match):
    path = write_rosmap(tmp_path, np.array([[0, 254]]))
    path.write_text(text)
    with pytest.raises(MapError, match=match) as err:
        load_obstacles(path)
    assert "\n" not in str(err.value)
