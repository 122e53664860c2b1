"""Seeded fault classes of the command line: user data, suites, resume files, saved-world
trust, readers' budgets and outputs (``fault_runs(corpus, root, rng)``).

Every run is a :class:`cli_cases.Run`; ``keep`` names a folder whose contents (names and
bytes) must be exactly as they were before the run, so a run that deletes, overwrites or
adds anything the user did not name is a problem even when it exits 2 with one line.

Classes (the category's first part):

* ``folders``: ``bench --out`` on a user's folder (with ``worlds/``, files, a file as
  ``--out``), with ``--force``, ``--resume`` or ``--report-only``; suite names that are paths.
* ``suites``: one schema violation each (types, ranges, lengths, NUL, nesting depth).
* ``resume``: a run folder whose ``results.jsonl`` or ``queries.json`` holds a bad line or
  record, or whose suite was edited since.
* ``trust``: saved worlds edited and re-digested, beside their source map.
* ``budget2``: map_server YAML alias bombs, map images over the memory budget, data after a
  PGM / PNG, bad ``--generator`` files, bag chunks inflating past the decompression budget.
* ``outputs2``: a path's sidecar the user did not name, a later output that fails, names at
  the file system's length limit.
"""

from __future__ import annotations

import hashlib
import io
import json
import random
import zlib
from pathlib import Path

import numpy as np
from _suites import result_row, suite_text  # tests/_suites.py (tests/ is on the path)
from cli_cases import OFFICE_QUERY, Run

SUITE = suite_text("faults")
ROW = result_row()


def snapshot(folder: Path) -> str:
    """A digest of every name and byte under ``folder`` (symlinks not followed)."""
    h = hashlib.sha256()
    if folder.exists():
        for p in sorted(folder.rglob("*")):
            h.update(str(p.relative_to(folder)).encode() + b"\0")
            if p.is_file() and not p.is_symlink():
                h.update(p.read_bytes())
    return h.hexdigest()


def _kept(folder: Path) -> tuple[str, str]:
    return (str(folder), snapshot(folder))


def folder_runs(corpus, root: Path) -> list[Run]:
    """``bench`` into folders it must not touch."""
    root.mkdir(parents=True, exist_ok=True)
    (root / "suite_map.xyz").write_bytes(corpus.xyz_text())
    suite = root / "faults.toml"
    suite.write_text(SUITE)
    runs = []
    layouts = {
        "worlds": {"worlds/scan.npz": b"user world", "worlds/notes.txt": b"mine"},
        "results": {"results.jsonl": b'{"mine": 1}\n', "worlds/a.npz": b"x"},
        "plain": {"thesis.tex": b"\\documentclass{article}"},
        "hidden": {".git/HEAD": b"ref: refs/heads/main\n"},
        "marker_bad": {".planner-bench.json": b"[1, 2]", "worlds/x.npz": b"x"},
        "marker_str": {".planner-bench.json": b'{"digest": 5}', "data.csv": b"1,2\n"},
        "nested": {"a/b/c/worlds/w.npz": b"deep"},
        "lockonly_and_worlds": {".lock": b"123", "worlds/keep.bin": b"k"},
    }
    for name, files in layouts.items():
        for flags in ((), ("--force",), ("--resume",), ("--report-only",),
                      ("--force", "--resume")):
            d = root / f"user_{name}_{len(runs)}"
            for rel, data in files.items():
                (d / rel).parent.mkdir(parents=True, exist_ok=True)
                (d / rel).write_bytes(data)
            runs.append(Run("folders:user", ("bench", str(suite), "--out", str(d),
                                             "--no-progress", *flags), True, keep=_kept(d)))
    files = root / "files"
    files.mkdir()
    f = files / "a_file.txt"
    f.write_text("not a folder")
    runs.append(Run("folders:file", ("bench", str(suite), "--out", str(f), "--no-progress"),
                    True, keep=_kept(files)))
    names = root / "names"
    names.mkdir()
    suites = []
    for k, name in enumerate(["../..", "../escape", "/tmp/abs", "a/b", "..", ".", "",
                              r"a\u0000b", "x" * 300, r"\n", ".hidden", "~", "a/../../b",
                              r"C:\\x", "-rf", r"a\tb", " lead"]):  # TOML escapes
        s = names / f"named{k}.toml"
        s.write_text(SUITE.replace('"faults"', f'"{name}"'))
        suites.append(s)
    kept = _kept(names)  # every suite file written first
    for s in suites:  # the default folder (results/<name>) and one given: nothing escapes
        runs.append(Run("folders:name", ("bench", str(s), "--no-progress"), True,
                        name=s.name, keep=kept))
        runs.append(Run("folders:name", ("bench", str(s), "--out", str(names / "o"),
                                         "--no-progress"), True, name=s.name, keep=kept))
    return runs


