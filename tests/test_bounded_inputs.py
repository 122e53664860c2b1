"""Every input bounded, every saved world verified: the classes of issue 25, one by one.

Each test runs the real command line in-process (``planner.cli.main``) and checks the exit
status, the one error line and that nothing was written.
"""

from __future__ import annotations

import bz2
import errno
import lzma
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from test_fuzz_readers import corpus  # tests/fuzz/make_corpus.py

import planner
from planner.cli import main
from planner.errors import MapError
from planner.world.check import digest
from planner.world.file import load_world, save_world

QUERY = ["--start", "1,1,1", "--goal", "7.6,7.8,0.8"]
REPO = Path(__file__).resolve().parents[1]


def _refused(capsys, argv: list[str], *words: str) -> str:
    assert main(argv) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("planner"), lines
    assert all(w in lines[0] for w in words), lines[0]
    return lines[0]


@pytest.fixture
def small_world(tmp_path) -> Path:
    cloud = tmp_path / "cloud.xyz"
    cloud.write_bytes(corpus.xyz_text())
    path = tmp_path / "cloud.npz"
    save_world(planner.build_world(str(cloud), "fcc", cell_volume=0.05, radius=0.1), path)
    return path


# -- 1. one budget gate -------------------------------------------------------------------------
def test_a_coarse_octomap_leaf_is_refused_before_it_is_split(tmp_path, capsys):
    bt = tmp_path / "d1.bt"
    bt.write_bytes(b"# Octomap OcTree binary file\nid OcTree\nsize 3\nres 0.1\ndata\n\x09\x00")
    out = tmp_path / "x.npz"
    _refused(capsys, ["world", str(bt), "--radius", "0.2", "--lattice", "cubic", "--out",
                      str(out)], "d1.bt", "sub-boxes", "--memory-budget")
    assert not out.exists()


@pytest.mark.parametrize("argv, words", [
    (["lattices", "--points", "100000000000"], ("--points", "--memory-budget")),
    (["explore", "office", *QUERY, "--resolution", "1e-6"], ("--resolution", "rays")),
    (["stats", "--samples", "100000000000"], ("--samples", "--memory-budget")),
])
def test_sizes_from_the_command_line_are_refused_before_allocating(capsys, argv, words):
    _refused(capsys, argv, *words)


def test_suite_rotations_are_whole_numbers_within_the_budget(tmp_path, capsys):
    (tmp_path / "suite_map.xyz").write_bytes(corpus.xyz_text())
    for text, words in (("rotations = 1.5", ("'rotations'", "integer")),
                        ("rotations = 1000000000", ("'rotations'", "1..1000000")),
                        ("rotations = 1000000\nqueries = 1000000", ("runs", "--memory-budget"))):
        suite = tmp_path / "s.toml"
        suite.write_text(corpus.SUITE.replace("queries = 1\n", text + "\n"))
        _refused(capsys, ["bench", str(suite), "--out", str(tmp_path / "o"), "--no-progress"],
                 "s.toml", *words)
        assert not (tmp_path / "o").exists()


def test_a_saved_world_declaring_a_huge_array_is_refused_unread(small_world, capsys):
    import io
    import zipfile

    with np.load(small_world) as z:
        d = {k: z[k] for k in z.files}
    with zipfile.ZipFile(small_world, "w") as out:
        for key, arr in d.items():
            buf = io.BytesIO()
            shape = (4 * 10**12, 3) if key == "blocked" else arr.shape  # a lying header
            np.lib.format.write_array_header_1_0(buf, {"descr": arr.dtype.str,
                                                       "fortran_order": False, "shape": shape})
            out.writestr(f"{key}.npy", buf.getvalue() + arr.tobytes())
    _refused(capsys, ["plan", str(small_world), "--start", "0,0,0", "--goal", "1,1,1"],
             "cloud.npz", "over the memory budget")


# -- 2. saved worlds verified --------------------------------------------------------------------
def _tamper(path: Path, redigest: bool = False, **change) -> None:
    with np.load(path) as z:
        d = {k: z[k] for k in z.files}
    d.update(change)
    if redigest:
        d["digest"] = np.array(digest(d))
    np.savez(path, **d)


