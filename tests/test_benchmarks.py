"""Every script in ``benchmarks/`` runs in its smoke mode (``--smoke``: tiny sizes, a few
seconds): it exits 0, prints the harness's header and its ratio lines.

    python -m pytest --slow tests/test_benchmarks.py

A script whose prerequisite is absent (the shared data, a browser) prints one
``skipped: <reason>`` line instead of its ratios; the test then reports it as skipped
with that reason. Every script has a smoke mode (a new script without one fails here).
The scripts read only the package's public API (a fast test: no import of a private
module or name).
"""

from __future__ import annotations

import ast
import json
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
BENCH = ROOT / "benchmarks"
MODULES = {"harness.py"}  # imported by the scripts, not run
SCRIPTS = sorted(p.name for p in BENCH.glob("*.py") if p.name not in MODULES)
RATIO = re.compile(r"^ratio \S.*: ", re.M)


@pytest.mark.slow
@pytest.mark.parametrize("name", SCRIPTS)
def test_smoke_run(name):
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    out = subprocess.run([sys.executable, str(BENCH / name), "--smoke"], cwd=ROOT, env=env,
                         capture_output=True, text=True, timeout=600)
    assert out.returncode == 0, (out.stdout[-2000:], out.stderr[-4000:])
    assert "# machine: " in out.stdout and "# load average at end" in out.stdout, out.stdout
    skipped = re.search(r"^skipped: (.*)$", out.stdout, re.M)
    if skipped and not RATIO.search(out.stdout):
        pytest.skip(f"benchmarks/{name}: {skipped.group(1)}")
    assert RATIO.search(out.stdout), out.stdout[-3000:]


def test_every_script_has_a_smoke_mode():
    """A fast check of what the slow smoke runs need: each script takes ``--smoke``."""
    for name in SCRIPTS:
        src = (BENCH / name).read_text()
        assert '"--smoke"' in src or "add_arguments(" in src, (
            f"benchmarks/{name} has no --smoke mode (harness.add_arguments)")


def _private_imports(path: Path) -> list[str]:
    """The private planner names ``path`` imports (``planner._x``, ``planner.x._y``, or a
    ``_name`` from a planner module)."""
    out = []
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom) and (node.module or "").startswith("planner"):
            names = node.module.split(".") + [a.name for a in node.names]
            out += [f"{node.module}: {n}" for n in names if n.startswith("_")]
        elif isinstance(node, ast.Import):
            out += [a.name for a in node.names if a.name.startswith("planner")
                    and any(x.startswith("_") for x in a.name.split("."))]
    return out


@pytest.mark.parametrize("name", SCRIPTS + sorted(MODULES))
def test_reads_public_api_only(name):
    found = _private_imports(BENCH / name)
    assert not found, f"benchmarks/{name} imports private names: {found}"


@pytest.fixture
def bench_modules(monkeypatch):
    """The benchmarks folder importable (its scripts import ``harness`` as a sibling)."""
    monkeypatch.syspath_prepend(str(BENCH))
    import harness

    return harness


def test_interleaved_takes_turns_and_keeps_each_items_fastest_round(bench_modules):
    calls = []
    times = {"a": iter([3.0, 1.0, 2.0, 5.0, 4.0, 6.0]), "b": iter([9.0, 7.0, 8.0, 1.0, 2.0,
                                                                   3.0])}

    def side(name):
        def run(item):
            calls.append((name, item))
            return next(times[name])
        return run

    best = bench_modules.interleaved({"a": side("a"), "b": side("b")}, ["q0", "q1"], 3)
    assert calls[:4] == [("a", "q0"), ("b", "q0"), ("a", "q0"), ("b", "q0")]
    assert calls[-1] == ("b", "q1") and len(calls) == 12
    assert best["a"].tolist() == [1.0, 4.0] and best["b"].tolist() == [7.0, 1.0]


def test_ratio_line_reads_like_the_scripts_print_it(bench_modules):
    x = [2.0, 4.0, 6.0, 8.0, 2.0, 4.0]
    y = [1.0, 2.0, 3.0, 2.0, 1.0, 2.0]
    line = bench_modules.ratio_line("ours/floor", x, y, goal=">= 0.9")
    assert RATIO.match(line)
    assert line.startswith("ratio ours/floor: median 2 [95% CI 2, ")
    assert line.endswith("overall 2.36, n 6 (goal >= 0.9)")
    assert bench_modules.single_ratio("x", 3.0, 2.0) == "ratio x: 1.5"


def test_ratio_line_says_when_there_are_too_few_pairs_for_an_interval(bench_modules):
    # under 6 pairs the signed-rank interval is [0, inf]: printed as such it would read
    # like a measured range
    line = bench_modules.ratio_line("ours/floor", [2.0, 4.0, 6.0, 8.0], [1.0, 2.0, 3.0, 2.0])
    assert line == ("ratio ours/floor: median 2 [no 95% CI: too few pairs], overall 2.5, "
                    "n 4")


def test_traced_peak_sees_an_array_made_in_the_call(bench_modules):
    _, peak = bench_modules.traced_peak(lambda: np.ones(1 << 20).sum())
    assert peak >= 8 << 20


def test_floor_without_a_compiler_is_one_skipped_line(bench_modules, monkeypatch, capsys):
    import cpp_anchor

    monkeypatch.setattr(cpp_anchor.shutil, "which", lambda name: None)
    assert cpp_anchor.main(["--smoke"]) == 0
    out = capsys.readouterr().out
    assert "skipped: no C++ compiler" in out and not RATIO.search(out)