def _suite_edits() -> list[tuple[str, str]]:
    """(old, new) edits of SUITE, each breaking one rule of the schema."""
    e = []
    for v in ('"1"', "true", "1.0", "-1", "0", "1000001", "[1]", "{a=1}", "1e3"):
        e.append(("queries = 1", f"queries = {v}"))
    for v in ('"1"', "true", "-1", "4294967296", "9223372036854775807", "1.5", "[]"):
        e.append(("seed = 1", f"seed = {v}"))
    for v in ("0", "1", "2.0", "-0.5", "1e300", "nan", "inf", "true", '"0.3"', "[0.3]"):
        e.append(("min_distance = 0.3", f"min_distance = {v}"))
    for key in ("lattices", "neighbors"):
        for v in ("[]", '"cubic"', "[1]", "[true]", "[[\"cubic\"]]", "{a=1}",
                  '["' + "c" * 5000 + '"]', '["cub\\u0000ic"]'):
            old = f'{key} = ["{"cubic" if key == "lattices" else "face"}"]'
            e.append((old, f"{key} = {v}"))
    for v in ("[]", '"astar"', "[1]", "[[]]", '["astar", 5]'):
        e.append(('methods = ["astar"]', f"methods = {v}"))
    for v in ("[true]", "[false]", '["0.5"]', "[0]", "[-0.5]", "[nan]", "[inf]", "[]",
              "0.5", "[[0.5]]", "[{a=1}]"):
        e.append(("cell_volumes = [0.5]", f"cell_volumes = {v}"))
    for v in ("[true]", '["0.1"]', "[-0.1]", "[nan]", "[inf]", "[]", "0.1", "[[0.1]]"):
        e.append(("radii = [0.1]", f"radii = {v}"))
    for v in ("5", "true", '""', '"suite\\u0000map.xyz"', '"' + "p" * 5000 + '"', "[]"):
        e.append(('path = "suite_map.xyz"', f"path = {v}"))
    for v in ("5", "true", '"a/b"', '"../../x"', '"/abs"', '"n\\u0000ul"', '"' + "n" * 101 + '"',
              '".."', '"."', "[]"):
        e.append(('name = "faults"', f"name = {v}"))
    tail = [
        'rotation = "yaw"\nrotations = 0', 'rotation = "yaw"\nrotations = true',
        'rotation = 5', 'rotation = "roll"', 'kind = "paper"\n[paper]\nseed = -1',
        'kind = "paper"\n[paper]\nseed = 9223372036854775807',
        'kind = "paper"\n[paper]\nsamples = 1000000000000',
        'kind = "paper"\n[paper]\nsamples = 5', 'kind = "paper"\n[paper]\nvolumes = []',
        'kind = "paper"\n[paper]\nvolumes = [true]', 'kind = "paper"\n[paper]\nquick = 1',
        'kind = "paper"\n[paper]\nrotations = 0', 'kind = "paper"\n[paper]\nextra = 1',
        'methods = []', '[ompl]\nplanners = "rrt"', '[ompl]\nplanners = [1]',
        '[ompl]\nplanners = ["rrtconnect"]\ntime = 0',
        '[ompl]\nplanners = ["rrtconnect"]\ntime = true',
        '[ompl]\nplanners = ["rrtconnect"]\nseeds = []',
        '[ompl]\nplanners = ["rrtconnect"]\nseeds = [4294967296]',
        '[ompl]\nplanners = ["rrtconnect"]\nlattice = 5',
        '[explore]\nsensor_range = 4.0', 'x = ' + '[' * 100 + ']' * 100,
        'x = ' + '{a=' * 50 + '1' + '}' * 50, 'x = ' + '[' * 3000 + ']' * 3000,
        'x = ' + '{a=' * 3000 + '1' + '}' * 3000,
    ]
    e += [('min_distance = 0.3', 'min_distance = 0.3\n' + t) for t in tail]
    e += [("radii = [0.1]", "radii = [0.1]\ncell_volume = 0.5"),
          ("radii = [0.1]", "radii = [0.1]\nradius = 0.1"),
          ("radii = [0.1]", "radii = [0.1]\nscenarios = 5"),
          ("radii = [0.1]", "radii = [0.1]\nqueries = 0"),
          ("radii = [0.1]", "radii = [0.1]\ndeep = [[[[[1]]]]]"),
          ("radii = [0.1]", "radii = [" + ", ".join(["0.1"] * 10_001) + "]")]
    e += [("cell_volumes = [0.5]\nradii = [0.1]", "radius = 0.1")]  # no cell volume
    return e


