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
