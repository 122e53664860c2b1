"""Hostile inputs through the API and the command line: one clean line, never a traceback.

Every case of ``tests/fuzz/make_corpus.py`` (malformed maps of every reader, sidecars,
scenario files, benchmark suites, saved voxel lists) runs through the API, which must
return or raise a ``planner`` exception. (The same cases run through the command line in
``tests/test_fuzz_corpus.py``.) The rest of this file runs the CLI in a subprocess under a
3 GB address-space limit on inputs that must be refused by the memory budget, or whose
searches must end: exit 2 with exactly one stderr line, no traceback, no hang.
"""

from __future__ import annotations

import gzip
import os
import resource
import subprocess
import sys
import time
from collections import Counter
from pathlib import Path
from types import SimpleNamespace

import pytest
from test_fuzz_readers import corpus  # tests/fuzz/make_corpus.py, loaded once

import planner
from planner import OccupiedVoxelList
from planner.bench.suite import load_suite
from planner.errors import PlannerError
from planner.io import load_scenarios, load_sidecar

pytestmark = pytest.mark.filterwarnings("error::RuntimeWarning")

ADDRESS_SPACE = 3 * 2**30  # bytes: a run over it would die of MemoryError (a traceback)
HANG = 90  # seconds: a run still going after this is a hang (generous: CI machines are shared)
REPO = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def cases(tmp_path_factory) -> list:
    root = tmp_path_factory.mktemp("corpus")
    return corpus.make_corpus(root) + corpus.make_entry_corpus(root / "entry")


def _map_for(case) -> Path:
    """The map a case is given as: the file itself, or (sidecars) a valid cloud beside it."""
    if case.loader != "sidecar":
        return case.path
    cloud = case.path.with_suffix(".xyz")
    cloud.write_bytes(corpus.xyz_text())
    return cloud


def _limit_memory() -> None:  # in the child, before exec
    resource.setrlimit(resource.RLIMIT_AS, (ADDRESS_SPACE, ADDRESS_SPACE))


def _env() -> dict:
    env = dict(os.environ, PYTHONPATH=str(REPO), PYTHONWARNINGS="ignore::DeprecationWarning")
    env.pop("PLANNER_MEMORY_BUDGET", None)
    return env


def _cli(argv: list[str], hang: float = HANG) -> SimpleNamespace | None:
    """``python -m planner ARGV`` in a subprocess (None: still running after ``hang`` s)."""
    try:
        p = subprocess.run([sys.executable, "-m", "planner", *argv], capture_output=True,
                           text=True, timeout=hang, env=_env(), preexec_fn=_limit_memory,
                           errors="replace")
    except subprocess.TimeoutExpired:
        return None
    return SimpleNamespace(returncode=p.returncode, stdout=p.stdout, stderr=p.stderr)


def _api(case):
    if case.loader == "voxels":
        return OccupiedVoxelList.load(case.path)
    if case.loader == "suite":
        return load_suite(str(case.path))
    if case.loader == "scenarios":
        return load_scenarios(case.path)
    if case.loader == "sidecar":
        load_sidecar(case.path)
    return planner.build_world(str(_map_for(case)), "fcc", radius=0.1, format=case.format)


@pytest.mark.slow
def test_every_corpus_case_through_the_api(cases):
    counts = Counter()
    for case in cases:
        try:
            _api(case)
            counts[case.reader, "ok"] += 1
        except PlannerError as exc:  # any other exception fails the test
            assert str(exc) and "\n" not in str(exc), (case.path.name, str(exc))
            counts[case.reader, "error"] += 1
    for reader in ("suite", "voxels", "sidecar", "3dscen"):
        assert counts[reader, "error"] > 0, reader


# -- budgets: refusals within seconds, searches that end ------------------------------------------
DATA = REPO.parent / "shared" / "data"
GEB079 = DATA / "octomap" / "geb079.bt"
DA1 = DATA / "warframe" / "DA1.3dmap"


