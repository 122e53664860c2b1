"""Paired statistics for "lattice X vs cubic": median ratio, BCa bootstrap interval
(:func:`scipy.stats.bootstrap`), Wilcoxon test.

Every comparison between lattices in the reports and the README goes through
:func:`paired_ratio`, so that a claim always carries its interval and its test, and
:func:`describe` turns the numbers into the sentence that the report prints.

Examples
--------
>>> import numpy as np
>>> rng = np.random.default_rng(0)
>>> cubic = rng.uniform(100, 200, size=60)
>>> fcc = cubic * rng.uniform(0.5, 0.7, size=60)      # ~40% fewer checks per query
>>> s = paired_ratio(fcc, cubic, seed=1)
>>> s.n, round(s.median, 2), s.low < s.median < s.high, s.p < 0.001
(60, 0.62, True, True)
>>> describe(s, "checks", less="fewer", more="more")[:20]
'fewer checks (median'
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["PairedRatio", "paired_ratio", "median_interval", "describe", "format_p"]


@dataclass(frozen=True)
class PairedRatio:
    """Summary of per-query ratios ``x_i / y_i``.

    Attributes
    ----------
    n : int
        Number of pairs with both values finite and positive.
    median : float
        Median of the per-query ratios.
    low, high : float
        Bootstrap interval of the median (``level``, default 95%): bias-corrected and
        accelerated (BCa) over resampled queries.  When every ratio is the same, both equal
        the median; with fewer than 3 pairs they are the smallest and largest ratio (the
        range every resample's median falls in); when BCa is undefined (the resampled
        medians barely vary) they are the resamples' percentiles.
    p : float
        Two-sided Wilcoxon signed-rank p-value of ``log(x_i / y_i)`` against 0 (NaN when
        fewer than 2 pairs differ).
    level : float
        Confidence level of the interval.
    """

    n: int
    median: float
    low: float
    high: float
    p: float
    level: float = 0.95

    def significant(self, alpha: float = 0.05) -> bool:
        """True when the Wilcoxon test rejects "no difference" at ``alpha``."""
        return bool(self.p < alpha)

    def to_dict(self) -> dict:
        return {"n": self.n, "median": self.median, "ci_low": self.low,
                "ci_high": self.high, "p": self.p, "level": self.level}


def paired_ratio(x, y, *, n_boot: int = 5000, level: float = 0.95,
                 seed: int = 0) -> PairedRatio:
    """Median of the paired ratios ``x / y`` with a BCa bootstrap interval and a Wilcoxon
    test.

    The pairs stay pairs: the queries are resampled, each with its own ratio.

    Parameters
    ----------
    x, y : array_like, shape (N,)
        Paired measurements of the same queries (e.g. cell checks on FCC and on cubic).
        Pairs where either value is not finite or not positive are left out (a failed
        query has no length to compare).
    n_boot : int
        Bootstrap resamples of the pairs.
    level : float
        Confidence level of the interval.
    seed : int
        Seed of the resampling, so a report is reproducible.

    Returns
    -------
    PairedRatio
    """
    from scipy.stats import wilcoxon

    x = np.asarray(x, dtype=float).ravel()
    y = np.asarray(y, dtype=float).ravel()
    if x.shape != y.shape:
        raise ValueError(f"paired samples differ in length: {x.size} and {y.size}")
    ok = np.isfinite(x) & np.isfinite(y) & (x > 0) & (y > 0)
    r = x[ok] / y[ok]
    n = int(r.size)
    if n == 0:
        return PairedRatio(0, math.nan, math.nan, math.nan, math.nan, level)
    med = float(np.median(r))
    low, high = median_interval(r, n_boot=n_boot, level=level, seed=seed)
    logr = np.log(r)
    if np.count_nonzero(np.abs(logr) > 1e-12) < 2:
        p = math.nan if n < 2 else 1.0
    else:
        p = float(wilcoxon(logr, zero_method="zsplit").pvalue)
    return PairedRatio(n, med, low, high, p, level)


def median_interval(r: np.ndarray, *, n_boot: int = 5000, level: float = 0.95,
                    seed: int = 0) -> tuple[float, float]:
    """BCa bootstrap interval of the median of ``r`` (shape (N,), N >= 1, finite).

    Degenerate samples get a definite answer, never NaN or a warning: all equal (or N = 1),
    the median itself; N = 2, the two values; a BCa interval that is undefined because the
    resampled medians (nearly) never differ from the sample's, their percentile interval.
    """
    import warnings

    from scipy.stats import bootstrap

    r = np.asarray(r, dtype=float).ravel()
    if r.size == 1 or np.all(r == r[0]):
        return float(r[0]), float(r[0])
    if r.size < 3:
        return float(r.min()), float(r.max())
    with warnings.catch_warnings():  # the degenerate cases are handled below
        warnings.simplefilter("ignore")
        res = bootstrap((r,), np.median, n_resamples=n_boot, confidence_level=level,
                        method="BCa", vectorized=True, axis=-1, batch=1000,
                        rng=np.random.default_rng(seed))
    low, high = float(res.confidence_interval.low), float(res.confidence_interval.high)
    if not (math.isfinite(low) and math.isfinite(high)):
        alpha = (1.0 - level) / 2.0
        low, high = (float(v) for v in np.quantile(res.bootstrap_distribution,
                                                   [alpha, 1.0 - alpha]))
    return low, high


def format_p(p: float) -> str:
    """``p < 0.001``, ``p = 0.03`` or ``p n/a``."""
    if not math.isfinite(p):
        return "p n/a"
    if p < 0.001:
        return "p < 0.001"
    return f"p = {p:.2g}" if p < 0.1 else f"p = {p:.2f}"


def describe(s: PairedRatio, what: str, *, less: str = "lower", more: str = "higher",
             alpha: float = 0.05) -> str:
    """One sentence fragment for a report, generated from the numbers.

    ``"fewer checks (median 0.59, 95% CI 0.55-0.63, p < 0.001, n = 120)"`` when the test
    is significant, else ``"no significant difference in checks (median 0.98, ...)"``.
    """
    if s.n == 0:
        return f"no paired {what} to compare"
    nums = (f"median {s.median:.3g}, {round(s.level * 100)}% CI {s.low:.3g}-{s.high:.3g}, "
            f"{format_p(s.p)}, n = {s.n}")
    if not s.significant(alpha):
        return f"no significant difference in {what} ({nums})"
    word = less if s.median < 1 else more
    return f"{word} {what} ({nums})"
