"""Deterministic fuzz corpus of malformed map inputs for every reader of ``planner.io``.

``make_corpus(folder)`` writes one small valid seed file per reader and, from each seed,
malformed variants: truncations at many offsets, byte flips, header lies (counts too small,
too large, huge, negative), absurd resolutions and dimensions, NaN / inf / 1e300 coordinates,
wrong JSON types, empty files and directories in place of files.  It returns the cases; the
same folder always gets the same bytes.  Run ``python tests/fuzz/make_corpus.py OUT`` to write
the corpus and print its size per reader.
"""

from __future__ import annotations

import bz2
import gzip
import json
import random
import sys
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # tests/, when run as a script
from _suites import suite_text  # noqa: E402


@dataclass(frozen=True)
class Case:
    """One corpus input: the file, the reader family and how to load it."""

    path: Path
    reader: str
    loader: str = "obstacles"  # "obstacles", "scenarios" or "sidecar"
    format: str | None = None
    kwargs: dict = field(default_factory=dict)


PTS = np.array([[1.0, 2.0, 3.0], [-4.0, 5.5, 0.25], [7.0, -8.0, 9.0], [0.5, 0.5, 0.5]])


# -- valid seeds -----------------------------------------------------------------------------------
def ply_binary() -> bytes:
    head = (f"ply\nformat binary_little_endian 1.0\nelement vertex {len(PTS)}\n"
            "property float x\nproperty float y\nproperty float z\nend_header\n")
    return head.encode() + PTS.astype("<f4").tobytes()


def ply_ascii() -> bytes:
    rows = "".join(f"{x} {y} {z}\n" for x, y, z in PTS)
    return (f"ply\nformat ascii 1.0\nelement vertex {len(PTS)}\nproperty double x\n"
            f"property double y\nproperty double z\nend_header\n{rows}").encode()


def pcd(kind: str, pts: np.ndarray = PTS) -> bytes:
    head = ("# .PCD v0.7\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n"
            f"WIDTH {len(pts)}\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS {len(pts)}\n"
            f"DATA {kind}\n").encode()
    if kind == "ascii":
        return head + "".join(f"{x} {y} {z}\n" for x, y, z in pts).encode()
    with np.errstate(over="ignore"):  # 1e300 is meant to become inf in float32
        f4 = pts.astype("<f4")
    if kind == "binary":
        return head + f4.tobytes()
    raw = np.ascontiguousarray(f4.T).tobytes()  # column-major fields
    lzf = b"".join(bytes([len(raw[k:k + 32]) - 1]) + raw[k:k + 32]
                   for k in range(0, len(raw), 32))  # literal runs only: valid LZF
    return head + np.array([len(lzf), len(raw)], "<u4").tobytes() + lzf


def xyz_text(pts: np.ndarray = PTS) -> bytes:
    return "".join(f"{x!r} {y!r} {z!r}\n" for x, y, z in pts.tolist()).encode()


def npy(arr: np.ndarray) -> bytes:
    import io

    buf = io.BytesIO()
    np.save(buf, arr)
    return buf.getvalue()


def octomap(res: str = "0.1") -> bytes:
    # A chain of 15 inner nodes down to depth 15, whose last holds an occupied and a free leaf.
    stream = b"\x03\x00" * 15 + b"\x06\x00"
    return (b"# Octomap OcTree binary file\nid OcTree\nsize 18\nres " + res.encode()
            + b"\ndata\n" + stream)


MAP3D = b"voxel 4 4 4\n0 0 0\n1 2 3\n3 3 3\n"
SCEN = b"version 1\nm.3dmap\n0 0 1 3 3 2 3.5 1.0\n1 1 1 2 2 2 1.7 1.0\n"
YAML = b"image: map.pgm\nresolution: 0.5\norigin: [0.0, 0.0, 0.0]\nnegate: 0\n" \
       b"occupied_thresh: 0.65\nfree_thresh: 0.196\n"
PGM = b"P5\n3 2\n255\n" + bytes([0, 254, 205, 254, 0, 254])
SIDECAR = {"bounds": [[0, 0, 0], [10, 10, 3]], "robot_radius": 0.3, "cell_volume": 0.008,
           "queries": [{"start": [1, 1, 1], "goal": [9, 9, 1]}]}


# -- mutations -------------------------------------------------------------------------------------
def truncations(data: bytes, n: int) -> list[bytes]:
    """``n`` prefixes of ``data`` at spread offsets (never the whole file)."""
    cuts = sorted({0, 1, len(data) - 1, *np.linspace(2, len(data) - 2, n).astype(int)})
    return [data[:c] for c in cuts if 0 <= c < len(data)][:n + 3]


