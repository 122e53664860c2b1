"""The paper's lattices: unit-determinant generators (eqs. 8-12) and off-by-one sets (eqs. 3-7).

``NAMED_LATTICES`` is the one list of lattice names the package accepts by name.
"""

from __future__ import annotations

import itertools
import math

import numpy as np

from planner.errors import LatticeError

__all__ = ["NAMED_LATTICES", "NAMED_LATTICES_2D", "PAPER_DELTAS", "named_generator"]

NAMED_LATTICES: tuple[str, ...] = ("cubic", "bcc", "fcc", "mcc", "hex")
NAMED_LATTICES_2D: tuple[str, ...] = ("square", "hex2d")  # for 2D maps (ROS map_server)


def named_generator(name: str) -> np.ndarray:
    """Unit-determinant generator of a named lattice (paper section II-A, eqs. 8-12).

    The paper prints 4-digit values; these are the exact forms they round:
    BCC ``a = 2**(1/3)``, FCC ``b = 2**(-1/3)``, hex side ``sqrt(2) h`` with
    ``h = 3**(-1/6)``, and MCC the upper Cholesky factor of its Gram matrix
    ``((1+s, -1, 1-s), (-1, 1+s, -1), (1-s, -1, 1+s)) / 2`` with ``s = sqrt(2)``.

    ``square`` and ``hex2d`` are the 2D square and hexagonal lattices (for 2D maps).

    Returns
    -------
    ndarray, shape (3, 3) or (2, 2)
        Columns are the basis vectors; ``|det| == 1``.

    Examples
    --------
    >>> round(abs(float(np.linalg.det(named_generator("fcc")))), 12)
    1.0
    """
    key = name.lower() if isinstance(name, str) else name
    if key == "cubic":
        return np.eye(3)
    if key == "bcc":
        a = 2.0 ** (1 / 3)
        return np.array([[a, 0, a / 2], [0, a, a / 2], [0, 0, a / 2]])
    if key == "fcc":
        b = 2.0 ** (-1 / 3)
        return np.array([[2 * b, b, 0], [0, -b, b], [0, 0, -b]])
    if key == "mcc":
        s = math.sqrt(2.0)
        gram = 0.5 * np.array([[1 + s, -1, 1 - s], [-1, 1 + s, -1], [1 - s, -1, 1 + s]])
        return np.linalg.cholesky(gram).T
    if key == "hex":
        h = 3.0 ** (-1 / 6)
        a = math.sqrt(2.0) * h
        return np.array([[a, -a / 2, 0], [0, a * math.sqrt(3) / 2, 0], [0, 0, h]])
    if key == "square":
        return np.eye(2)
    if key == "hex2d":  # the hexagonal (triangular) lattice, unit area
        a = math.sqrt(2 / math.sqrt(3))
        return np.array([[a, a / 2], [0, a * math.sqrt(3) / 2]])
    names = ", ".join(NAMED_LATTICES + NAMED_LATTICES_2D)
    raise LatticeError(f"unknown lattice name {name!r}; expected one of {names}")


# The paper's off-by-one sets, eqs. (3)-(7), as index offsets in the paper's generators.
# Kept to test and report whether they suffice (they do not all: see Lattice.rounding_offsets).
def _pm(cols: list[tuple[int, int, int]]) -> np.ndarray:
    a = np.array(cols, dtype=np.int64)
    return np.concatenate([a, -a])


PAPER_DELTAS: dict[str, np.ndarray] = {
    "cubic": np.array(
        [p for p in itertools.product((-1, 0, 1), repeat=3) if any(p)], dtype=np.int64
    ),
    "fcc": _pm([(1, -2, -1), (0, -1, -1), (1, -1, -1), (0, 0, -1), (0, -1, 0), (1, -1, 0)]),
    "bcc": _pm(
        [(1, 1, -2), (0, 0, -1), (1, 0, -1), (0, 1, -1), (1, 1, -1), (0, -1, 0), (-1, 0, 0)]
    ),
    "mcc": _pm(
        [(-1, -1, -1), (0, -1, -1), (-1, 0, -1), (0, 0, -1), (-1, -1, 0), (0, -1, 0), (-1, 0, 0)]
    ),
    "hex": _pm(
        [(0, -1, -1), (-1, 0, -1), (0, 0, -1), (1, 0, -1), (0, 1, -1), (1, 1, -1), (-1, -1, 0),
         (0, -1, 0)]
    ),
}