def suite_runs(root: Path) -> list[Run]:
    """One schema violation per suite: exit 2 naming the suite file, nothing written."""
    root.mkdir(parents=True, exist_ok=True)
    runs = []
    for k, (old, new) in enumerate(_suite_edits()):
        assert old in SUITE, old
        s = root / f"schema{k:03d}.toml"
        s.write_text(SUITE.replace(old, new, 1))
        out = root / f"out{k:03d}"
        runs.append(Run("suites:schema", ("bench", str(s), "--out", str(out),
                                          "--no-progress"), True, str(out), name=s.name))
    big = root / "big.toml"
    big.write_text(SUITE + "#" * (1 << 20) + "\n")
    runs.append(Run("suites:schema", ("bench", str(big), "--out", str(root / "obig"),
                                      "--no-progress"), True, str(root / "obig"), "big.toml"))
    return runs


def resume_runs(root: Path) -> list[Run]:
    """Run folders (marker, rows, saved queries) with one bad line or record each."""
    from planner.bench.run_folder import write_marker
    from planner.bench.suite import load_suite

    root.mkdir(parents=True, exist_ok=True)
    (root / "suite_map.xyz").write_bytes(b"0 0 0\n1 1 1\n2 0 1\n")
    suite = root / "faults.toml"
    suite.write_text(SUITE)
    loaded = load_suite(str(suite))
    good = json.dumps(ROW)
    bad_rows = ["{}", "[1, 2]", "null", "42", '"x"', "true", "{not json", "[" * 3000,
                "[" * 3000 + "]" * 3000]
    for key, vals in (("length", ['"1.0"', "[1]", "{}", "true"]),
                      ("map", ["5", "null", "[]"]), ("query", ['"0"', "1.5", "true", "null"]),
                      ("cell_volume", ['"0.5"', "null", "true"]),
                      ("lattice", ["1", "null"]), ("seed", ["0.5", '"0"']),
                      ("found", ['"yes"', "1"]), ("rotation", ['"0"', "0.5"]),
                      ("seconds", ['"fast"']), ("clearance", ["[0.2]"])):
        for v in vals:
            bad_rows.append(json.dumps({**ROW, key: "@"}).replace('"@"', v))
    bad_rows += [json.dumps({k: v for k, v in ROW.items() if k != key})
                 for key in ("map", "lattice", "neighbors", "method", "seed", "query",
                             "cell_volume", "radius")]
    bad_queries = ["[1]", "42", "null", '{"g": 1}', '{"g": [1, 2]}', '{"g": null}',
                   '{"g": {"queries": [1]}}', '{"g": {"queries": 5}}',
                   '{"g": {"queries": [{"id": "0", "start": [0, 0, 0], "goal": [1, 1, 1]}]}}',
                   '{"g": {"queries": [{"id": 0, "start": [0, 0], "goal": "x"}]}}',
                   '{"g": {"queries": [{"id": 0, "start": [0, 0, 1e999], "goal": [1, 1, 1]}]}}',
                   '{"g": {"queries": [], "wanted": "1"}}', '{"g": {"dropped": []}}',
                   '{"g": {"quaternion_xyzw": [0, 0, 0]}}',
                   '{"g": {"queries": [{"id": 0, "start": [0, 0, 0], "goal": [1, 1, 1], '
                   '"optimal_cost": "x"}]}}']
    runs = []
    k = 0

    def folder(lines: list[str], queries: str | None = None) -> Path:
        nonlocal k
        d = root / f"run{k:03d}"
        k += 1
        d.mkdir()
        write_marker(d, loaded)
        (d / "results.jsonl").write_text("".join(x + "\n" for x in lines))
        if queries is not None:
            (d / "queries.json").write_text(queries)
        return d

    for bad in bad_rows:
        for at in (0, 2):  # first line, or after two good rows
            lines = [good, good.replace('"query": 0', '"query": 1')][:at] + [bad]
            for flag in ("--resume", "--report-only"):
                d = folder(lines)
                runs.append(Run("resume:rows", ("bench", str(suite), "--out", str(d),
                                                "--no-progress", flag), True,
                                name="results.jsonl", keep=_kept(d)))
    for q in bad_queries:
        d = folder([good], q)
        runs.append(Run("resume:queries", ("bench", str(suite), "--out", str(d),
                                           "--no-progress", "--resume"), True,
                        name="queries.json", keep=_kept(d)))
    edited = root / "edited.toml"
    for k2, (old, new) in enumerate([("queries = 1", "queries = 2"), ("seed = 1", "seed = 2"),
                                     ('["cubic"]', '["fcc"]'), ("[0.1]", "[0.2]"),
                                     ("min_distance = 0.3", "min_distance = 0.4")]):
        e = root / f"edited{k2}.toml"
        e.write_text(SUITE.replace(old, new, 1))
        for flag in ("--resume", "--report-only"):
            d = folder([good])
            runs.append(Run("resume:edited", ("bench", str(e), "--out", str(d),
                                              "--no-progress", flag), True, keep=_kept(d)))
    assert not edited.exists()
    return runs