def flips(data: bytes, n: int, seed: int, start: int = 0) -> list[bytes]:
    """``n`` variants with 1-3 random bytes replaced at or after ``start``."""
    rng = random.Random(seed)
    out = []
    for _ in range(n):
        raw = bytearray(data)
        for _ in range(rng.randint(1, 3)):
            raw[rng.randrange(start, len(raw))] = rng.randrange(256)
        out.append(bytes(raw))
    return out


def replaced(data: bytes, old: bytes, news: list[bytes]) -> list[bytes]:
    assert old in data, old
    return [data.replace(old, new, 1) for new in news]


# -- the corpus ------------------------------------------------------------------------------------
def make_corpus(folder: str | Path) -> list[Case]:
    """Write every case under ``folder`` (created) and return them in a fixed order."""
    root = Path(folder)
    root.mkdir(parents=True, exist_ok=True)
    cases: list[Case] = []

    def add(reader: str, name: str, data: bytes, **kw) -> None:
        path = root / f"{len(cases):04d}_{name}"
        path.write_bytes(data)
        cases.append(Case(path, reader, **kw))

    def add_all(reader: str, ext: str, variants: list[bytes], **kw) -> None:
        for v in variants:
            add(reader, f"{reader}{ext}", v, **kw)

    huge = [b"1000000000000000000", b"-5", b"99999999999999999999999999", b"0", b"2"]
    # PLY
    for seed, tag in ((ply_binary(), "bin"), (ply_ascii(), "asc")):
        head = seed.index(b"end_header\n") + len(b"end_header\n")
        add_all("ply", ".ply", truncations(seed, 8) + flips(seed, 8, len(seed), head)
                + replaced(seed, b"element vertex 4", [b"element vertex " + h for h in huge])
                + replaced(seed, b"format", [b"formot"]) + [seed + seed[head:]])
        if tag == "asc":
            add_all("ply", ".ply", replaced(seed, b"1.0 2.0 3.0", [b"nan 2 3", b"inf 1 1",
                                                                  b"1e300 1e300 1e300",
                                                                  b"1 2", b"a b c"]))
    # PCD
    for kind in ("ascii", "binary", "binary_compressed"):
        seed = pcd(kind)
        head = seed.index(b"DATA") + len(f"DATA {kind}\n")
        add_all("pcd", ".pcd", truncations(seed, 6) + flips(seed, 6, head, head)
                + replaced(seed, b"POINTS 4", [b"POINTS " + h for h in huge])
                + replaced(seed, b"SIZE 4 4 4", [b"SIZE 4 4 3", b"SIZE 4 4"])
                + [seed + seed[head:]])
    add_all("pcd", ".pcd", [pcd("binary", np.full((4, 3), np.nan)),
                            pcd("binary", np.array([[np.inf, 0, 0], [1e300, 1, 1]] * 2)),
                            b"# .PCD\n" * 100 + pcd("binary")])
    # XYZ text, compressed
    text = xyz_text()
    add_all("xyz", ".xyz", [b"", b"# nothing\n", b"1 2\n", b"nan nan nan\n", b"inf 0 0\n",
                            b"1e300 1e300 1e300\n1 2 3\n", b"\xef\xbb\xbf" + text,
                            b"\xff\xfe garbage", b"1,2,3\n4,,6\n", text.replace(b"\n", b"\r")]
            + flips(text, 4, 7))
    gz, bz = gzip.compress(text, mtime=0), bz2.compress(text)
    add_all("xyz", ".xyz.gz", truncations(gz, 5) + flips(gz, 4, 11)
            + [gzip.compress(b"0 0 0\n" * 20000, mtime=0)])
    add_all("xyz", ".xyz.bz2", truncations(bz, 4) + flips(bz, 3, 13))
    # npy
    seed = npy(PTS)
    add_all("npy", ".npy", truncations(seed, 6) + flips(seed, 6, 17)
            + [npy(np.zeros((3, 2))), npy(np.array([["a", "b", "c"]])),
               npy(np.full((2, 3), np.nan)), npy(np.array([[1e300, 0, 0], [np.inf, 1, 1]])),
               npy(np.zeros((0, 3))), npy(np.array([[1, 2, 3]], dtype=np.int64)),
               seed.replace(b"(4, 3)", b"(400000000000, 3)")])
    # OctoMap
    seed = octomap()
    head = seed.index(b"data\n") + 5
    add_all("bt", ".bt", truncations(seed, 8) + flips(seed, 8, 19, head)
            + [octomap(r) for r in ("1e300", "1e-300", "nan", "-1", "0", "x")]
            + replaced(seed, b"size 18", [b"size " + h for h in huge])
            + replaced(seed, b"id OcTree", [b"id ColorOcTree"])
            + [seed.replace(b"\x03\x00" * 15 + b"\x06\x00", b"\x03\x00" * 17)])
    # MovingAI
    add_all("3dmap", ".3dmap", truncations(MAP3D, 5)
            + replaced(MAP3D, b"voxel 4 4 4", [b"voxel 99999999999999999999 4 4",
                                               b"voxel 0 4 4", b"voxel -1 4 4", b"voxel 4 4"])
            + replaced(MAP3D, b"1 2 3", [b"1 2 9", b"1 2", b"1.5 2 3", b"nan 2 3",
                                         b"1e300 2 3"]))
    for v in truncations(SCEN, 4) + replaced(SCEN, b"0 0 1 3 3 2", [b"1e300 0 1 3 3 2",
                                                                    b"nan 0 1 3 3 2"]):
        add("3dscen", "s.3dscen", v, loader="scenarios")
    # Pose lists (scans are the valid seed cloud)
    scan = root / "scan.xyz"
    scan.write_bytes(text)
    for line in [b"scan.xyz 1 2 3\n", b"scan.xyz 0 0 0 0 0 0 0\n", b"scan.xyz 0 0 0 nan 0 0 1\n",
                 b"none.xyz 0 0 0 0 0 0 1\n", b"scan.xyz " + b"1 " * 16 + b"\n", b"",
                 b"scan.xyz 1e300 0 0 0 0 0 1\n"]:
        add("poses", "poses.txt", line, format="poses")
    # ROS maps: the YAML and the image it names
    for i, v in enumerate(truncations(PGM, 5) + flips(PGM, 3, 23, 11)
                          + [b"P5\n3 2\n70000\n" + PGM[11:], b"P2\n3 2\n255\n1 2\n"]):
        (root / f"map{i}.pgm").write_bytes(v)
        add("rosmap", "map.yaml", YAML.replace(b"map.pgm", f"map{i}.pgm".encode()))
    (root / "good.pgm").write_bytes(PGM)
    good = YAML.replace(b"map.pgm", b"good.pgm")
    add_all("rosmap", ".yaml", truncations(good, 5)
            + replaced(good, b"resolution: 0.5", [b"resolution: x", b"resolution: 1e300",
                                                  b"resolution: -1"])
            + replaced(good, b"origin: [0.0, 0.0, 0.0]", [b"origin: [0", b"origin: 5",
                                                          b"origin: [1, nan, 0]"]))
    # Sidecars: wrong types, missing keys
    for change in ({"robot_radius": "x"}, {"bounds": "abc"}, {"bounds": [[0, 0, 0]]},
                   {"cell_volume": -1}, {"queries": [{"start": [1, 1, 1]}]},
                   {"queries": {"a": 1}}, {"queries": [[1, 2, 3]]}, {"robot_radius": None},
                   {"bounds": [[0, 0, 0], [1, 1, 1e400]]}, {"file": 5}):
        add("sidecar", "m.json", json.dumps({**SIDECAR, **change}).encode(), loader="sidecar")
    for raw in (b"[1, 2]", b"{", b"", b"null", b'{"bounds": [[0,0,0],[1,1,1]]}'):
        add("sidecar", "m.json", raw, loader="sidecar", kwargs={"required": ("queries",)})
    # Empty files and directories where files are expected, every extension
    for ext in (".ply", ".pcd", ".xyz", ".npy", ".bt", ".3dmap", ".yaml", ".las", ".e57",
                ".bag"):
        add("empty", f"empty{ext}", b"")
        d = root / f"{len(cases):04d}_dir{ext}"
        d.mkdir()
        cases.append(Case(d, "directory"))
    cases += _robot_cases(root, len(cases))
    return cases