def _refused(argv: list[str], *words: str) -> str:
    """Run the CLI (3 GB limit); assert one budget error line naming ``words``."""
    proc = _cli(argv)
    assert proc is not None, f"hang: {argv}"
    lines = proc.stderr.strip().splitlines()
    assert proc.returncode == 2 and len(lines) == 1, proc.stderr[-500:]
    assert all(w in lines[0] for w in words), lines[0]
    return lines[0]


@pytest.mark.skipif(not GEB079.exists(), reason="shared OctoMap data not present")
@pytest.mark.parametrize("extra", [["--cell-volume", "1e-9", "--radius", "0"],
                                   ["--cell-volume", "1e-9", "--radius", "0.2"],
                                   ["--cell-volume", "1e-6", "--radius", "0"]])
@pytest.mark.slow
def test_huge_octomap_worlds_are_refused_by_the_memory_budget(extra):
    _refused(["plan", str(GEB079), "--start", "0,0,0.5", "--goal", "1,0,0.5", *extra],
             "geb079.bt", "over the memory budget", "--memory-budget")


@pytest.mark.slow
@pytest.mark.skipif(not GEB079.exists(), reason="shared OctoMap data not present")
def test_a_robot_wider_than_the_corridors_gets_one_line_within_the_memory_limit():
    # r = 3 m with 0.08 m cells: a 200,000-offset stencil over unknown space dilated past
    # the map box. It is slow (minutes under load) but must end in one line under 3 GB.
    proc = _cli(["plan", str(GEB079), "--start", "0,0,0.5", "--goal", "1,0,0.5",
                 "--radius", "3"], hang=8 * HANG)
    assert proc is not None, "hang"
    lines = proc.stderr.strip().splitlines()
    assert proc.returncode == 2 and len(lines) == 1, proc.stderr[-500:]
    assert "start (0.000, 0.000, 0.500) is blocked" in lines[0], lines[0]


