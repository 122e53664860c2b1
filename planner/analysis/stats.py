"""Paired statistics for "lattice X vs cubic": one estimate, one interval and one p-value
that cannot disagree with each other.

Every comparison between lattices in the reports and the README goes through
:func:`paired_ratio`; :func:`describe` turns its numbers into the sentence a report prints,
and :meth:`PairedRatio.verdict` is the only place a direction is decided.

The statistic is the Hodges-Lehmann estimate of the per-query log ratios ``log(x_i/y_i)``
(the median of their Walsh averages), reported as a ratio. Its interval and p-value come
from one procedure, so that "the interval excludes 1" and "p <= alpha" are the same
statement and the direction is read off the interval:

- queries from one map x rotation (or each its own cluster): the Wilcoxon signed-rank test
  and the interval obtained by inverting it (order statistics of the Walsh averages at the
  test's critical value; exact null distribution up to :data:`EXACT_MAX` pairs, the normal
  approximation with continuity correction beyond). Pairs whose ratio is exactly 1 count
  against both directions (conservative).
- queries pooled from several clusters (map x rotation groups, whose queries share one
  world and are not independent): a cluster bootstrap of the same estimate (clusters
  resampled with replacement), the percentile interval, and the p-value of its inversion
  (twice the smaller share of resampled estimates on either side of 1).

Fewer than :data:`MIN_PAIRS` pairs (or :data:`MIN_CLUSTERS` clusters) give no verdict.

Examples
--------
Ten hand-checkable ratios, all below 1: every one of the 55 Walsh averages is negative, so
the exact two-sided signed-rank p is ``2 / 2**10``:

>>> import numpy as np
>>> x = np.array([5, 6, 7, 8, 9, 10, 11, 12, 13, 14.0])
>>> s = paired_ratio(x, 2 * x)
>>> s.n, round(s.estimate, 3), s.high < 1, round(s.p, 5), s.verdict()
(10, 0.5, True, 0.00195, 'lower')
>>> describe(s, "checks", less="fewer", more="more")[:20]
'fewer checks (Hodges'
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

__all__ = ["PairedRatio", "paired_ratio", "hodges_lehmann", "walsh_averages",
           "signed_rank_cdf", "describe", "format_p", "disagreement", "MIN_PAIRS",
           "MIN_CLUSTERS", "EXACT_MAX", "STATISTICS_NOTE"]

MIN_PAIRS = 10
"""Fewer pairs than this: "too few queries", no verdict."""
MIN_CLUSTERS = 5
"""Pooled samples with fewer map x rotation clusters than this: no verdict."""
EXACT_MAX = 400
"""Largest number of pairs for the exact signed-rank null distribution."""

STATISTICS_NOTE = (
    "Ratios are Hodges-Lehmann estimates of the per-query ratio against cubic with the "
    "same neighbours and method (median of the Walsh averages of the log ratios), on the "
    "queries every lattice solved with that neighbour set and method. Within one map x "
    "rotation the 95% interval and p-value "
    "come from the Wilcoxon signed-rank test (interval by inverting the test); pooled over "
    "several map x rotation groups, from a cluster bootstrap that resamples whole groups "
    f"(percentile interval, p by inverting it). The interval excludes 1 exactly when "
    f"p <= 0.05, and the direction is read off it; fewer than {MIN_PAIRS} queries or "
    f"{MIN_CLUSTERS} groups: no verdict.")
"""One paragraph naming the statistics, for reports and results pages."""


@dataclass(frozen=True)
class PairedRatio:
    """Summary of per-query ratios ``x_i / y_i``.

    Attributes
    ----------
    n : int
        Pairs with both values finite and positive.
    estimate : float
        Hodges-Lehmann estimate of the ratio: exp of the median of the Walsh averages of
        the log ratios (for symmetric log ratios, their median).
    low, high : float
        Interval at ``level``, matched to ``p`` (module docstring); 0 and inf when the
        sample is too small for any interval at that level.
    p : float
        Two-sided p-value of "ratio 1" by the same procedure (NaN with no pairs).
    level : float
        Confidence level of the interval.
    clusters : int
        Map x rotation groups the pairs come from (0 when not given).
    method : str
        ``"wilcoxon"`` or ``"cluster bootstrap"``.
    """

    n: int
    estimate: float
    low: float
    high: float
    p: float
    level: float = 0.95
    clusters: int = 0
    method: str = "wilcoxon"

    @property
    def too_few(self) -> bool:
        """Too few pairs (or clusters) for a verdict."""
        return self.n < MIN_PAIRS or (self.method == "cluster bootstrap"
                                      and self.clusters < MIN_CLUSTERS)

    def verdict(self) -> str:
        """``"lower"`` / ``"higher"`` (the interval lies below / above 1, i.e. p <= 1 -
        level), ``"same"`` (it contains 1) or ``"too few"``."""
        if self.too_few or not math.isfinite(self.estimate):
            return "too few"
        if self.high < 1.0:
            return "lower"
        if self.low > 1.0:
            return "higher"
        return "same"

    def significant(self) -> bool:
        """The verdict is a direction."""
        return self.verdict() in ("lower", "higher")

    def to_dict(self) -> dict:
        return {"n": self.n, "estimate": self.estimate, "ci_low": self.low,
                "ci_high": self.high, "p": self.p, "level": self.level,
                "clusters": self.clusters, "method": self.method,
                "verdict": self.verdict()}


def walsh_averages(d: np.ndarray) -> np.ndarray:
    """All ``(d_i + d_j) / 2`` for ``i <= j``, sorted: shape (n (n + 1) / 2,).

    >>> walsh_averages(np.array([1.0, 3.0])).tolist()
    [1.0, 2.0, 3.0]
    """
    d = np.asarray(d, dtype=float).ravel()
    i, j = np.triu_indices(len(d))
    return np.sort(0.5 * (d[i] + d[j]))


def hodges_lehmann(d: np.ndarray) -> float:
    """Median of the Walsh averages of ``d`` (shape (n,), n >= 1).

    >>> hodges_lehmann(np.array([0.0, 1.0, 5.0]))   # of 0, 0.5, 1, 2.5, 3, 5
    1.75
    """
    return float(np.median(walsh_averages(d)))


@functools.cache
def _exact_cdf(n: int) -> np.ndarray:
    p = np.zeros(n * (n + 1) // 2 + 1)
    p[0] = 1.0
    top = 0
    for k in range(1, n + 1):  # rank k is positive or negative with probability 1/2
        p[k:top + k + 1] += p[:top + 1].copy()
        p[:top + k + 1] *= 0.5
        top += k
    return np.minimum(np.cumsum(p), 1.0)


def signed_rank_cdf(n: int) -> np.ndarray:
    """``P(T <= t)`` for t = 0 .. n (n + 1) / 2, T the signed-rank statistic of n pairs
    under "no difference": exact up to :data:`EXACT_MAX`, else normal with continuity
    correction.

    >>> signed_rank_cdf(3).round(3).tolist()   # T's 8 outcomes: 0,1,2,3,3,4,5,6
    [0.125, 0.25, 0.375, 0.625, 0.75, 0.875, 1.0]
    """
    if n <= EXACT_MAX:
        return _exact_cdf(n)
    from scipy.stats import norm

    m = n * (n + 1) / 2
    sd = math.sqrt(n * (n + 1) * (2 * n + 1) / 24)
    return norm.cdf((np.arange(int(m) + 1) + 0.5 - m / 2) / sd)


def _wilcoxon(d: np.ndarray, level: float) -> tuple[float, float, float]:
    """(low, high, p) of the log ratios ``d``: the signed-rank interval and its p."""
    w = walsh_averages(d)
    cdf = signed_rank_cdf(len(d))
    alpha = 1.0 - level
    k = int(np.searchsorted(cdf, alpha / 2 * (1 + 1e-12), side="right"))  # cdf[t] <= a/2
    low, high = (-math.inf, math.inf) if k == 0 else (float(w[k - 1]), float(w[-k]))
    below, above = int(np.sum(w <= 0)), int(np.sum(w >= 0))
    p = min(1.0, 2.0 * float(min(cdf[below], cdf[above])))
    return low, high, p


def _cluster_bootstrap(d: np.ndarray, labels: np.ndarray, n_boot: int, level: float,
                       seed: int) -> tuple[float, float, float]:
    """(low, high, p) of the Hodges-Lehmann estimate of ``d`` by resampling whole
    clusters (``labels``, shape (n,)): percentile interval and its inversion."""
    _, inv = np.unique(labels, return_inverse=True)
    n_groups = int(inv.max()) + 1
    rng = np.random.default_rng(seed)
    picks = rng.integers(0, n_groups, size=(n_boot, n_groups))
    counts = np.zeros((n_boot, n_groups))
    np.add.at(counts, (np.arange(n_boot)[:, None], picks), 1.0)
    boot = np.empty(n_boot)
    chunk = max(1, int(2e6 // len(d)))
    for a in range(0, n_boot, chunk):
        boot[a:a + chunk] = _weighted_hl(d, counts[a:a + chunk][:, inv])
    boot.sort()
    k = int(math.floor(n_boot * (1.0 - level) / 2 + 1e-9))
    low, high = float(boot[k]), float(boot[n_boot - 1 - k])
    p = min(1.0, 2.0 * min(int(np.sum(boot <= 0)), int(np.sum(boot >= 0))) / n_boot)
    return low, high, p


def _weighted_hl(d: np.ndarray, w: np.ndarray) -> np.ndarray:
    """Hodges-Lehmann estimates of resamples that hold pair i ``w[b, i]`` times (w: shape
    (B, n), integers as floats): (B,).

    A resample's Walsh averages are the sample's with weights ``w_i w_j`` (i < j) and
    ``w_i (w_i + 1) / 2`` (i = j), so the weight of those <= v is
    ``(sum_i w_i W(2 v - d_i) + W(v)) / 2`` with ``W(t)`` the weight of the d_j <= t: a
    bisection over the sample's sorted Walsh averages finds each resample's two middle
    ranks without building the resample (O(B n log n) per step).
    """
    order = np.argsort(d, kind="stable")
    ds, w = d[order], w[:, order]
    cum = np.concatenate([np.zeros((len(w), 1)), np.cumsum(w, axis=1)], axis=1)
    walsh = walsh_averages(ds)
    tol = 1e-12 * (1.0 + float(np.abs(ds).max()))
    rows = np.arange(len(w))[:, None]

    def weight_le(v: np.ndarray) -> np.ndarray:
        pos = np.searchsorted(ds, (2.0 * v[:, None] - ds[None, :] + tol).ravel(),
                              side="right").reshape(w.shape)
        own = cum[rows[:, 0], np.searchsorted(ds, v + tol, side="right")]
        return 0.5 * (np.sum(w * cum[rows, pos], axis=1) + own)

    total = weight_le(np.full(len(w), walsh[-1]))

    def at_rank(k: np.ndarray) -> np.ndarray:  # smallest Walsh average with weight_le > k
        lo, hi = np.zeros(len(w), dtype=np.int64), np.full(len(w), len(walsh) - 1)
        while np.any(lo < hi):
            mid = (lo + hi) // 2
            above = weight_le(walsh[mid]) > k
            hi = np.where(above, mid, hi)
            lo = np.where(above, lo, mid + 1)
        return walsh[lo]

    return 0.5 * (at_rank(np.floor((total - 1) / 2)) + at_rank(np.floor(total / 2)))


def paired_ratio(x, y, *, clusters=None, n_boot: int = 2000, level: float = 0.95,
                 seed: int = 0) -> PairedRatio:
    """Hodges-Lehmann ratio of paired measurements ``x / y`` with its matched interval and
    p-value (module docstring).

    Parameters
    ----------
    x, y : array_like, shape (N,)
        Paired measurements of the same queries (e.g. cell checks on FCC and on cubic).
        Pairs where either value is not finite or not positive are left out (a failed
        query has no length to compare).
    clusters : array_like, shape (N,), optional
        Group label per pair (map x rotation). With more than one group, and some group
        holding more than one pair, the interval is a cluster bootstrap.
    n_boot : int
        Cluster bootstrap resamples.
    level : float
        Confidence level of the interval.
    seed : int
        Seed of the resampling, so a report is reproducible.

    Returns
    -------
    PairedRatio
    """
    x = np.asarray(x, dtype=float).ravel()
    y = np.asarray(y, dtype=float).ravel()
    if x.shape != y.shape:
        raise ValueError(f"paired samples differ in length: {x.size} and {y.size}")
    ok = np.isfinite(x) & np.isfinite(y) & (x > 0) & (y > 0)
    d = np.log(x[ok]) - np.log(y[ok])
    n = int(d.size)
    labels = None if clusters is None else np.asarray(
        [str(c) for c in np.asarray(clusters, dtype=object).ravel()])
    if labels is not None and labels.shape != x.shape:
        raise ValueError(f"clusters: {labels.size} labels for {x.size} pairs")
    if n == 0:
        return PairedRatio(0, math.nan, math.nan, math.nan, math.nan, level, 0)
    g = 0 if labels is None else len(set(labels[ok]))
    est = hodges_lehmann(d)
    if 1 < g < n:
        low, high, p = _cluster_bootstrap(d, labels[ok], n_boot, level, seed)
        method = "cluster bootstrap"
    else:
        low, high, p = _wilcoxon(d, level)
        method = "wilcoxon"
    return PairedRatio(n, math.exp(est), math.exp(low), math.exp(high), p, level, g, method)


def format_p(p: float) -> str:
    """``p < 0.001``, ``p = 0.03`` or ``p n/a``."""
    if not math.isfinite(p):
        return "p n/a"
    if p < 0.001:
        return "p < 0.001"
    return f"p = {p:.2g}" if p < 0.1 else f"p = {p:.2f}"


def _num(v: float) -> str:
    if v == 0 or not math.isfinite(v):
        return "0" if v == 0 else "inf"
    return f"{v:.3g}"


def numbers(s: PairedRatio) -> str:
    """``"0.59 [0.55, 0.63], p < 0.001, n = 120"`` (and the clusters when pooled)."""
    cl = f", {s.clusters} map x rotation groups" if s.method == "cluster bootstrap" else ""
    return (f"{_num(s.estimate)} [{_num(s.low)}, {_num(s.high)}], {format_p(s.p)}, "
            f"n = {s.n}{cl}")


def describe(s: PairedRatio, what: str, *, less: str = "lower", more: str = "higher") -> str:
    """One sentence fragment for a report, generated from :meth:`PairedRatio.verdict`.

    ``"fewer checks (Hodges-Lehmann ratio 0.59 [0.55, 0.63], p < 0.001, n = 120)"``;
    ``"no clear difference in checks (...)"``; ``"too few queries to compare checks
    (...)"``.
    """
    if s.n == 0:
        return f"no paired {what} to compare"
    nums = f"Hodges-Lehmann ratio {numbers(s)}"
    v = s.verdict()
    if v == "too few":
        unit = ("groups" if s.n >= MIN_PAIRS else "queries")
        return f"too few {unit} to compare {what} ({nums})"
    if v == "same":
        return f"no clear difference in {what} ({nums})"
    return f"{less if v == 'lower' else more} {what} ({nums})"


def disagreement(checks: PairedRatio, time: PairedRatio, who: str, *,
                 time_name: str = "time") -> str | None:
    """One sentence when the checks and the time verdicts point opposite ways (each
    interval excludes 1, on opposite sides), else None."""
    a, b = checks.verdict(), time.verdict()
    if {a, b} != {"lower", "higher"}:
        return None
    c_word = "fewer" if a == "lower" else "more"
    t_word = "less" if b == "lower" else "more"
    return (f"Checks and {time_name} disagree: {who} makes {c_word} cell checks than cubic "
            f"({_num(checks.estimate)}x [{_num(checks.low)}, {_num(checks.high)}]) but takes "
            f"{t_word} {time_name} ({_num(time.estimate)}x [{_num(time.low)}, "
            f"{_num(time.high)}]).")
