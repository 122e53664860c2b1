"""Polyline helpers shared by planning results, the baseline and the benchmarks."""

from __future__ import annotations

import math

import numpy as np


def path_length(path: np.ndarray, empty: float = math.nan) -> float:
    """Length (m) of a polyline ``path`` of shape (K, d); ``empty`` when K < 2.

    >>> path_length(np.array([[0.0, 0, 0], [3, 4, 0], [3, 4, 1]]))
    6.0
    >>> path_length(np.zeros((1, 3)), empty=0.0)
    0.0
    """
    p = np.asarray(path, dtype=float)
    if len(p) < 2:
        return float(empty)
    return float(np.linalg.norm(np.diff(p, axis=0), axis=1).sum())
