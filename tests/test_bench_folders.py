"""A suite run touches nothing the user did not name: its folder, its suite file and the
files it resumes from are checked before anything is written.

A folder that is not a previous run of the suite is refused untouched; a suite's name is a
label, never a path; rows and saved queries are checked line by line; a suite whose
settings changed does not resume the old rows; a suite that keeps no query says why.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from _suites import result_row, suite_text  # tests/_suites.py

from planner.bench.run_folder import MARKER, remove_world_cache, suite_digest, write_marker
from planner.bench.suite import SuiteError, load_suite
from planner.cli import main

SUITE = suite_text("tiny", seed=None, queries=2, path="office", cell_volume=0.01)
ROW = result_row(suite="tiny", map="office.ply", cell_volume=0.01, length=3.5,
                 length_smoothed=3.4, cell_checks=10, expansions=5)


def _snapshot(folder: Path) -> dict:
    return {str(p.relative_to(folder)): p.read_bytes() if p.is_file() else None
            for p in sorted(folder.rglob("*"))}


def _bench(capsys, *argv: str) -> tuple[int, str]:
    rc = main(["bench", *argv, "--no-progress"])
    return rc, capsys.readouterr().err


def _one_line(err: str) -> str:
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("planner: error: "), err
    return lines[0]


@pytest.fixture
def suite(tmp_path) -> Path:
    p = tmp_path / "tiny.toml"
    p.write_text(SUITE)
    return p


def test_a_users_folder_holding_worlds_is_refused_untouched(tmp_path, suite, capsys):
    user = tmp_path / "mine"
    (user / "worlds").mkdir(parents=True)
    (user / "worlds" / "scan.npz").write_bytes(b"the user's own world")
    (user / "notes.txt").write_text("keep me")
    before = _snapshot(user)
    rc, err = _bench(capsys, str(suite), "--out", str(user))
    assert rc == 2 and "not a planner bench results folder" in _one_line(err)
    assert _snapshot(user) == before  # not even a lock file
    for flag in ("--force", "--resume", "--report-only"):
        rc, err = _bench(capsys, str(suite), "--out", str(user), flag)
        assert rc == 2 and "nothing in it was touched" in _one_line(err)
        assert _snapshot(user) == before


def test_an_out_that_is_a_file_is_refused(tmp_path, suite, capsys):
    f = tmp_path / "results.txt"
    f.write_text("x")
    rc, err = _bench(capsys, str(suite), "--out", str(f))
    assert rc == 2 and "must be a folder" in _one_line(err) and f.read_text() == "x"


@pytest.mark.parametrize("name", ["../..", "/tmp/escape", "a/b", "a\\\\b", "..", ".hidden",
                                  "ti\\u0000ny", "x" * 101, ""])
def test_a_suite_name_is_a_label_never_a_path(tmp_path, name, capsys):
    s = tmp_path / "s.toml"
    s.write_text(SUITE.replace('"tiny"', f'"{name}"'))
    with pytest.raises(SuiteError, match="'name'"):
        load_suite(str(s))
    rc, err = _bench(capsys, str(s))
    assert rc == 2 and "'name'" in _one_line(err)
    assert not (tmp_path / "escape").exists() and not Path("results").joinpath(name).exists()


def test_a_suite_without_a_name_is_labelled_by_its_file_name(tmp_path):
    s = tmp_path / "run..1 [v2].toml"
    s.write_text(SUITE.replace('name = "tiny"\n', ""))
    assert load_suite(str(s)).name == "run_1 _v2_"


def test_cleanup_removes_only_the_world_files_runs_make(tmp_path):
    worlds = tmp_path / "worlds"
    worlds.mkdir()
    made = worlds / "0123456789abcdef0123.npz"
    made.write_bytes(b"cache")
    tmp = worlds / ".0123456789abcdef0123.npz.k3j2.tmp"
    tmp.write_bytes(b"half")
    keep = [worlds / "office.npz", worlds / "0123456789abcdef0123.npz.bak", worlds / "sub"]
    keep[0].write_bytes(b"user")
    keep[1].write_bytes(b"user")
    keep[2].mkdir()
    remove_world_cache(worlds)
    assert not made.exists() and not tmp.exists()
    assert all(p.exists() for p in keep)
    for p in keep:
        p.rmdir() if p.is_dir() else p.unlink()
    remove_world_cache(worlds)
    assert not worlds.exists()  # empty once only its own files were in it


def _run_folder(tmp_path: Path, suite: Path, lines: list[str]) -> Path:
    """A folder as a run of ``suite`` leaves it: its marker and these results lines."""
    out = tmp_path / "out"
    out.mkdir()
    write_marker(out, load_suite(str(suite)))
    (out / "results.jsonl").write_text("".join(line + "\n" for line in lines))
    return out


@pytest.mark.parametrize("bad, why", [
    ("{}", "no 'map'"), ("[1, 2]", "array"), ("null", "null"), ("42", "number"),
    ('"row"', "string"), ("{not json", "not JSON"),
    (json.dumps({**ROW, "length": "3.5"}), "'length' is not a number"),
    (json.dumps({**ROW, "query": "0"}), "'query' is not an integer"),
    (json.dumps({**ROW, "cell_volume": None}), "'cell_volume'"),
    (json.dumps({**ROW, "found": "yes"}), "'found'"),
    (json.dumps({**ROW, "map": ["office"]}), "'map'"),
    ("[" * 5000 + "]" * 5000, "not JSON"),
])
@pytest.mark.parametrize("flag", ["--resume", "--report-only"])
def test_a_results_line_that_is_not_a_row_is_refused_with_its_number(tmp_path, suite, bad,
                                                                      why, flag, capsys):
    out = _run_folder(tmp_path, suite, [json.dumps(ROW), json.dumps({**ROW, "query": 1}), bad])
    before = _snapshot(out)
    rc, err = _bench(capsys, str(suite), "--out", str(out), flag)
    line = _one_line(err)
    assert rc == 2 and "results.jsonl line 3: not a result row" in line and why in line, line
    assert _snapshot(out) == before


@pytest.mark.parametrize("record, why", [
    ("[1]", "got array"), ('{"g": 1}', "number, not an object"),
    ('{"g": [1, 2]}', "array, not an object"), ('{"g": {"queries": [1]}}', "a query is number"),
    ('{"g": {"queries": [{"id": 0, "start": [0, 0], "goal": "x"}]}}', "'goal'"),
    ('{"g": {"queries": 5}}', "'queries' is not a list"),
    ('{"g": {"wanted": "2", "queries": []}}', "'wanted'"),
])
def test_saved_query_records_of_the_wrong_shape_are_refused(tmp_path, suite, record, why,
                                                             capsys):
    out = _run_folder(tmp_path, suite, [json.dumps(ROW)])
    (out / "queries.json").write_text(record)
    before = _snapshot(out)
    rc, err = _bench(capsys, str(suite), "--out", str(out), "--resume")
    line = _one_line(err)
    assert rc == 2 and "queries.json" in line and why in line, line
    assert _snapshot(out) == before


def test_rows_of_an_edited_suite_are_not_resumed(tmp_path, suite, capsys):
    out = _run_folder(tmp_path, suite, [json.dumps(ROW)])
    before = _snapshot(out)
    suite.write_text(SUITE.replace('lattices = ["cubic"]', 'lattices = ["fcc"]'))
    for flag in ("--resume", "--report-only"):
        rc, err = _bench(capsys, str(suite), "--out", str(out), flag)
        assert rc == 2 and "different suite" in _one_line(err) and "--force" in err
        assert _snapshot(out) == before
    # the same settings written differently (a comment, key order) are the same suite
    suite.write_text("# reordered\n" + SUITE.replace('queries = 2\n', '') .replace(
        'min_distance = 0.3\n', 'min_distance = 0.3\nqueries = 2\n'))
    assert suite_digest(load_suite(str(suite))) == json.loads(
        (out / MARKER).read_text())["digest"]


def test_a_suite_that_keeps_no_query_exits_2_naming_why(tmp_path, capsys):
    s = tmp_path / "far.toml"
    s.write_text(SUITE.replace("min_distance = 0.3", "min_distance = 0.999"))
    out = tmp_path / "far"
    rc, err = _bench(capsys, str(s), "--out", str(out))
    line = _one_line(err)
    assert rc == 2 and "no query kept for office.ply" in line, line
    assert "start and goal too close" in line and "min_distance" in line
    assert not out.exists()  # a refused run leaves nothing of its own


BAD_SUITES = {
    "deep arrays": SUITE.replace("queries = 2", "queries = " + "[" * 100_000 + "]" * 100_000),
    "deep arrays 900": SUITE.replace("queries = 2", "queries = " + "[" * 900 + "]" * 900),
    "deep tables": SUITE.replace("queries = 2", "x = " + "{a=" * 5000 + "1" + "}" * 5000),
    "nested lists": SUITE.replace("radii = [0.1]", "radii = [[[[0.1]]]]"),
    "NUL in name": SUITE.replace('"tiny"', '"ti\\u0000ny"'),
    "NUL in a path": SUITE.replace('"office"', '"off\\u0000ice"'),
    "boolean cell volume": SUITE.replace("[0.01]", "[true]"),
    "boolean radius": SUITE.replace("radii = [0.1]", "radii = [false]"),
    "nothing to run": SUITE.replace('methods = ["astar"]', "methods = []"),
    "paper seed 2^63": 'kind = "paper"\n[paper]\nseed = 9223372036854775807\n',
    "paper samples 1e12": 'kind = "paper"\n[paper]\nsamples = 1000000000000\n',
    "min_distance 2": SUITE.replace("min_distance = 0.3", "min_distance = 2.0"),
    "min_distance 0": SUITE.replace("min_distance = 0.3", "min_distance = 0"),
    "min_distance 1": SUITE.replace("min_distance = 0.3", "min_distance = 1"),
    "a long path": SUITE.replace('"office"', '"' + "x" * 5000 + '"'),
    "many lattices": SUITE.replace('["cubic"]', "[" + ", ".join(['"cubic"'] * 10_001) + "]"),
    "both cell_volume keys": SUITE.replace("cell_volumes = [0.01]",
                                           "cell_volumes = [0.01]\ncell_volume = 0.01"),
    "empty cell volumes": SUITE.replace("[0.01]", "[]"),
    "ompl planners a string": SUITE + '[ompl]\nplanners = "rrt"\n',
    "rotation a number": SUITE.replace("queries = 2", "queries = 2\nrotation = 5"),
    "scenarios a number": SUITE.replace("radii = [0.1]", "radii = [0.1]\nscenarios = 5"),
    "over 1 MB": SUITE + "#" * (1 << 20) + "\n",
}


@pytest.mark.parametrize("case", sorted(BAD_SUITES))
def test_bad_suites_exit_2_with_one_line_naming_the_key(tmp_path, case, capsys):
    s = tmp_path / "bad.toml"
    s.write_text(BAD_SUITES[case])
    rc, err = _bench(capsys, str(s), "--out", str(tmp_path / "out"))
    assert rc == 2, err
    line = _one_line(err)
    assert "bad.toml" in line
    assert not (tmp_path / "out").exists()


def test_min_distance_error_says_what_it_means(tmp_path):
    s = tmp_path / "bad.toml"
    s.write_text(BAD_SUITES["min_distance 2"])
    with pytest.raises(SuiteError, match=r"'min_distance' must be a number in \(0, 1\).*"
                                         r"fraction of the map box's diagonal"):
        load_suite(str(s))


def test_suite_keys_are_in_bench_help(capsys):
    with pytest.raises(SystemExit):
        main(["bench", "--help"])
    out = capsys.readouterr().out
    for key in ("min_distance", "cell_volumes", "[ompl]", "[paper]", "rotations", "a label"):
        assert key in out, key


def test_a_task_lost_with_its_dask_scheduler_is_one_line(monkeypatch):
    import distributed

    from planner.bench import runner
    from planner.errors import PlannerError

    class Future:
        status = "cancelled"

    class Client:
        def __init__(self, *a, **k):
            pass

        def __enter__(self):
            return self

        def __exit__(self, *exc):
            return False

        def map(self, *a, **k):
            return [Future()]

        def cancel(self, futs):
            raise OSError("the scheduler is gone")  # cancelling fails too: still one line

    def completed(futs, with_results=False, raise_errors=True):
        # what distributed yields for a future cancelled when its scheduler died
        yield futs[0], distributed.client.FutureCancelledError("k", "scheduler-connection-lost")

    monkeypatch.setattr(distributed, "Client", Client)
    monkeypatch.setattr(distributed, "as_completed", completed)
    written = []
    with pytest.raises(PlannerError, match="a task was lost .*--resume"):
        runner._run_dask([{"queries": []}], "tcp://127.0.0.1:1", written.append)
    assert written == []


def test_a_group_that_keeps_no_query_is_reported_and_the_rest_runs(tmp_path, capsys):
    # a 3 m robot fits nowhere in the office: that group keeps no query, the 0.1 m one runs
    s = tmp_path / "wide.toml"
    s.write_text(SUITE.replace("radii = [0.1]", "radii = [0.1, 3.0]"))
    out = tmp_path / "wide"
    rc = main(["bench", str(s), "--out", str(out), "--no-progress"])
    err = capsys.readouterr().err
    assert rc == 0, err
    warning = [ln for ln in err.splitlines() if ln.startswith("WARNING: no query kept")]
    assert len(warning) == 1 and "radius 3" in warning[0] and "left out" in warning[0]
    rows = [json.loads(ln) for ln in (out / "results.jsonl").read_text().splitlines()]
    assert rows and {r["radius"] for r in rows} == {0.1}
    assert "0/2" in (out / "report.md").read_text()  # the group's line, with its reasons
    page = (out / "results_section.md").read_text()
    assert "Groups that kept no query (1 of 2" in page and "radius 3" in page