def _tampered(world: Path, rng: random.Random, edit: str) -> bytes:
    from planner.world.check import digest

    with np.load(world) as z:
        d = {key: z[key] for key in z.files}
    bits = np.frombuffer(zlib.decompress(d["blocked"].tobytes()), np.uint8).copy()
    on = np.flatnonzero(bits)
    if edit == "clear":
        bits[:] = 0
    elif edit.startswith("free"):
        for i in rng.sample(list(on), min(len(on), int(edit[4:]))):
            bits[i] &= bits[i] - 1
    elif edit.startswith("radius"):
        d["radius"] = np.array(float(edit[6:]))
    d["blocked"] = np.frombuffer(zlib.compress(bits), np.uint8)
    d["digest"] = np.array(digest(d))
    buf = io.BytesIO()
    np.savez(buf, **d)
    return buf.getvalue()


def trust_runs(corpus, root: Path, rng: random.Random) -> list[Run]:
    """Saved worlds edited by someone who read the format, re-digested, beside their
    source: refused (by default and with ``--check-source``)."""
    import planner
    from planner.world.file import save_world

    root.mkdir(parents=True, exist_ok=True)
    cloud = root / "trust.xyz"
    g = np.stack(np.meshgrid(np.arange(6.0), np.arange(6.0), [0.0, 3.0]), -1).reshape(-1, 3)
    cloud.write_bytes(corpus.xyz_text(g))
    seed = root / "trust_seed.npz"
    save_world(planner.build_world(str(cloud), "fcc", cell_volume=0.05, radius=0.2), seed)
    runs = []
    edits = ["clear", "free1", "free5", "free50", "radius0", "radius0.5", "radius1.5",
             "radius0.19", "radius0.21"]
    for edit in edits:
        w = root / f"t_{edit}.npz"
        w.write_bytes(_tampered(seed, rng, edit))
        for cmd, extra in (("plan", ()), ("plan", ("--check-source",)),
                           ("compare", ()), ("compare", ("--check-source",))):
            runs.append(Run("trust:edited", (cmd, str(w), "--start", "0.5,0.5,1.5", "--goal",
                                             "4.5,4.5,1.5", *extra), True, name=w.name))
    return runs