def _robot_cases(root: Path, start: int) -> list[Case]:
    """Corrupt LAS / LAZ / E57 / bag files, from seeds written by each library (if present)."""
    out: list[Case] = []
    seeds: list[tuple[str, str, bytes]] = []
    try:
        import laspy

        for ext in (".las", ".laz"):
            if ext == ".laz":
                import lazrs  # noqa: F401
            las = laspy.LasData(laspy.LasHeader(point_format=0, version="1.2"))
            las.x, las.y, las.z = PTS[:, 0], PTS[:, 1], PTS[:, 2]
            tmp = root / f"seed{ext}"
            las.write(str(tmp))
            seeds.append(("las", ext, tmp.read_bytes()))
    except ImportError:
        pass
    try:
        import pye57

        tmp = root / "seed.e57"
        e57 = pye57.E57(str(tmp), mode="w")
        e57.write_scan_raw({"cartesianX": PTS[:, 0], "cartesianY": PTS[:, 1],
                            "cartesianZ": PTS[:, 2]})
        e57.close()
        seeds.append(("e57", ".e57", tmp.read_bytes()))
    except ImportError:
        pass
    try:
        seeds.append(("bag", ".bag", _bag_seed(root / "seed.bag")))
    except ImportError:
        pass
    for reader, ext, seed in seeds:
        lies = []
        if reader == "las":  # a VLR count and a point count the file cannot hold
            lies = [seed[:100] + b"\xff\xff\xff\x00" + seed[104:],
                     seed[:107] + b"\xff\xff\xff\x7f" + seed[111:]]
        for i, v in enumerate(truncations(seed, 6) + flips(seed, 6, len(seed), 0) + lies):
            path = root / f"{start + len(out):04d}_{reader}{i}{ext}"
            path.write_bytes(v)
            out.append(Case(path, reader))
    for i, v in enumerate((b"#ROSBAG V2.0\n" + b"\x00" * 40, b"#ROSBAG V2.0\n",
                           b"#ROSBAG V1.2\n" + bytes(range(256)))):
        path = root / f"{start + len(out):04d}_bag{i}.bag"
        path.write_bytes(v)
        out.append(Case(path, "bag"))
    return out


