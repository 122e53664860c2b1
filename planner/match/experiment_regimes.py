"""Regimes of the scan-matching experiment: how far the start is and what each scan keeps.

* ``default``: the paper's setting, initial errors up to 0.5 m and 10 degrees, whole scans;
* ``far``: initial errors up to 2 m and 45 degrees, whole scans; the lattice matcher gets two
  more levels (its coarsest cell must be comparable to the initial error: 0.1 m cells and 6
  levels give 3.2 m), the registration anchors run as configured;
* ``overlap``: low overlap, the default's initial errors; both scans are cut by one plane
  with a random normal: in the reference's frame (the source mapped by the known or
  centre transform) the reference keeps its points below the plane's 70th percentile and
  the source its points above the 30th percentile of the pair's positions along the normal,
  so about 40% of each scan lies in the shared slab;
* ``sparse``: the default's initial errors, each scan randomly thinned to 2,000 points.

The cut and the thinning draw from ``numpy.random.default_rng([seed, pair, index, code])``
(``code`` the regime's position in :data:`REGIMES`), so every method sees the same scans.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from scipy.spatial.transform import Rotation

from planner.errors import PlannerError

__all__ = ["REGIMES", "Regime", "parse_regimes", "regime_scans"]


class Regime(NamedTuple):
    """One regime (see the module).

    Attributes
    ----------
    name : str
    max_offset, max_angle : float
        Largest initial position (m) and rotation (degrees) error.
    keep : float or None
        Overlap cut: the percentile split (0.7 keeps about 40% shared); None: whole scans.
    points : int or None
        Points kept per scan; None: all.
    extra_levels : int
        Levels added to the lattice matcher's.
    """

    name: str
    max_offset: float
    max_angle: float
    keep: float | None = None
    points: int | None = None
    extra_levels: int = 0


REGIMES: dict[str, Regime] = {
    "default": Regime("default", 0.5, 10.0),
    "far": Regime("far", 2.0, 45.0, extra_levels=2),
    "overlap": Regime("overlap", 0.5, 10.0, keep=0.7),
    "sparse": Regime("sparse", 0.5, 10.0, points=2000),
}


def parse_regimes(names: list[str], max_offset: float = 0.5, max_angle: float = 10.0
                  ) -> list[Regime]:
    """The named regimes in :data:`REGIMES` order; ``default`` with the given initial
    errors. :class:`PlannerError` on an unknown or missing name."""
    bad = [n for n in names if n not in REGIMES]
    if bad or not names:
        raise PlannerError(f"unknown regime {bad[0] if bad else '(none)'!r}: choose from "
                           f"{', '.join(REGIMES)}")
    out = [REGIMES[n] for n in REGIMES if n in names]
    return [r._replace(max_offset=max_offset, max_angle=max_angle) if r.name == "default"
            else r for r in out]


def regime_scans(regime: Regime, source: np.ndarray, reference: np.ndarray,
                 transform: np.ndarray, seed: int, pair: int, index: int
                 ) -> tuple[np.ndarray, np.ndarray]:
    """The source ((N, 3), m) and reference ((M, 3), m) as the regime's trial sees them;
    ``transform`` is the pair's source -> reference 4x4."""
    if regime.keep is None and regime.points is None:
        return source, reference
    code = list(REGIMES).index(regime.name)
    rng = np.random.default_rng([seed, pair, index, code])
    if regime.keep is not None:
        normal = Rotation.random(random_state=rng).apply([1.0, 0.0, 0.0])
        s = (source @ transform[:3, :3].T + transform[:3, 3]) @ normal
        r = reference @ normal
        both = np.concatenate([s, r])
        lo, hi = np.quantile(both, [1 - regime.keep, regime.keep])
        source, reference = source[s >= lo], reference[r <= hi]
    if regime.points is not None:
        if len(source) > regime.points:
            source = source[np.sort(rng.choice(len(source), regime.points, replace=False))]
        if len(reference) > regime.points:
            reference = reference[np.sort(rng.choice(len(reference), regime.points,
                                                     replace=False))]
    return np.ascontiguousarray(source), np.ascontiguousarray(reference)