def _yaml(image: str, head: str = "") -> str:
    return (head + f"image: {image}\nresolution: 0.05\norigin: [0, 0, 0]\nnegate: 0\n"
            "occupied_thresh: 0.65\nfree_thresh: 0.196\n")


def budget_runs(root: Path) -> list[Run]:
    """Readers' budgets: YAML alias bombs, huge map images, trailing data, generators."""
    from PIL import Image

    root.mkdir(parents=True, exist_ok=True)
    runs = []
    q2 = ("--start", "0.05,0.05", "--goal", "0.1,0.1", "--radius", "0")
    (root / "ok.pgm").write_bytes(b"P5\n4 4\n255\n" + bytes([254] * 16))
    for k, d in ((2, 20), (4, 9), (9, 9), (10, 12), (3, 30), (2, 60)):
        head = "a0: &a0 [x, x]\n" + "".join(
            f"a{i + 1}: &a{i + 1} [{', '.join([f'*a{i}'] * k)}]\n" for i in range(d))
        y = root / f"lol_{k}_{d}.yaml"
        y.write_text(_yaml("ok.pgm", head))
        runs.append(Run("budget2:yaml", ("plan", str(y), *q2), True, name=y.name))
    y = root / "many.yaml"
    y.write_text(_yaml("ok.pgm", "".join(f"k{i}: {i}\n" for i in range(20_000))))
    runs.append(Run("budget2:yaml", ("plan", str(y), *q2), True, name=y.name))
    for w, h, budget in ((6000, 6000, "1G"), (20000, 20000, "2G"), (3000, 3000, "64M"),
                         (30000, 1, "1M")):
        p = root / f"big_{w}x{h}.pgm"
        p.write_bytes(b"P5\n%d %d\n255\n" % (w, h) + bytes(w * h))
        y = root / f"big_{w}x{h}.yaml"
        y.write_text(_yaml(p.name))
        runs.append(Run("budget2:image", ("--memory-budget", budget, "plan", str(y), *q2),
                        True, name=p.name))
    png = io.BytesIO()
    Image.fromarray(np.full((4, 4), 254, np.uint8)).save(png, format="PNG")
    for k, tail in enumerate([b"\n", b"\x00", b"garbage", b"IEND" * 3, b"\x00" * 4096]):
        for ext, data in (("pgm", (root / "ok.pgm").read_bytes()), ("png", png.getvalue())):
            p = root / f"tail{k}.{ext}"
            p.write_bytes(data + tail)
            y = root / f"tail{k}_{ext}.yaml"
            y.write_text(_yaml(p.name))
            runs.append(Run("budget2:trailing", ("plan", str(y), *q2), True, name=p.name))
    gens = {"complex": np.eye(3) + 0j, "string": np.array([["a"] * 3] * 3),
            "bool": np.eye(3, dtype=bool), "shape4": np.eye(4), "shape1": np.eye(1),
            "row": np.ones(9), "scalar": np.array(1.0), "nan": np.full((3, 3), np.nan),
            "inf": np.diag([np.inf] * 3), "big": np.eye(3) * 1e300, "small": np.eye(3) * 1e-300,
            "singular": np.zeros((3, 3)), "object": None, "shape32": np.ones((3, 2))}
    for name, g in gens.items():
        p = root / f"gen_{name}.npy"
        if g is None:
            p.write_bytes(b"\x93NUMPY\x01\x00v\x00{'descr': '|O', 'fortran_order': False, "
                          b"'shape': (3, 3), }" + b" " * 53 + b"\n" + b"\x00" * 72)
        else:
            buf = io.BytesIO()
            np.save(buf, g)
            p.write_bytes(buf.getvalue())
        runs.append(Run("budget2:generator", ("plan", "office", *OFFICE_QUERY, "--generator",
                                              str(p)), True))
    buf = io.BytesIO()
    np.save(buf, np.eye(3) * 0.2)
    ok = buf.getvalue()
    for name, data in (("huge", ok.replace(b"(3, 3)", b"(3000000000, 3)")),
                       ("trailing", ok + b"\x00" * 8), ("cut", ok[:-10]), ("empty", b"")):
        p = root / f"gen_{name}.npy"
        p.write_bytes(data)
        runs.append(Run("budget2:generator", ("plan", "office", *OFFICE_QUERY, "--generator",
                                              str(p)), True))
    return runs


