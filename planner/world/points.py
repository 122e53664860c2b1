"""Points as the world reads them: a start, a goal or a segment's end (m).

:func:`as_point` checks any input and names what is wrong; :func:`xyz` is the fast read of
the usual forms (a (3,) float64 array, a tuple or list of three reals) that a plan's
one-call path and a segment check take without building an array.
"""

from __future__ import annotations

import math

import numpy as np

from planner.errors import PlanError

__all__ = ["as_point", "fmt", "xyz"]

_P3, _F8 = (3,), np.dtype(np.float64)
_REAL = (float, int, np.float64)  # scalar types a point's coordinates are read from as-is


def xyz(p) -> list | tuple | None:
    """The three coordinates of point ``p`` as Python floats when it is a (3,) float64
    array, or a tuple or list of three Python (or numpy float64) reals, else None (any
    other input: :func:`as_point` checks it and names what is wrong)."""
    kind = type(p)
    if kind is np.ndarray:
        return p.tolist() if p.shape == _P3 and p.dtype == _F8 else None
    if (kind is tuple or kind is list) and len(p) == 3:
        a, b, c = p
        if type(a) in _REAL and type(b) in _REAL and type(c) in _REAL:
            try:
                return float(a), float(b), float(c)
            except OverflowError:  # an int beyond float range
                return None
    return None


def as_point(p, what: str = "point", dim: int = 3) -> np.ndarray:
    """``p`` as a finite (3,) float array (m); PlanError naming ``what`` otherwise. With
    ``dim`` 2, (x, y) is accepted too and becomes (x, y, 0)."""
    if type(p) is np.ndarray and p.shape == (3,) and p.dtype == np.float64:  # the usual case
        x, y, z = p.tolist()
        if math.isfinite(x) and math.isfinite(y) and math.isfinite(z):
            return p
    try:
        a = np.asarray(p, dtype=float).reshape(-1)
    except OverflowError:  # an integer beyond float range
        raise PlanError(f"{what} must be three finite numbers x, y, z, got "
                        f"{_show(p)}") from None
    except (TypeError, ValueError):
        raise PlanError(f"{what} must be three numbers x, y, z, got {_show(p)}") from None
    if dim == 2 and a.shape == (2,) and np.isfinite(a).all():
        a = np.append(a, 0.0)
    if a.shape != (3,) or not np.isfinite(a).all():
        raise PlanError(f"{what} must be three finite numbers x, y, z, got {_show(p)}")
    return a


def _show(p) -> str:
    """A value on one line for an error message: coordinates as :func:`fmt` prints them,
    anything else by its repr with the white space folded."""
    try:
        return fmt(np.asarray(p, dtype=float))
    except (TypeError, ValueError, OverflowError):
        return " ".join(repr(p).split())


def fmt(p: np.ndarray) -> str:
    return "(" + ", ".join(f"{v:.3f}" for v in np.asarray(p).reshape(-1)) + ")"
