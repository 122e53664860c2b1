"""``planner match``: read two point files, match them, print the transform."""

from __future__ import annotations

import json
import sys

import numpy as np

from planner.errors import MapError, PlannerError
from planner.io import load_points
from planner.match import anchor
from planner.match.experiment import run_experiment, trial_methods
from planner.match.experiment_pairs import load_sources, user_pair
from planner.match.experiment_regimes import REGIMES, parse_regimes
from planner.match.experiment_report import format_report, write_outputs
from planner.match.matcher import match, pose_matrix

__all__ = ["run_match"]


def run_match(source: str, reference: str, *, lattice: str = "fcc", cell_volume: float = 0.001,
              levels: int = 4, init=None, as_json: bool = False) -> int:
    """Match ``source`` onto ``reference`` (any point format :func:`planner.io.load_points`
    reads) and print the 4x4 transform (row-major, metres), score, levels, iterations and
    time; JSON (key ``transform``) with ``as_json``. Returns the exit status (0)."""
    src, ref = _scan(source), _scan(reference)
    m0 = None if init is None else pose_matrix(init)
    res = match(src, ref, lattice=lattice, cell_volume=cell_volume, levels=levels, init=m0)
    if as_json:
        print(json.dumps(res.as_dict()))
        return 0
    with np.printoptions(precision=6, suppress=True):
        for row in res.transform:
            print(" ".join(f"{v: .6f}" for v in row))
    print(f"score {res.score} of {len(src)} source points ({res.fraction:.3f}); "
          f"levels {res.levels}; iterations {res.iterations}; {res.seconds:.3f} s")
    return 0


def _anchors(a) -> list[str]:
    """The anchors a run asks for (checked), or all of them when the extra is installed."""
    if a.no_icp:
        return []
    if a.anchors is not None:
        return [s for s in a.anchors.split(",") if s]
    if not anchor.available():
        print(f"planner: note: anchors left out, {anchor.EXTRA_MESSAGE}", file=sys.stderr)
        return []
    return list(anchor.ANCHORS)


def _scan(path: str) -> np.ndarray:
    """(N, 3) the points of a scan or map file (a bundled map by name too); a 2D map is
    refused in one line (the matching is 6-DOF)."""
    from planner.maps import resolve  # lazy: scipy

    pts = load_points(resolve(path))
    if pts.shape[1] != 3:
        raise MapError(f"{path}: a 2D map; scan matching needs 3D scans (6-DOF poses)")
    return pts


def run_match_experiment(a) -> int:
    """``planner match-experiment``: the pairs from ``a.sources`` (in ``a.data``) and
    ``a.pair`` triples, the trials of every regime
    (:func:`planner.match.experiment.run_experiment`), then the tables and verdicts on
    stdout and the outputs in ``a.out``. Returns 0."""
    names = [s for s in (a.sources or "").split(",") if s]
    anchors = _anchors(a)
    regimes = list(REGIMES) if a.regimes == "all" else a.regimes.split(",")
    parse_regimes(regimes)  # bad names refused before loading data
    methods = trial_methods(a.lattices.split(","), anchors)
    pairs = load_sources(names, a.data, seed=a.seed,
                         simulated_per_separation=a.simulated_pairs,
                         cell_volume=a.cell_volume, levels=a.levels)
    pairs += [user_pair(*p) for p in a.pair or []]
    if not pairs:
        raise PlannerError("no pairs: name --sources or give --pair SOURCE REFERENCE T.txt")
    rows = run_experiment(pairs, a.out, lattices=a.lattices.split(","), anchors=anchors,
                          regimes=regimes, trials=a.trials, cell_volume=a.cell_volume,
                          levels=a.levels, seed=a.seed, max_offset=a.max_offset,
                          max_angle=a.max_angle, resume=a.resume, force=a.force,
                          progress=not a.no_progress)
    summary = write_outputs(rows, methods, a.out, a.plot)
    print(format_report(summary), end="")
    print(f"{len(rows)} rows in {a.out}/trials.jsonl; table.md, summary.json, trials.csv "
          f"and {a.plot or str(a.out) + '/fig6.png'} written")
    return 0
