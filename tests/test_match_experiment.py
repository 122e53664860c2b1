"""The Fig. 6 experiment: trials, resume, report and the ``planner match-experiment`` CLI."""

import json
from pathlib import Path

import numpy as np
import pytest

from planner.cli import main
from planner.errors import PlannerError
from planner.match import anchor, pose_matrix
from planner.match.experiment import ROWS, read_rows, run_experiment
from planner.match.experiment_pairs import Pair, draw_trial, load_sources
from planner.match.experiment_regimes import REGIMES, regime_scans
from planner.match.experiment_report import format_report, write_outputs

DATA = Path(__file__).resolve().parents[1] / ".." / "shared" / "data"
LATTICES = ["cubic", "fcc"]


def _office(rng, n=6000):
    """Points on the walls, floor and ceiling of an 8 x 5 x 3 m room with a pillar and a
    desk, metres, centred on the origin."""
    u = rng.uniform(0, 1, (n, 3)) * [8, 5, 3]
    face = rng.integers(0, 8, n)
    p = u.copy()
    p[face == 0, 1], p[face == 1, 1] = 0, 5
    p[face == 2, 0], p[face == 3, 0] = 0, 8
    p[face == 4, 2], p[face == 5, 2] = 0, 3
    a = rng.uniform(0, 2 * np.pi, n)
    pillar = face == 6
    p[pillar, 0], p[pillar, 1] = 2 + 0.4 * np.cos(a[pillar]), 2 + 0.4 * np.sin(a[pillar])
    desk = face == 7
    p[desk, 0], p[desk, 1], p[desk, 2] = 5 + u[desk, 0] / 8 * 2, 3 + u[desk, 1] / 5, 0.75
    return p - [4, 2.5, 1.5]


def _pair(name, seed, kind="truth"):
    rng = np.random.default_rng(seed)
    truth = pose_matrix([0.4, -0.3, 0.05, 1.0, -2.0, 8.0])
    src = (_office(rng) - truth[:3, 3]) @ truth[:3, :3]  # the room from the moved sensor
    return Pair(name, src, _office(rng), truth, kind=kind, group="synthetic")


def _run(out, pairs, trials, **kw):
    kw.setdefault("anchors", [])
    return run_experiment(pairs, out, lattices=LATTICES, trials=trials, max_offset=0.3,
                          max_angle=5.0, progress=False, **kw)


@pytest.mark.slow
def test_every_method_sees_the_same_draws_and_the_report_has_its_tables(tmp_path):
    pairs = [_pair("a", 1), _pair("loop", 3, kind="consistency")]
    rows = _run(tmp_path, pairs, trials=3)
    assert len(rows) == 2 * 3 * len(LATTICES)
    by_method = {m: [(r["trial"], round(r["initial_position_error"], 12)) for r in rows
                     if r["method"] == m] for m in LATTICES}
    assert by_method["cubic"] == by_method["fcc"]
    summary = write_outputs(rows, LATTICES, tmp_path)
    default = summary["regimes"]["default"]
    assert list(default["methods"]) == LATTICES
    for s in default["methods"].values():
        assert s["n"] == 3 and s["success"]["rate"] == 1.0 and s["outliers"]["rate"] == 0.0
        lo, hi = s["position_error"]["ci"]
        assert lo <= s["position_error"]["median"] <= hi
    assert set(default["consistency"]) == set(LATTICES)
    assert default["consistency"]["fcc"]["position_residual"]["median"] < 0.05
    assert summary["paired"]["fcc"]["n"] == 3
    assert summary["verdict"].startswith("Verdict on the paper's claim")
    text = (tmp_path / "table.md").read_text()
    assert text == format_report(summary) and "| fcc | 3 |" in text
    assert (tmp_path / "fig6.png").read_bytes()[:4] == b"\x89PNG"
    assert len((tmp_path / "trials.csv").read_text().splitlines()) == len(rows) + 1
    assert json.loads((tmp_path / "summary.json").read_text())["verdict"] == summary["verdict"]


def test_resume_runs_only_the_missing_trials_and_survives_a_cut_line(tmp_path):
    pairs = [_pair("a", 1)]
    first = _run(tmp_path, pairs, trials=1)
    with open(tmp_path / ROWS, "a") as f:
        f.write('{"trial": "0/1", "meth')  # a kill in the middle of a row
    with pytest.raises(PlannerError, match="--resume"):
        _run(tmp_path, pairs, trials=2)
    rows = _run(tmp_path, pairs, trials=2, resume=True)
    assert rows[:len(first)] == first  # the finished rows were kept, not rerun
    assert sorted((r["trial"], r["method"]) for r in rows) == sorted(
        (f"default/0/{k}", m) for k in range(2) for m in LATTICES)
    assert len(read_rows(tmp_path / ROWS)) == len(rows)
    with pytest.raises(PlannerError, match="other settings"):
        _run(tmp_path, pairs, trials=2, resume=True, seed=5)