def test_a_saved_world_plans_as_its_map(tmp_path, capsys):
    world = tmp_path / "office.npz"
    assert main(["world", "office", "--out", str(world)]) == 0
    assert main(["plan", str(world), *QUERY, "--json"]) == 0
    saved = capsys.readouterr().out.strip().splitlines()[-1]
    assert main(["plan", "office", *QUERY, "--json"]) == 0
    built = capsys.readouterr().out.strip().splitlines()[-1]
    import json

    a, b = json.loads(saved), json.loads(built)
    assert a["length"] == pytest.approx(b["length"]) and a["found"]


@pytest.mark.parametrize("change, words", [
    ({"source": np.array("other.bt")}, "digest"),
    ({"radius": np.array(5.0)}, "digest"),
])
def test_edited_values_break_the_digest(small_world, capsys, change, words):
    _tamper(small_world, **change)
    _refused(capsys, ["plan", str(small_world), "--start", "0,0,0", "--goal", "1,1,1"],
             "cloud.npz: corrupt or modified world file", words)


@pytest.mark.parametrize("change, words", [
    ({"dim": np.array(5)}, "'dim'"), ({"lattice": np.array("bcc")}, "'lattice' says 'bcc'"),
    ({"unknown_policy": np.array("maybe")}, "'unknown_policy'"),
    ({"unknown": np.array([7, 3], np.int64)}, "'unknown'"),
    ({"radius": np.array(np.nan)}, "'radius'"), ({"bounds": np.zeros(6)}, "'bounds'"),
])
def test_every_key_is_checked_even_under_a_matching_digest(small_world, capsys, change, words):
    _tamper(small_world, redigest=True, **change)
    _refused(capsys, ["plan", str(small_world), "--start", "0,0,0", "--goal", "1,1,1"],
             "corrupt or modified world file", words)


def test_cells_are_checked_in_bounds(small_world):
    import zlib

    def bits(a):
        return np.frombuffer(zlib.decompress(a.tobytes()), np.uint8).copy()

    def stream(b):
        return np.frombuffer(zlib.compress(b.tobytes()), np.uint8)

    with np.load(small_world) as z:
        b, u = bits(z["blocked"]), bits(z["unknown"])
    b[0] |= 1  # the first cell of the index box: a margin cell, out of bounds
    _tamper(small_world, redigest=True, blocked=stream(b))
    with pytest.raises(MapError, match="'blocked' holds cells outside the bounds"):
        load_world(small_world)
    u[0] |= 1
    _tamper(small_world, redigest=True, blocked=stream(b * 0), unknown=stream(u))
    with pytest.raises(MapError, match="'unknown' holds cells outside the bounds"):
        load_world(small_world)
    _tamper(small_world, redigest=True, unknown=stream(u[:-1]))
    with pytest.raises(MapError, match=r"'unknown' must hold \d+ bytes of bits over the box"):
        load_world(small_world)


@pytest.mark.parametrize("data", [b"", b"garbage", b"PK\x03\x04"])
def test_an_unreadable_npz_is_a_corrupt_world_not_a_map(tmp_path, capsys, data):
    p = tmp_path / "w.npz"
    p.write_bytes(data)
    _refused(capsys, ["plan", str(p), "--start", "0,0,0", "--goal", "1,1,1"],
             "w.npz: corrupt or modified world file")


def test_missing_keys_and_trailing_bytes_are_corrupt(small_world, capsys):
    raw = small_world.read_bytes()
    small_world.write_bytes(raw + b"\0" * 16)
    _refused(capsys, ["plan", str(small_world), "--start", "0,0,0", "--goal", "1,1,1"],
             "corrupt or modified world file", "after the end")
    small_world.write_bytes(raw)
    with np.load(small_world) as z:
        d = {k: z[k] for k in z.files if k != "generator"}
    np.savez(small_world, **d)
    _refused(capsys, ["plan", str(small_world), "--start", "0,0,0", "--goal", "1,1,1"],
             "missing key 'generator'")


