"""One command's outputs are all or nothing: a later output that fails leaves no earlier one,
a file the user did not name is never overwritten, temporary names fit the file system and
SIGTERM ends a command with 143, one line and no temporary file."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from planner.cli import main
from planner.fsutil import NAME_MAX, atomic_path, staged_outputs, temp_prefix

QUERY = ["--start", "1,1,1", "--goal", "7.6,7.8,0.8"]
REPO = Path(__file__).resolve().parents[1]


def _one_line(capsys) -> str:
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("planner: error: "), err
    return err[0]


def test_a_csvs_sidecar_the_user_did_not_name_is_not_overwritten(tmp_path, capsys):
    side = tmp_path / "p.json"
    side.write_text('{"my": "notes"}')
    assert main(["plan", "office", *QUERY, "--out", str(tmp_path / "p.csv")]) == 2
    assert "p.json" in _one_line(capsys) and side.read_text() == '{"my": "notes"}'
    assert sorted(p.name for p in tmp_path.iterdir()) == ["p.json"]
    side.unlink()
    side.mkdir()  # a folder where the sidecar would go: refused before any work
    assert main(["plan", "office", *QUERY, "--out", str(tmp_path / "p.csv")]) == 2
    _one_line(capsys)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["p.json"]
    side.rmdir()
    # a sidecar written by planner belongs to the CSV it is replaced with
    assert main(["plan", "office", *QUERY, "--out", str(tmp_path / "p.csv")]) == 0
    assert main(["plan", "office", *QUERY, "--out", str(tmp_path / "p.csv")]) == 0
    capsys.readouterr()


def test_a_later_output_failing_leaves_no_earlier_one(tmp_path, capsys):
    (tmp_path / "bag").mkdir()  # --bag must be a new folder: refused after --out is written
    rc = main(["plan", "office", *QUERY, "--out", str(tmp_path / "p.csv"), "--bag",
               str(tmp_path / "bag")])
    if rc == 2:
        assert "bag" in _one_line(capsys)
    else:  # the robot extra (rosbags) is missing: then --bag is refused the same way
        pytest.skip("rosbags not installed")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bag"]


def test_staged_outputs_are_renamed_together_or_removed(tmp_path):
    a, b = tmp_path / "a.txt", tmp_path / "b.txt"
    with pytest.raises(RuntimeError), staged_outputs():
        with atomic_path(a) as tmp:
            tmp.write_text("a")
        assert not a.exists()  # staged: not in place before the command succeeds
        raise RuntimeError("a later output failed")
    assert list(tmp_path.iterdir()) == []
    b.mkdir()
    with pytest.raises(IsADirectoryError), staged_outputs():
        with atomic_path(a) as tmp:
            tmp.write_text("a")
        with atomic_path(b / "x") as tmp:  # fine
            tmp.write_text("x")
        with atomic_path(tmp_path / "c.txt") as tmp:
            tmp.write_text("c")
        (tmp_path / "c.txt").mkdir()  # a folder appears where an output goes
    assert sorted(p.name for p in tmp_path.iterdir()) == ["b.txt", "c.txt"]
    assert list(b.iterdir()) == [] and not a.exists()
    with staged_outputs():
        with atomic_path(a) as tmp:
            tmp.write_text("a")
    assert a.read_text() == "a"


@pytest.mark.parametrize("length", [244, 248, 251, 254, 255])
def test_output_names_up_to_the_file_system_limit_are_written(tmp_path, length, capsys):
    name = "p" * (length - 4) + ".csv"
    assert len(name.encode()) == length
    assert len((temp_prefix(name, ".tmp") + "x" * 8 + ".tmp").encode()) <= NAME_MAX
    rc = main(["plan", "office", *QUERY, "--out", str(tmp_path / name)])
    if length == 255:  # its sidecar, NAME.json, would be 256 bytes: refused before any work
        assert rc == 2 and "longer than 255 bytes" in _one_line(capsys)
        assert list(tmp_path.iterdir()) == []
        return
    assert rc == 0
    capsys.readouterr()
    assert (tmp_path / name).is_file() and (tmp_path / name).with_suffix(".json").is_file()
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]


def test_temporary_names_cut_multibyte_names_whole():
    p = temp_prefix("é" * 200 + ".npz", ".tmp")
    assert len(p.encode()) + 8 + 4 <= NAME_MAX and p.startswith(".é")


def _wait_for_sigterm_handler(pid: int, timeout: float = 60.0) -> None:
    """Until process ``pid`` catches SIGTERM (Linux: its ``SigCgt`` mask; elsewhere a fixed
    wait): a signal before that kills it the default way, whatever the CLI does, and on a
    loaded machine the imports alone can outlast a fixed delay."""
    status = Path(f"/proc/{pid}/status")
    if not status.is_file():
        time.sleep(2.0)
        return
    end = time.monotonic() + timeout
    bit = 1 << (signal.SIGTERM - 1)
    while time.monotonic() < end:
        try:
            caught = next(ln for ln in status.read_text().splitlines()
                          if ln.startswith("SigCgt:"))
        except (OSError, StopIteration):
            return  # the process ended
        if int(caught.split()[1], 16) & bit:
            return
        time.sleep(0.01)


@pytest.mark.parametrize("delay", [0.0, 0.5])
def test_sigterm_ends_a_world_build_with_143_and_no_temporary_file(tmp_path, delay):
    env = dict(os.environ, PYTHONPATH=str(REPO))
    out = tmp_path / "w.npz"
    proc = subprocess.Popen([sys.executable, "-m", "planner", "world", "office", "--radius",
                             "0.2", "--cell-volume", "0.0004", "--out", str(out)],
                            stderr=subprocess.PIPE, stdout=subprocess.DEVNULL, env=env,
                            text=True)
    _wait_for_sigterm_handler(proc.pid)
    time.sleep(delay)  # at the start of the build, or into it
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=120)
    if proc.returncode == 0:
        pytest.skip("the build finished before the signal")
    assert proc.returncode == 143, err
    assert "Traceback" not in err and err.strip().splitlines()[-1:] in ([],
                                                                       ["planner: terminated"])
    assert list(tmp_path.iterdir()) == []


def test_a_full_disk_under_the_planner_arena_database_is_an_os_error(tmp_path, monkeypatch):
    import sqlite3

    from planner.export import arena

    class Full:
        def executescript(self, _):
            raise sqlite3.OperationalError("database or disk is full")

        def close(self):
            pass

    monkeypatch.setattr(arena.sqlite3, "connect", lambda _: Full())
    with pytest.raises(OSError, match="disk is full") as got:
        arena.write_arena_db(tmp_path / "planner_arena.db", [])
    assert got.value.filename == str(tmp_path / "planner_arena.db")
    assert list(tmp_path.iterdir()) == []  # the temporary file is gone too
