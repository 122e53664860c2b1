"""Paired comparisons "lattice X vs cubic" over benchmark rows, with intervals and tests.

Every ratio here is a Hodges-Lehmann ratio of per-query values
(:func:`planner.analysis.stats.paired_ratio`) between a lattice and cubic with the same
neighbour set and method on the same query (same map, cell volume, radius and rotation), so
maps of very different sizes never mix in one ratio, on the queries that every lattice of
the run solved with that neighbour set and method (a lattice that blocks or cannot connect
a query shows in the success columns, not as a missing pair). Pooled over several map x
rotation groups, the interval resamples whole groups. The report's sentences come from
:func:`planner.analysis.stats.describe` and :func:`planner.analysis.stats.disagreement`,
never from hand-written text.
"""

from __future__ import annotations

import math

import numpy as np

from planner.analysis.stats import describe, disagreement, format_p, numbers, paired_ratio
from planner.analysis.tables import format_table
from planner.lattice import NAMED_LATTICES

__all__ = ["query_key", "configs", "common_queries", "compare_to_cubic", "paired_table",
           "wilson_interval", "METRICS", "cost_value"]

METRICS = (("cpu_seconds", "CPU time to the delivered path", "less", "more"),
           ("cell_checks", "cell checks (search + smoothing)", "fewer", "more"),
           ("search_checks", "search checks alone", "fewer", "more"),
           ("length_smoothed", "delivered path length", "shorter", "longer"),
           ("length", "raw (as searched) path length", "shorter", "longer"))
"""(row key, words, less, more) of the paired metrics, what the user pays first."""


def query_key(r: dict) -> tuple:
    """The query a row answers: map, cell volume, radius, rotation, query id."""
    return (r["map"], r["cell_volume"], r["radius"], r.get("rotation", 0), r["query"])


def configs(rows: list[dict]) -> list[tuple[str, str, str]]:
    """(lattice, neighbours, method) of the lattice methods, cubic first, in lattice order."""
    cfg = {(r["lattice"], r["neighbors"], r["method"]) for r in rows
           if not str(r["method"]).startswith("ompl:")}

    def order(c):
        lat = NAMED_LATTICES.index(c[0]) if c[0] in NAMED_LATTICES else 9
        return (c[2], c[1], lat)

    return sorted(cfg, key=order)


_configs = configs


def _index(rows: list[dict]) -> dict:
    return {(r["lattice"], r["neighbors"], r["method"], query_key(r)): r for r in rows}


def cost_value(r: dict | None, key: str) -> float:
    """A found row's value of ``key`` (NaN when not found or not recorded). Rows written
    before search and smoothing were recorded apart have ``search_checks`` = their
    ``cell_checks`` only when they were not smoothed."""
    if r is None or not r.get("found"):
        return math.nan
    if key == "search_checks" and "search_checks" not in r and r.get("method") not in (
            "astar", "dijkstra"):
        key = "cell_checks"
    v = r.get(key)
    return math.nan if v is None else float(v)


_value = cost_value


def common_queries(rows: list[dict], neighbors: str, method: str) -> set:
    """Queries that every lattice of ``rows`` ran and solved with these neighbours and
    method (the paired ratios' sample)."""
    lats = {r["lattice"] for r in rows if (r["neighbors"], r["method"]) == (neighbors, method)}
    keys = None
    for lat in lats:
        k = {query_key(r) for r in rows if (r["lattice"], r["neighbors"], r["method"])
             == (lat, neighbors, method) and r.get("found")}
        keys = k if keys is None else keys & k
    return keys or set()