def test_check_source_notices_a_changed_map(tmp_path, capsys):
    cloud = tmp_path / "cloud.xyz"
    cloud.write_bytes(corpus.xyz_text())
    world = tmp_path / "w.npz"
    assert main(["world", str(cloud), "--radius", "0.1", "--cell-volume", "0.05", "--out",
                 str(world)]) == 0
    argv = ["plan", str(world), "--check-source", "--start", "0,0,2", "--goal", "3,0,5"]
    assert main(argv) in (0, 1)
    cloud.write_bytes(corpus.xyz_text() + b"0 0 0\n")
    _refused(capsys, argv, "w.npz", "cloud.xyz has changed")


# -- 3. OS errors on outputs ---------------------------------------------------------------------
@pytest.mark.parametrize("code", [errno.ENOSPC, errno.EROFS, errno.EACCES])
@pytest.mark.parametrize("command", ["world", "plan"])
def test_a_failing_output_is_one_line_and_leaves_nothing(tmp_path, capsys, monkeypatch, code,
                                                         command):
    def fail(src, dst):
        raise OSError(code, os.strerror(code))

    cloud = tmp_path / "cloud.xyz"
    cloud.write_bytes(corpus.xyz_text())
    out = tmp_path / "out" / ("w.npz" if command == "world" else "p.csv")
    argv = (["world", str(cloud), "--radius", "0.1", "--out", str(out)] if command == "world"
            else ["plan", str(cloud), "--radius", "0.1", "--start", "0,0,2", "--goal",
                  "3,0,5", "--out", str(out)])
    monkeypatch.setattr(os, "replace", fail)
    line = _refused(capsys, argv, out.name, os.strerror(code))
    assert "Traceback" not in line
    assert not any(out.parent.iterdir())  # neither the output nor a temporary file


def test_an_output_on_a_missing_place_is_one_line(tmp_path, capsys):
    _refused(capsys, ["bench", "quick", "--out", "/proc/planner-bench", "--no-progress"],
             "/proc/planner-bench")


# -- 4. and 5. numeric edge cases and the right reason -------------------------------------------
@pytest.mark.parametrize("volume", ["1e300", "1e-300", "1e30"])
def test_absurd_cell_volumes_are_refused(capsys, volume):
    _refused(capsys, ["plan", "office", *QUERY, "--cell-volume", volume],
             "outside the supported range")


def test_huge_bounds_say_why(capsys):
    line = _refused(capsys, ["plan", "office", *QUERY,
                             "--bounds=-1e300,-1e300,-1e300,1e300,1e300,1e300"],
                    "bounds reach 1e+300 m", "exact")
    assert "obstacle" not in line


# -- 6. trailing data and silent acceptance -------------------------------------------------------
TRAILING = {"a.npy": corpus.npy(corpus.PTS), "m.bt": corpus.octomap(),
            "c.pcd": corpus.pcd("binary_compressed"), "p.xyz.bz2": bz2.compress(
                corpus.xyz_text()), "p.xyz.xz": lzma.compress(corpus.xyz_text())}


@pytest.mark.parametrize("name", sorted(TRAILING))
def test_data_after_a_complete_file_is_refused(tmp_path, capsys, name):
    p = tmp_path / name
    seed = TRAILING[name]
    p.write_bytes(seed)
    argv = ["plan", str(p), "--radius", "0.1", "--start", "0,0,0", "--goal", "1,1,1"]
    main(argv)  # the complete file is read (the query may be outside it)
    assert "trailing" not in capsys.readouterr().err
    p.write_bytes(seed + (seed if name.endswith((".bt", ".npy")) else b"junk"))
    _refused(capsys, argv, name, "trailing data")