def _bag_seed(path: Path) -> bytes:
    """A ROS 1 bag with one PointCloud2 of PTS (no tf: the cloud's frame is the fixed one)."""
    from rosbags.rosbag1 import Writer
    from rosbags.typesys import Stores, get_typestore

    ts = get_typestore(Stores.ROS1_NOETIC)
    T = ts.types
    field = T["sensor_msgs/msg/PointField"]
    msg = T["sensor_msgs/msg/PointCloud2"](
        header=T["std_msgs/msg/Header"](seq=0, stamp=T["builtin_interfaces/msg/Time"](
            sec=1, nanosec=0), frame_id="lidar"),
        height=1, width=len(PTS), is_bigendian=False, point_step=12, row_step=12 * len(PTS),
        fields=[field(name=c, offset=4 * i, datatype=7, count=1) for i, c in enumerate("xyz")],
        data=np.frombuffer(PTS.astype("<f4").tobytes(), dtype=np.uint8), is_dense=True)
    if path.exists():
        path.unlink()
    with Writer(path) as writer:
        conn = writer.add_connection("/points", msg.__msgtype__, typestore=ts)
        writer.write(conn, 1_000_000_000, ts.serialize_ros1(msg, msg.__msgtype__))
    return path.read_bytes()


# -- benchmark suites and saved voxel lists -------------------------------------------------------
SUITE = suite_text("fuzz")


def suite_variants() -> list[str]:
    """Suites with wrong types, unknown keys and absurd values, each one edit of SUITE."""
    edits = [("queries = 1", v) for v in ('queries = "x"', "queries = -5", "queries = 0",
                                          "queries = 1e300", "queries = [1]")]
    edits += [("seed = 1", v) for v in ('seed = "a"', "seed = -1", "seed = 1.5",
                                        "seed = 9223372036854775807")]
    edits += [("min_distance = 0.3", v) for v in ('min_distance = "far"', "min_distance = nan",
                                                  "min_distance = -1", "min_distance = inf")]
    edits += [('lattices = ["cubic"]', v) for v in ('lattices = "fcc"', "lattices = [1]",
                                                     "lattices = []", 'lattices = ["fcc2"]')]
    edits += [('neighbors = ["face"]', v) for v in ('neighbors = ["face+1000"]',
                                                     'neighbors = ["edge"]', "neighbors = 5")]
    edits += [('methods = ["astar"]', v) for v in ('methods = ["astra"]', 'methods = "astar"',
                                                   "methods = [[]]")]
    edits += [("cell_volumes = [0.5]", v) for v in ("cell_volumes = [0]", 'cell_volumes = ["a"]',
                                                    "cell_volumes = [1e-12]",
                                                    "cell_volumes = [nan]", "cell_volumes = 0.5",
                                                    "cell_volumes = [inf]")]
    edits += [("radii = [0.1]", v) for v in ("radii = [-1]", 'radii = ["x"]', "radii = [1e300]",
                                             "radii = [nan]", "radii = [1e4]")]
    edits += [('path = "suite_map.xyz"', v) for v in ('path = "missing.xyz"', "path = 5",
                                                       'path = "suite_bad.xyz"',
                                                       'path = "/proc"')]
    edits += [('name = "fuzz"', v) for v in ("querys = 4", "name = [1]", 'kind = "other"',
                                             "kind = 5", "maps = 5", "[paper]\nbad = 1")]
    edits += [("[[maps]]", v) for v in ("[ompl]\nplanners = [\"nope\"]\n[[maps]]",
                                        "[ompl]\nplanners = [\"rrtconnect\"]\ntime = -1\n"
                                        "[[maps]]",
                                        "[ompl]\nplanners = [\"rrtconnect\"]\nseeds = [-5]\n"
                                        "[[maps]]",
                                        "[ompl]\nlattice = \"bogus\"\n[[maps]]")]
    edits += [("radii = [0.1]", "radii = [0.1]\nradious = [0.2]"),
              ("radii = [0.1]", "radii = [0.1]\nqueries = \"all\""),
              ("radii = [0.1]", "radii = [0.1]\nscenarios = \"missing.3dscen\"")]
    out = [SUITE.replace(old, new, 1) for old, new in edits]
    assert all(v != SUITE for v in out)
    raw = SUITE.encode()
    out += [t.decode("latin-1") for t in truncations(raw, 6)[1:]]
    out += [t.decode("latin-1") for t in flips(raw, 6, 29)]
    out += ["", "[[maps]]\n", "maps = []\n", '= "x"\n', "\x00" * 10]
    return out