def compare_to_cubic(rows: list[dict], lattice: str, neighbors: str, method: str,
                     seed: int = 0) -> dict:
    """Paired statistics of one configuration against cubic (same neighbours and method).

    Returns
    -------
    dict
        ``{metric: PairedRatio}`` for :data:`METRICS` on the queries every lattice solved
        (``common``: their number; ``groups``: their map x rotation groups), plus
        ``success`` counts on every query both ran: ``n``, ``x_only`` / ``cubic_only``
        solved by one of them, and ``p`` (exact binomial test on those discordant queries,
        NaN when there are none), ``x_rate`` / ``cubic_rate``.
    """
    from scipy.stats import binomtest

    idx = _index(rows)
    keys = sorted({query_key(r) for r in rows if (r["lattice"], r["neighbors"], r["method"])
                   == (lattice, neighbors, method)}, key=str)
    keys = [k for k in keys if ("cubic", neighbors, method, k) in idx]
    mine = [idx[(lattice, neighbors, method, k)] for k in keys]
    cub = [idx[("cubic", neighbors, method, k)] for k in keys]
    common = common_queries(rows, neighbors, method)
    both = [k for k in keys if k in common]
    groups = [f"{k[0]}|{k[3]}" for k in both]  # map x rotation
    out: dict = {"common": len(both), "groups": len(set(groups))}
    for key, *_ in METRICS:
        out[key] = paired_ratio(
            [cost_value(idx[(lattice, neighbors, method, k)], key) for k in both],
            [cost_value(idx[("cubic", neighbors, method, k)], key) for k in both],
            clusters=groups, seed=seed)
    a = sum(bool(x.get("found")) and not c.get("found") for x, c in zip(mine, cub, strict=True))
    b = sum(bool(c.get("found")) and not x.get("found") for x, c in zip(mine, cub, strict=True))
    p = binomtest(a, a + b).pvalue if a + b else math.nan

    def rate(rs: list[dict]) -> float:
        return float(np.mean([bool(r.get("found")) for r in rs])) if rs else math.nan

    out["success"] = {"n": len(keys), "x_only": a, "cubic_only": b, "p": float(p),
                      "x_rate": rate(mine), "cubic_rate": rate(cub)}
    return out


def _ci(s) -> str:
    if s.n == 0:
        return "-"
    return numbers(s).split(", n =")[0] + ("" if not s.too_few else " (too few)")


def paired_table(rows: list[dict], markdown: bool = True,
                 comparisons: dict | None = None) -> tuple[str, list[str]]:
    """Table of every non-cubic configuration against cubic, and the report's sentences.

    Columns: success on every query both ran (solved by it / by cubic, with the discordant
    counts), the queries every lattice solved, then per metric the Hodges-Lehmann ratio
    with its 95% interval and p-value. The sentence of a configuration whose checks and
    time verdicts point opposite ways starts with that disagreement. ``comparisons``, when
    given, receives each configuration's :func:`compare_to_cubic` (keyed by (lattice,
    neighbours, method)) for the other tables to reuse.
    """
    head = ["lattice", "nbrs", "method", "solved (cubic)", "only it / only cubic",
            "all solved (groups)", "CPU time / cubic", "checks / cubic",
            "search checks / cubic", "delivered length / cubic", "raw length / cubic"]
    lines, prose = [], []
    for lat, nb, meth in configs(rows):
        if lat == "cubic":
            continue
        c = compare_to_cubic(rows, lat, nb, meth)
        if comparisons is not None:
            comparisons[(lat, nb, meth)] = c
        s = c["success"]
        lines.append(dict(zip(head, [
            lat, nb, meth, f"{s['x_rate']:.0%} ({s['cubic_rate']:.0%})",
            f"{s['x_only']} / {s['cubic_only']} ({format_p(s['p'])})",
            f"{c['common']} ({c['groups']})",
            *[_ci(c[k]) for k, *_ in METRICS]], strict=True)))
        who = f"{lat} {nb} {meth}"
        delivered = "smoothed" if meth in ("astar", "dijkstra") else "as searched"
        parts = [describe(c[k], what, less=less, more=more) for k, what, less, more in METRICS]
        solved = (f"solved {s['x_rate']:.0%} of {s['n']} queries vs cubic's "
                  f"{s['cubic_rate']:.0%} ({s['x_only']} only by {lat}, {s['cubic_only']} only "
                  f"by cubic, {format_p(s['p'])})")
        warn = disagreement(c["cell_checks"], c["cpu_seconds"], who, time_name="CPU time")
        prose.append(f"- **{who}** vs cubic {nb} {meth}: " + (f"**{warn}** It " if warn else "")
                     + f"{solved}; on the {c['common']} queries every lattice solved "
                     f"(delivered path: {delivered}): " + "; ".join(parts) + ".")
    return format_table(lines, head, markdown=markdown), prose


def wilson_interval(k: int, n: int, z: float = 1.96) -> tuple[float, float]:
    """Wilson score interval (default 95%) of a success rate ``k / n``; (0, 1) when n = 0.

    >>> [round(v, 3) for v in wilson_interval(10, 10)]
    [0.722, 1.0]
    """
    if n <= 0:
        return 0.0, 1.0
    p = k / n
    d = 1 + z * z / n
    mid = (p + z * z / (2 * n)) / d
    half = z * np.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / d
    return float(max(0.0, mid - half)), float(min(1.0, mid + half))