@pytest.mark.skipif(shutil.which("g++") is None and shutil.which("c++") is None,
                    reason="no C++ compiler")
def test_floor_agrees_with_our_search_on_a_small_map(bench_modules):
    """The floor in process: optimal costs equal to ours, the same expansions, and its axis
    permutation does not change a cost."""
    import cpp_anchor

    m = cpp_anchor.synthetic(n=24, seed=1, queries=6)
    row = cpp_anchor.compare(m, repeat=1)
    assert row.mismatches == 0 and row.checked == 6
    assert (row.exp_ours == row.exp_floor).all()
    res = cpp_anchor.run(m.free, m.queries)  # the map in its own order, a batch call
    assert np.allclose(res[:, 0], cpp_anchor.run(m.free.transpose(2, 1, 0),
                                                 m.queries[:, [2, 1, 0, 5, 4, 3]])[:, 0])
    assert (res[:, 1] > 0).all() and (res[:, 2] >= 0).all()


def test_plain_python_astar_finds_our_costs_under_either_tie_break(bench_modules):
    """``plateau.py``'s replay: any order among equal f keeps A* optimal, so the plain-Python
    A* finds the engine's cost under either tie-break."""
    import lattice_sight
    import search_speed

    from planner import search as S

    worlds = lattice_sight.map_worlds("narrow_passage", bench_modules.DATA)
    world = worlds["bcc"]
    ends = world.lattice.quantize(lattice_sight.query_points(worlds, 3).reshape(-1, 3))
    for start, goal in ends.reshape(-1, 2, 3):
        cost = S.search(world, start, goal).cost
        for tie in search_speed.TIES:
            got, expansions = search_speed.python_astar(world, start, goal, tie=tie)
            assert got == pytest.approx(cost, rel=1e-9) and expansions > 0, tie
    with pytest.raises(ValueError, match="tie must be one of"):
        search_speed.python_astar(world, start, goal, tie="smaller-g")


def _figures_block(h):
    print(h.ratio_line("ours/floor", [2.0, 4.0, 6.0, 8.0, 2.0, 4.0],
                       [1.0, 2.0, 3.0, 2.0, 1.0, 2.0], goal=">= 0.9"))
    print(h.single_ratio("a/b", 3.0, 2.0, note="medians"))
    h.record("floor/Simple", {"speed": np.float64(0.5), "long": float("nan"),
                              "n": np.int64(3)})


def _body(out: str) -> list[str]:
    """The printed lines but the header's and the end's (load and time vary)."""
    return [ln for ln in out.splitlines() if not ln.startswith("# ")]


def test_json_keeps_what_the_session_printed_and_prints_the_same(bench_modules, tmp_path,
                                                                  capsys):
    h = bench_modules
    with h.session("figures"):
        _figures_block(h)
    plain = capsys.readouterr().out
    path = tmp_path / "run.json"
    cmd = h.command_line("x.py", ["--json", "my run.json"])
    assert cmd == "python benchmarks/x.py --json 'my run.json'"
    with h.session("figures", json=path, command=cmd):
        _figures_block(h)
    assert _body(capsys.readouterr().out) == _body(plain)
    rec = json.loads(path.read_text())
    assert rec["command"] == cmd and rec["title"] == "figures" and rec["smoke"] is False
    assert rec["header"][0].startswith("machine: ") and " commit " in rec["header"][1]
    assert rec["end"].startswith("load average at end ")
    r = rec["ratios"]["ours/floor"]
    assert r["median"] == pytest.approx(2) and r["low"] == pytest.approx(2)
    assert r["n"] == 6 and r["goal"] == ">= 0.9" and r["high"] >= 2
    assert r["overall"] == pytest.approx(26 / 11)
    assert rec["ratios"]["a/b"] == {"value": 1.5, "goal": "", "note": "medians"}
    assert rec["figures"] == {"floor": {"Simple": {"speed": 0.5, "long": None, "n": 3}}}
    assert not list(tmp_path.glob(".*"))  # no temp file left


def test_json_is_not_written_when_the_run_fails_and_nothing_is_kept_outside(
        bench_modules, tmp_path, capsys):
    h = bench_modules
    path = tmp_path / "run.json"
    with pytest.raises(RuntimeError), h.session("figures", json=path):
        _figures_block(h)
        raise RuntimeError("the run broke")
    assert not path.exists() and h._record is None
    h.record("floor/Simple", {"speed": 1.0})  # outside a session: a no-op
    assert h._record is None


@pytest.mark.slow
def test_search_speed_json_on_a_smoke_run(tmp_path):
    from planner.analysis.speed_docs import load
    from planner.errors import PlannerError

    env = dict(os.environ, PYTHONPATH=str(ROOT))
    path = tmp_path / "speed.json"
    out = subprocess.run([sys.executable, str(BENCH / "search_speed.py"), "--smoke",
                          "--json", str(path)], cwd=ROOT, env=env, capture_output=True,
                         text=True, timeout=900)
    assert out.returncode == 0, out.stderr[-3000:]
    rec = json.loads(path.read_text())
    assert rec["smoke"] and rec["command"].startswith("python benchmarks/search_speed.py")
    figs = rec["figures"]
    assert {"fixed_cost", "sight", "plan", "anyangle"} <= set(figs)
    assert figs["sight"]["cubic"]["vs_cubic"] == 1.0 and "office" in figs["plan"]
    printed = RATIO.findall(out.stdout)
    assert len(rec["ratios"]) == len(printed)  # one entry per ratio line printed
    with pytest.raises(PlannerError, match="smoke run"):
        load(path)
