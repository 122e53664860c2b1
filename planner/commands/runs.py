"""``planner match``, ``planner match-experiment`` (scan matching), ``planner bench``."""

from __future__ import annotations

import argparse


def match(a: argparse.Namespace) -> int:
    """Match the source scan to the reference; print the 4x4 transform."""
    from planner.match.cli_run import run_match  # lazy: numba, scipy

    return run_match(a.source, a.reference, lattice=a.lattice, cell_volume=a.cell_volume,
                     levels=a.levels, init=a.init, as_json=a.json)


def match_experiment(a: argparse.Namespace) -> int:
    """The paper's Fig. 6 (:mod:`planner.match.experiment`) into ``a.out``."""
    from planner.match.cli_run import run_match_experiment  # lazy: numba, scipy

    return run_match_experiment(a)


def bench(a: argparse.Namespace) -> int:
    """Run a suite into ``a.out``; 130 / 143 when stopped by SIGINT / SIGTERM."""
    from planner.bench.session import run_suite  # lazy: scipy

    return run_suite(a.suite, out=a.out, jobs=a.jobs, scheduler=a.scheduler, resume=a.resume,
                     progress=not a.no_progress, report_only=a.report_only,
                     force=a.force)
