"""Growing the engines' fixed-size kernel arrays between compiled calls."""

from __future__ import annotations

import numpy as np

__all__ = ["grown"]


def grown(a: np.ndarray, size: int, keep: int) -> np.ndarray:
    """A new array of ``size`` rows (``a``'s dtype and row shape) holding ``a[:keep]``."""
    b = np.empty((size, *a.shape[1:]), a.dtype)
    b[:keep] = a[:keep]
    return b