@pytest.mark.slow
def test_huge_move_sets_and_gzip_bombs_are_refused(tmp_path):
    _refused(["plan", "office", "--start", "1,1,1", "--goal", "7.6,7.8,0.8", "--neighbors",
              "face+1000"], "neighbour shells")
    bomb = tmp_path / "bomb.xyz.gz"
    chunk = b"0 0 0\n" * ((1 << 20) // 6)
    with gzip.open(bomb, "wb") as f:
        for _ in range(64):  # 64 MB of text, 64 kB compressed
            f.write(chunk)
    _refused(["--memory-budget", "64M", "plan", str(bomb), "--radius", "0.1", "--start",
              "0,0,0", "--goal", "1,1,1"], "bomb.xyz.gz", "decompression budget")


@pytest.mark.slow
def test_any_angle_scratch_does_not_grow_with_the_box():
    # a 2000 km box: the sight-line scratch is capped by the budget, not sized by the box
    proc = _cli(["plan", "office", "--method", "lazy-theta", "--start", "1,1,1", "--goal",
                 "7.6,7.8,0.8", "--bounds", "-1e6,-1e6,-1e6,1e6,1e6,1e6",
                 "--max-expansions", "50"])
    assert proc is not None and "Traceback" not in proc.stderr, proc.stderr[-500:]
    assert proc.returncode == 1 and "search budget exhausted after 50 expansions" in proc.stdout


def _sealed(tmp_path: Path, shell: int) -> tuple[Path, str, str]:
    """DA1 with a closed cube of voxels ``shell`` cells around the first scenario's goal."""
    lines = DA1.read_text().splitlines()
    scen = (DATA / "warframe" / "DA1.3dmap.3dscen").read_text().splitlines()[2].split()
    start, goal = scen[0:3], scen[3:6]
    g = [int(v) for v in goal]
    r = range(-shell, shell + 1)
    walls = {f"{g[0] + i} {g[1] + j} {g[2] + k}" for i in r for j in r for k in r
             if max(abs(i), abs(j), abs(k)) == shell}
    keep = [ln for ln in lines[1:] if ln.strip() and ln != " ".join(goal)]
    path = tmp_path / f"DA1_sealed{shell}.3dmap"
    path.write_text("\n".join([lines[0], *keep, *sorted(walls - set(keep))]) + "\n")
    return path, ",".join(start), ",".join(goal)


@pytest.mark.slow
@pytest.mark.skipif(not DA1.exists(), reason="shared Warframe data not present")
def test_a_sealed_goal_on_a_large_map_is_unreachable_at_once(tmp_path):
    path, start, goal = _sealed(tmp_path, 2)
    proc = _cli(["plan", str(path), "--lattice", "cubic", "--cell-volume", "1", "--radius",
                 "0", "--start", start, "--goal", goal])
    assert proc is not None and proc.returncode == 1, proc and proc.stderr[-500:]
    assert "no path (goal unreachable" in proc.stdout and "Traceback" not in proc.stderr


@pytest.mark.slow
@pytest.mark.skipif(not DA1.exists(), reason="shared Warframe data not present")
def test_an_unreachable_goal_ends_at_the_search_budget(tmp_path):
    # a pocket too big for the goal probe: the search explores until the node budget the
    # memory budget allows (256 MB), then answers in one line
    path, start, goal = _sealed(tmp_path, 12)
    proc = _cli(["--memory-budget", "256M", "plan", str(path), "--lattice", "cubic",
                 "--cell-volume", "1", "--radius", "0", "--start", start, "--goal", goal])
    assert proc is not None and proc.returncode == 1, proc and proc.stderr[-500:]
    out = proc.stdout.strip().splitlines()
    assert len(out) == 1 and "search budget exhausted after" in out[0], proc.stdout
    assert "Traceback" not in proc.stderr


# -- kill -9 at three points: no finished row is lost -----------------------------------------
KILL_SUITE = """name = "killed"
seed = 3
queries = 6
lattices = ["cubic", "fcc"]
neighbors = ["full"]
methods = ["astar", "dijkstra"]
min_distance = 0.3

[[maps]]
path = "office"
cell_volumes = [0.004]
radii = [0.25]
"""


def _rows(results: Path) -> dict:
    """Finished rows by run key (a last line cut short by the kill does not count)."""
    from planner.bench import runner

    return {runner.row_key(r): r for r in runner.read_rows(results)} if results.is_file() else {}


@pytest.mark.slow
@pytest.mark.parametrize("point", ["first row", "half the rows", "report"])
def test_kill_9_loses_no_finished_row(tmp_path, point):
    suite = tmp_path / "killed.toml"
    suite.write_text(KILL_SUITE)
    out = tmp_path / "out"
    results = out / "results.jsonl"
    wanted = 2 * 2 * 6
    need = {"first row": 1, "half the rows": wanted // 2, "report": wanted}[point]
    proc = subprocess.Popen([sys.executable, "-m", "planner", "bench", str(suite), "--out",
                             str(out), "--no-progress"], env=_env(),
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    try:
        while proc.poll() is None and len(_rows(results)) < need:
            time.sleep(0.005)
    finally:
        proc.kill()  # SIGKILL: no handler runs
        _, err = proc.communicate(timeout=HANG)
    assert "Traceback" not in err.decode(errors="replace")
    before = _rows(results)
    assert len(before) >= min(need, wanted) or proc.returncode == 0, err
    resumed = _cli(["bench", str(suite), "--out", str(out), "--resume", "--no-progress"])
    assert resumed is not None and resumed.returncode == 0, resumed and resumed.stderr[-500:]
    after = _rows(results)
    assert len(after) == wanted
    assert all(after[k] == row for k, row in before.items())  # kept, not redone
    assert "PARTIAL" not in resumed.stdout and (out / "report.md").is_file()