def voxel_list_seed(path: Path) -> bytes:
    """A valid saved voxel list (OccupiedVoxelList.save) of PTS on FCC."""
    from planner import Lattice, OccupiedVoxelList

    OccupiedVoxelList.from_points(PTS, Lattice.named("fcc", 0.5)).save(path)
    return path.read_bytes()


def npz(**fields) -> bytes:
    import io

    buf = io.BytesIO()
    np.savez(buf, **fields)
    return buf.getvalue()


def voxel_list_variants(seed: bytes) -> list[bytes]:
    """Corrupt and lying saved voxel lists."""
    import io

    with np.load(io.BytesIO(seed), allow_pickle=False) as z:
        good = {k: z[k] for k in z.files}
    lies = [dict(good, version=np.array(99)), dict(good, format=np.array("other")),
            dict(good, dim=np.array(7)), dict(good, keys=good["keys"][::-1].copy()),
            dict(good, keys=good["keys"].astype(np.float64)),
            dict(good, generator=np.full((3, 3), np.nan)),
            dict(good, generator=np.zeros((3, 3))), dict(good, generator=np.eye(2)),
            dict(good, generator=np.diag([1.0, 1.0, 1e-300])),
            dict(good, lattice=np.array("nonsense")), dict(good, version=np.array("x")),
            {k: v for k, v in good.items() if k != "keys"},
            dict(good, keys=np.array([[1, 2]], dtype=np.int64))]
    return (truncations(seed, 8) + flips(seed, 8, 31) + [npz(**f) for f in lies]
            + [npz(**dict(good, keys=np.array([None], dtype=object))), b"PK\x03\x04",
               ply_binary(), b""])


def make_entry_corpus(folder: str | Path) -> list[Case]:
    """Suites (``planner bench``) and saved voxel lists (``OccupiedVoxelList.load``) under
    ``folder``: reader ``suite`` (loader ``suite``) and ``voxels`` (loader ``voxels``)."""
    root = Path(folder)
    root.mkdir(parents=True, exist_ok=True)
    (root / "suite_map.xyz").write_bytes(xyz_text())
    (root / "suite_bad.xyz").write_bytes(b"nan nan nan\n")
    cases = []
    for i, text in enumerate(suite_variants()):
        path = root / f"s{i:03d}_suite.toml"
        path.write_bytes(text.encode("latin-1"))
        cases.append(Case(path, "suite", loader="suite"))
    for i, data in enumerate(voxel_list_variants(voxel_list_seed(root / "seed_voxels.npz"))):
        path = root / f"v{i:03d}_voxels.npz"
        path.write_bytes(data)
        cases.append(Case(path, "voxels", loader="voxels"))
    return cases


if __name__ == "__main__":
    from collections import Counter

    out = sys.argv[1] if len(sys.argv) > 1 else "fuzz_corpus"
    corpus = make_corpus(out) + make_entry_corpus(Path(out) / "entry")
    for reader, n in sorted(Counter(c.reader for c in corpus).items()):
        print(f"{reader:10s} {n}")
    print(f"{'total':10s} {len(corpus)}")