def bag_runs(root: Path) -> list[Run]:
    """Bags whose compressed chunk inflates past the decompression budget (ROS 1 bz2 / lz4,
    rosbag2 zstd messages / files, mcap): one line each (none without ``rosbags``)."""
    try:
        import rosbags  # noqa: F401
        from test_bag_budget import _write  # the same bags as tests/test_bag_budget.py
    except ImportError:
        return []
    root.mkdir(parents=True, exist_ok=True)
    runs = []
    for kind in ("ros1_bz2", "ros1_lz4", "ros2_message", "ros2_file", "mcap"):
        path = root / (f"{kind}.bag" if kind.startswith("ros1") else kind)
        try:
            _write(path, kind)
        except ImportError:  # a compressor rosbags needs is missing
            continue
        for budget in ("8M", "4M"):
            runs.append(Run("budget2:bag", ("--memory-budget", budget, "plan", str(path),
                                            "--fixed-frame", "map", "--start", "0,0,0",
                                            "--goal", "1,1,1", "--radius", "0.1"), True))
    return runs


def output_runs(root: Path) -> list[Run]:
    """Outputs: sidecars the user did not name, later outputs failing, long names."""
    root.mkdir(parents=True, exist_ok=True)
    runs = []
    for k, side in enumerate([b'{"mine": 1}', b"[1, 2]", b"not json", b"", b"\xff\xfe",
                              b'{"path": [], "other": 1}']):
        d = root / f"side{k}"
        d.mkdir()
        (d / "p.json").write_bytes(side)
        runs.append(Run("outputs2:sidecar", ("plan", "office", *OFFICE_QUERY, "--out",
                                             str(d / "p.csv")), True, keep=_kept(d)))
    d = root / "sidedir"
    (d / "p.json").mkdir(parents=True)
    runs.append(Run("outputs2:sidecar", ("plan", "office", *OFFICE_QUERY, "--out",
                                         str(d / "p.csv")), True, keep=_kept(d)))
    for k, opt in enumerate(["--view", "--plot"]):
        d = root / f"later{k}"
        (d / "bag").mkdir(parents=True)
        runs.append(Run("outputs2:later", ("plan", "office", *OFFICE_QUERY, "--out",
                                           str(d / "p.csv"), opt, str(d / "v.html" if k == 0
                                                                      else d / "f.png"),
                                           "--bag", str(d / "bag")), True, keep=_kept(d)))
    for length in (244, 246, 248, 250, 251, 254):
        d = root / f"long{length}"
        d.mkdir()
        for ext in (".csv", ".json"):
            name = "p" * (length - len(ext)) + ext
            runs.append(Run("outputs2:long", ("plan", "office", *OFFICE_QUERY, "--out",
                                              str(d / name)), False, str(d / name)))
        name = "w" * (length - 4) + ".npz"
        runs.append(Run("outputs2:long", ("world", "office", "--radius", "0.2", "--out",
                                          str(d / name)), False, str(d / name)))
    d = root / "long255"
    d.mkdir()
    # a CSV of 255 bytes: its sidecar NAME.json would be 256: refused before any work
    runs.append(Run("outputs2:long255", ("plan", "office", *OFFICE_QUERY, "--out",
                                         str(d / ("p" * 251 + ".csv"))), True, keep=_kept(d)))
    return runs


def fault_runs(corpus, root: Path, rng: random.Random) -> list[Run]:
    """Every class above, in a fixed order."""
    return (folder_runs(corpus, root / "folders") + suite_runs(root / "suites")
            + resume_runs(root / "resume") + trust_runs(corpus, root / "trust", rng)
            + budget_runs(root / "budget2") + bag_runs(root / "bags")
            + output_runs(root / "outputs2"))
