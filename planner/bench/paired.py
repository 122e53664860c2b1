"""Paired comparisons "lattice X vs cubic" over benchmark rows, with intervals and tests.

Every ratio here is a median of per-query ratios (:func:`planner.analysis.stats.paired_ratio`:
bootstrap 95% interval, Wilcoxon signed-rank p) between a lattice and cubic with the same
neighbour set and method on the same query (same map, cell volume, radius and rotation), so
maps of very different sizes never mix in one ratio.  The report's sentences come from
:func:`planner.analysis.stats.describe`, never from hand-written text.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from planner.analysis.stats import describe, format_p, paired_ratio
from planner.analysis.tables import format_table
from planner.lattice import NAMED_LATTICES

__all__ = ["query_key", "paired_table", "rotation_spread", "headline", "wilson_interval"]

METRICS = (("cell_checks", "checks", "fewer", "more"),
           ("length", "raw length", "shorter", "longer"),
           ("length_smoothed", "smoothed length", "shorter", "longer"),
           ("seconds", "search time", "less", "more"))


def query_key(r: dict) -> tuple:
    """The query a row answers: map, cell volume, radius, rotation, query id."""
    return (r["map"], r["cell_volume"], r["radius"], r.get("rotation", 0), r["query"])


def _configs(rows: list[dict]) -> list[tuple[str, str, str]]:
    """(lattice, neighbours, method) of the lattice methods, cubic first, in lattice order."""
    cfg = {(r["lattice"], r["neighbors"], r["method"]) for r in rows
           if not str(r["method"]).startswith("ompl:")}

    def order(c):
        lat = NAMED_LATTICES.index(c[0]) if c[0] in NAMED_LATTICES else 9
        return (c[2], c[1], lat)

    return sorted(cfg, key=order)


def _index(rows: list[dict]) -> dict:
    return {(r["lattice"], r["neighbors"], r["method"], query_key(r)): r for r in rows}


def _value(r: dict | None, key: str) -> float:
    if r is None or not r.get("found") or r.get(key) is None:
        return math.nan
    return float(r[key])


def compare_to_cubic(rows: list[dict], lattice: str, neighbors: str, method: str,
                     seed: int = 0) -> dict:
    """Paired statistics of one configuration against cubic (same neighbours and method).

    Returns
    -------
    dict
        ``{metric: PairedRatio}`` for cell checks, raw and smoothed length and time (queries
        both solved), plus ``success`` counts: ``n`` queries tried by both, ``x_only`` /
        ``cubic_only`` solved by one of them, and ``p`` (exact binomial test on those
        discordant queries, NaN when there are none).
    """
    from scipy.stats import binomtest

    idx = _index(rows)
    keys = sorted({query_key(r) for r in rows if (r["lattice"], r["neighbors"], r["method"])
                   == (lattice, neighbors, method)}, key=str)
    keys = [k for k in keys if ("cubic", neighbors, method, k) in idx]
    mine = [idx[(lattice, neighbors, method, k)] for k in keys]
    cub = [idx[("cubic", neighbors, method, k)] for k in keys]
    out = {}
    for key, *_ in METRICS:
        out[key] = paired_ratio([_value(r, key) for r in mine], [_value(r, key) for r in cub],
                                seed=seed)
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
    return f"{s.median:.3f} [{s.low:.3f}, {s.high:.3f}] {format_p(s.p)}"


def paired_table(rows: list[dict], markdown: bool = True) -> tuple[str, list[str]]:
    """Table of every non-cubic configuration against cubic, and the report's sentences.

    Columns: success (solved by it / by cubic on the same queries, with the discordant
    counts), then per metric the median paired ratio with its 95% interval and p-value.
    """
    head = ["lattice", "nbrs", "method", "solved (cubic)", "only it / only cubic",
            "checks / cubic", "raw length / cubic", "smoothed length / cubic", "time / cubic"]
    lines, prose = [], []
    for lat, nb, meth in _configs(rows):
        if lat == "cubic":
            continue
        c = compare_to_cubic(rows, lat, nb, meth)
        s = c["success"]
        lines.append(dict(zip(head, [
            lat, nb, meth, f"{s['x_rate']:.0%} ({s['cubic_rate']:.0%})",
            f"{s['x_only']} / {s['cubic_only']} ({format_p(s['p'])})",
            _ci(c["cell_checks"]), _ci(c["length"]), _ci(c["length_smoothed"]),
            _ci(c["seconds"])], strict=True)))
        parts = [describe(c[k], what, less=less, more=more) for k, what, less, more in METRICS]
        solved = (f"solved {s['x_rate']:.0%} of {s['n']} queries vs cubic's "
                  f"{s['cubic_rate']:.0%} ({s['x_only']} only by {lat}, {s['cubic_only']} only "
                  f"by cubic, {format_p(s['p'])})")
        prose.append(f"- **{lat} {nb} {meth}** vs cubic {nb} {meth}: {solved}; "
                     + "; ".join(parts) + ".")
    return format_table(lines, head, markdown=markdown), prose


def rotation_spread(rows: list[dict], markdown: bool = True) -> str:
    """Per map: how much the answer moves with the rotation of the map.

    One line per map x configuration: success rate per rotation (min-max and each one), and
    the per-rotation median of the paired checks ratio against cubic (min-max).
    """
    head = ["map", "lattice", "nbrs", "method", "rotations", "success min-max",
            "success per rotation", "checks/cubic per-rotation medians min-max"]
    idx = _index(rows)
    lines = []
    for m in sorted({r["map"] for r in rows}):
        mrows = [r for r in rows if r["map"] == m]
        rots = sorted({r.get("rotation", 0) for r in mrows})
        for lat, nb, meth in _configs(mrows):
            succ, ratio = [], []
            for k in rots:
                rs = [r for r in mrows if r.get("rotation", 0) == k and
                      (r["lattice"], r["neighbors"], r["method"]) == (lat, nb, meth)]
                if not rs:
                    continue
                succ.append(np.mean([bool(r.get("found")) for r in rs]))
                rr = [_value(r, "cell_checks") / _value(idx.get(("cubic", nb, meth,
                                                                 query_key(r))), "cell_checks")
                      for r in rs]
                rr = [v for v in rr if math.isfinite(v)]
                if rr:
                    ratio.append(float(np.median(rr)))
            if not succ:
                continue
            lines.append(dict(zip(head, [
                Path(m).name, lat, nb, meth, str(len(succ)),
                f"{min(succ):.0%}-{max(succ):.0%}", " ".join(f"{v:.0%}" for v in succ),
                f"{min(ratio):.2f}-{max(ratio):.2f}" if ratio and lat != "cubic" else "-",
            ], strict=True)))
    return format_table(lines, head, markdown=markdown)


def headline(rows: list[dict]) -> str:
    """The README's results block: the paired table and its sentences (Markdown)."""
    table, prose = paired_table(rows)
    n_q = len({query_key(r) for r in rows})
    maps = ", ".join(sorted({Path(r["map"]).name for r in rows}))
    rots = sorted({r.get("rotation", 0) for r in rows})
    return "\n".join([
        f"{n_q} queries over {maps} ({len(rots)} rotation(s) per map). Ratios are medians "
        "of per-query ratios against cubic with the same neighbours and method, on the queries "
        "both solved, with a BCa bootstrap 95% interval and a Wilcoxon signed-rank p-value; "
        "success compares the queries only one of the two solved (exact binomial test).", "",
        table, "", *prose])


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