def test_trial_draws_do_not_depend_on_the_number_of_trials():
    a, b = draw_trial(0, 1, 3, 0.5, 10.0), draw_trial(0, 1, 3, 0.5, 10.0)
    assert np.array_equal(a.rotation, b.rotation) and np.array_equal(a.error, b.error)
    assert np.linalg.norm(a.error[:3, 3]) <= 0.5
    assert not np.array_equal(a.rotation, draw_trial(0, 1, 4, 0.5, 10.0).rotation)


def test_cli_runs_user_pairs_end_to_end(tmp_path, capsys):
    pair = _pair("x", 4)
    np.save(tmp_path / "src.npy", pair.source)
    np.save(tmp_path / "ref.npy", pair.reference)
    np.savetxt(tmp_path / "t.txt", pair.transform)
    out = tmp_path / "run"
    args = ["match-experiment", "--sources", "", "--pair", str(tmp_path / "src.npy"),
            str(tmp_path / "ref.npy"), str(tmp_path / "t.txt"), "--lattices", "cubic,fcc",
            "--trials", "2", "--max-offset", "0.3", "--max-angle", "5", "--no-icp",
            "--out", str(out), "--plot", str(tmp_path / "fig.svg"), "--no-progress"]
    assert main(args) == 0
    text = capsys.readouterr().out
    assert "| cubic | 2 |" in text and "| fcc | 2 |" in text and "Verdict on" in text
    assert (tmp_path / "fig.svg").read_text().lstrip().startswith("<?xml")
    assert main(args + ["--resume"]) == 0  # nothing left to run: the report again
    assert len(read_rows(out / ROWS)) == 4


@pytest.mark.parametrize("extra", [["--sources", "moon"], ["--data", "/nonexistent"],
                                   ["--lattices", "cubic,square"], ["--anchors", "icp"],
                                   ["--regimes", "default,near"],
                                   ["--sources", "", "--pair", "a.npy", "b.npy", "t.txt"],
                                   ["--plot", "fig.gif"]])
def test_cli_bad_input_is_one_line_exit_2(tmp_path, capsys, extra):
    code = main(["match-experiment", "--out", str(tmp_path / "o"), *extra])
    assert code == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("planner: error:")


@pytest.mark.skipif(not (DATA / "velodyne").is_dir(), reason="Velodyne pair not present")
def test_velodyne_trial_succeeds_on_fcc(tmp_path):
    pairs = load_sources(["velodyne"], DATA)
    rows = run_experiment(pairs, tmp_path, lattices=["fcc"], anchors=[], trials=1,
                          progress=False)
    assert rows[0]["position_error"] < 0.05 and rows[0]["rotation_error"] < 1.0


@pytest.mark.slow
@pytest.mark.skipif(not (DATA / "octomap").is_dir(), reason="geb079 not present")
def test_simulated_geb079_pairs_have_their_separations():
    pairs = load_sources(["geb079"], DATA)
    seps = sorted(round(float(np.linalg.norm(p.transform[:3, 3])), 6) for p in pairs)
    assert seps == [0.25, 0.5, 1.0]
    assert all(len(p.source) > 10000 and len(p.reference) > 10000 for p in pairs)


def test_regimes_cut_and_thin_the_scans_the_same_way_for_every_method():
    pair = _pair("a", 1)
    full = regime_scans(REGIMES["default"], pair.source, pair.reference, pair.transform,
                        0, 0, 0)
    assert full[0] is pair.source and full[1] is pair.reference
    src, ref = regime_scans(REGIMES["sparse"], pair.source, pair.reference, pair.transform,
                            0, 0, 0)
    assert len(src) == len(ref) == 2000
    src, ref = regime_scans(REGIMES["overlap"], pair.source, pair.reference, pair.transform,
                            0, 0, 0)
    assert 0.5 < len(src) / len(pair.source) < 0.85 and 0.5 < len(ref) / len(pair.reference)
    again = regime_scans(REGIMES["overlap"], pair.source, pair.reference, pair.transform,
                         0, 0, 0)
    assert np.array_equal(src, again[0]) and np.array_equal(ref, again[1])


@pytest.mark.skipif(not anchor.available(), reason="the 'match' extra is not installed")
def test_regimes_and_anchors_are_reported_with_where_the_lattice_matcher_loses(tmp_path):
    rows = _run(tmp_path, [_pair("a", 1)], trials=1, anchors=["gicp"],
                regimes=["default", "far", "sparse"])
    assert sorted({(r["regime"], r["method"]) for r in rows}) == sorted(
        (g, m) for g in ("default", "far", "sparse") for m in [*LATTICES, "gicp"])
    assert {r["source_points"] for r in rows if r["regime"] == "sparse"} == {2000}
    far = [r for r in rows if r["regime"] == "far"]
    assert max(r["initial_position_error"] for r in far) > 0.3  # far's own draw, not 0.3 m
    summary = write_outputs(rows, [*LATTICES, "gicp"], tmp_path)
    text = format_report(summary)
    assert "Regime far, truth pairs:" in text and "| gicp | 1 |" in text
    niche = summary["niche"]
    assert set(niche["regimes"]) == {"default", "far", "sparse"}
    assert niche["text"].startswith("The lattice matcher wins")
    for g, v in niche["regimes"].items():  # the sentence names each regime's outcome
        assert f"{g}: the lattice matcher {'wins' if v['lattice_wins'] else 'loses'}" in text