@pytest.mark.parametrize("name", ["p12.las", "p12.laz", "p14.las", "p14.laz"])
def test_data_after_a_complete_las_or_laz_file_is_refused(tmp_path, capsys, name):
    laspy = pytest.importorskip("laspy")
    if name.endswith(".laz"):
        pytest.importorskip("lazrs")
    las = laspy.LasData(laspy.LasHeader(point_format=3, version="1.4" if "14" in name else "1.2"))
    xyz = np.random.default_rng(0).uniform(0, 2, (3000, 3))
    las.x, las.y, las.z = xyz.T
    if "14" in name:  # an extended VLR after the points (after the chunk table in a LAZ)
        from laspy.vlrs.vlrlist import VLRList

        las.evlrs = VLRList([laspy.VLR(user_id="test", record_id=7, record_data=b"payload")])
    p = tmp_path / name
    las.write(str(p))
    seed = p.read_bytes()
    argv = ["plan", str(p), "--radius", "0.1", "--start", "0,0,0", "--goal", "1,1,1"]
    main(argv)
    assert "trailing" not in capsys.readouterr().err
    for tail in (b"\x01", seed):  # one stray byte; the whole file again
        p.write_bytes(seed + tail)
        _refused(capsys, argv, name, f"{len(tail)} bytes of trailing data")


def test_a_bare_plus_in_the_move_set_is_refused(capsys):
    _refused(capsys, ["plan", "office", *QUERY, "--neighbors", "face+"], "face+",
             "shell count")


def test_compare_reports_a_corrupt_scenario_file(tmp_path, capsys):
    grid = tmp_path / "g.3dmap"
    grid.write_bytes(corpus.MAP3D)
    Path(str(grid) + ".3dscen").write_bytes(b"version 1\ng.3dmap\n1 2 x\n")
    _refused(capsys, ["compare", str(grid), "--lattices", "cubic", "--radius", "0",
                      "--cell-volume", "1"], "g.3dmap.3dscen")


# -- 7. an interrupt ends the program cleanly -----------------------------------------------------
def _sigint_as_from_a_terminal() -> None:
    """In the child, before it runs: Ctrl-C's default disposition, as in a terminal. A test
    run started in the background leaves SIGINT ignored, and Python keeps it ignored."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def test_ctrl_c_during_a_build_exits_130_with_one_line():
    env = dict(os.environ, PYTHONPATH=str(REPO))
    proc = subprocess.Popen([sys.executable, "-m", "planner", "compare", "office",
                             "--cell-volume", "0.0001", *QUERY], env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            preexec_fn=_sigint_as_from_a_terminal)
    time.sleep(4)  # inside the imports, the map build or a kernel: each must end cleanly
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=120)
    text = err.decode(errors="replace")
    assert proc.returncode == 130, (proc.returncode, text[-500:])
    lines = text.strip().splitlines()  # progress lines may come first, nothing else
    assert lines[-1] == "planner: interrupted", text[-500:]
    assert all(line.startswith("progress ") for line in lines[:-1]), text[-500:]


def test_ctrl_c_inside_a_kernel_load_callback_still_interrupts():
    """numba loads and compiles kernels through llvmlite, which calls back into Python from
    C and drops a callback's exception: the KeyboardInterrupt of a Ctrl-C that lands there
    must still stop the program once the callback returns."""
    script = "\n".join([
        "import os, signal, sys, time",
        "from planner._interrupt import install_sigint",
        "install_sigint()",
        "src = ('def callback():\\n'",
        "       '    try:\\n'",
        "       '        os.kill(os.getpid(), signal.SIGINT)\\n'",
        "       '        for _ in range(100000):\\n'",
        "       '            pass\\n'",
        "       '    except BaseException:\\n'",  # what ctypes does with a callback's error
        "       '        pass\\n')",
        "ns = {'os': os, 'signal': signal}",
        "exec(compile(src, '/site-packages/llvmlite/binding/callback.py', 'exec'), ns)",
        "try:",
        "    ns['callback']()",
        "    time.sleep(5)",
        "except KeyboardInterrupt:",
        "    sys.exit(130)",
    ])
    env = dict(os.environ, PYTHONPATH=str(REPO))
    proc = subprocess.run([sys.executable, "-c", script], env=env, capture_output=True,
                          timeout=60, preexec_fn=_sigint_as_from_a_terminal)
    assert proc.returncode == 130, proc.stderr.decode()[-500:]
