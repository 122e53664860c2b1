"""Progress of long commands: a live line with an ETA on a terminal, sparse lines in a log."""

from __future__ import annotations

import io

from planner.progress import Progress, format_seconds


class Tty(io.StringIO):
    def isatty(self):
        return True


class Clock:
    def __init__(self):
        self.t = 0.0

    def __call__(self):
        return self.t


def test_a_terminal_gets_one_live_line_with_done_total_and_eta():
    out, clock = Tty(), Clock()
    with Progress(4, "queries", label="sampling", stream=out, clock=clock) as bar:
        for _ in range(2):
            clock.t += 10
            bar.step()
    text = out.getvalue()
    frames = text.split("\r")[1:]
    assert len(frames) == 2 and text.endswith("\n") and text.count("\n") == 1
    # half the work in 20 s: 20 s left
    assert "sampling 2/4 queries" in frames[-1] and "eta 20s" in frames[-1]


def test_a_log_gets_a_line_per_tenth_and_nothing_redrawn():
    out, clock = io.StringIO(), Clock()
    bar = Progress(200, "runs", stream=out, clock=clock, quiet=0)
    for _ in range(200):
        clock.t += 0.01
        bar.step()
    bar.close()
    lines = out.getvalue().splitlines()
    assert "\r" not in out.getvalue() and len(lines) == 10
    assert lines[-1].startswith("progress 100%") and "200/200 runs" in lines[-1]


def test_a_slow_step_in_a_log_still_reports_every_interval():
    out, clock = io.StringIO(), Clock()
    bar = Progress(1000, "rotations", stream=out, clock=clock, every=30, quiet=0)
    for _ in range(3):  # 0.3% of the work, 90 s
        clock.t += 30
        bar.step()
    assert len(out.getvalue().splitlines()) == 3


def test_a_short_run_in_a_log_stays_silent():
    out, clock = io.StringIO(), Clock()
    with Progress(5, "plans", stream=out, clock=clock, quiet=5) as bar:
        for _ in range(5):
            clock.t += 0.5
            bar.step()
    assert out.getvalue() == ""


def test_disabled_progress_prints_nothing_even_on_a_terminal():
    out = Tty()
    with Progress(3, enabled=False, stream=out) as bar:
        bar.step(3)
    assert out.getvalue() == ""


def test_durations_read_as_minutes_and_hours():
    assert [format_seconds(s) for s in (0, 59.4, 185, 7620)] == ["0s", "59s", "3m05s",
                                                                 "2h07m"]


# -- the long commands report through it ---------------------------------------------------------
def _frames(tty: Tty) -> list[str]:
    return [f for f in tty.getvalue().replace("\n", "\r").split("\r") if f.strip()]


def test_compare_shows_the_lattice_plans_done_and_an_eta_on_a_terminal(monkeypatch):
    import sys

    from planner.analysis.compare import compare

    tty = Tty()
    monkeypatch.setattr(sys, "stderr", tty)
    compare("office", lattices=["cubic", "fcc"], cell_volume=0.03, radius=0.2,
            start=[2.5, 2.5, 1.2], goal=[18.3, 10.5, 1.2])
    frames = _frames(tty)
    assert any("cubic 0/2 plans" in f for f in frames)  # shown while cubic's world is built
    assert "fcc 2/2 plans" in frames[-1] and "eta 0s" in frames[-1]
    assert tty.getvalue().endswith("\n")  # a message printed next starts on its own line


def test_explore_counts_moves_against_the_plan_left(monkeypatch):
    import sys

    from planner.explore import explore

    tty = Tty()
    monkeypatch.setattr(sys, "stderr", tty)
    res = explore("office", [2.5, 2.5, 1.2], [18.3, 10.5, 1.2], lattice="bcc", sensor_range=3,
                  resolution=10, fov=(360, 10), max_steps=6, progress=True)
    last = _frames(tty)[-1]
    assert res.status == "budget" and "exploring on bcc 6/" in last and "moves" in last
    total = int(last.split("6/")[1].split()[0])
    assert total > 6  # the goal is further than six moves away


def test_the_suite_shows_the_worlds_it_builds_to_sample_queries(monkeypatch, tmp_path):
    import sys

    from planner.bench.suite import load_suite
    from planner.bench.tasks import plan_tasks
    from planner.maps import map_path

    suite = tmp_path / "s.toml"
    suite.write_text(f'name = "s"\nqueries = 2\nlattices = ["cubic", "fcc"]\n'
                     f'neighbors = ["face"]\nmethods = ["astar"]\n\n[[maps]]\n'
                     f'path = "{map_path("office").as_posix()}"\ncell_volumes = [0.03]\n'
                     f'radii = [0.2, 0.3]\n')
    tty, said = Tty(), []
    monkeypatch.setattr(sys, "stderr", tty)
    _, record = plan_tasks(load_suite(str(suite)), log=said.append, progress=True)
    assert len(record) == 2 and len(said) == 2
    frames = _frames(tty)
    assert "sampling queries 4/4 worlds" in frames[-1]
    # the log's lines do not land inside the live line: it is cleared before each one
    assert tty.getvalue().count("\r\033[K") >= 1


def test_stats_fig5_rotations_are_counted(monkeypatch, tmp_path):
    import sys

    import numpy as np

    from planner.analysis.paper import rotation_experiment

    tty = Tty()
    monkeypatch.setattr(sys, "stderr", tty)
    pts = np.random.default_rng(0).uniform(0, 2, (500, 3))
    rotation_experiment(tmp_path, {"scan": pts}, [0.125, 0.05], 3, 0)
    assert "Fig. 5 6/6 rotations" in _frames(tty)[-1]
    tty2 = Tty()
    monkeypatch.setattr(sys, "stderr", tty2)
    rotation_experiment(tmp_path, {"scan": pts}, [0.125, 0.05], 4, 0)  # resumed: 2 new
    assert "Fig. 5 2/2 rotations" in _frames(tty2)[-1]
