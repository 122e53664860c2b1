"""``planner match``: read two point files, match them, print the transform."""

from __future__ import annotations

import json

import numpy as np

from planner.io import load_points
from planner.match.matcher import match, pose_matrix

__all__ = ["run_match"]


def run_match(source: str, reference: str, *, lattice: str = "fcc", cell_volume: float = 0.001,
              levels: int = 4, init=None, as_json: bool = False) -> int:
    """Match ``source`` onto ``reference`` (any point format :func:`planner.io.load_points`
    reads) and print the 4x4 transform (row-major, metres), score, levels, iterations and
    time; JSON (key ``transform``) with ``as_json``. Returns the exit status (0)."""
    src, ref = load_points(source), load_points(reference)
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
