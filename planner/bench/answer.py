"""The answer a user reads first: what each lattice, neighbour set and method costs to
deliver its path, which queries each lattice cannot run, and which configuration to pick
per map and goal.

- :func:`delivered_table`: per configuration, the median CPU time and cell checks to the
  delivered path (search + smoothing, each shown), with the paired ratio to cubic.
- :func:`fair_queries_table`: per lattice, the share of sampled queries whose start or
  goal it blocks and the share it cannot connect.
- :func:`per_map_table` / :func:`decision_table`: per map, numbered rows of medians on the
  queries every configuration solved; per map and goal (fewest checks, fastest plan,
  shortest path) the best row, cited by its number.
"""

from __future__ import annotations

import math
from collections import defaultdict
from pathlib import Path

import numpy as np

from planner.analysis.tables import format_table
from planner.bench.paired import common_queries, compare_to_cubic, configs, cost_value, query_key

__all__ = ["delivered_table", "fair_queries_table", "per_map_table", "decision_table",
           "empty_group_lines", "GOALS"]

GOALS = (("fewest checks", "cell_checks"), ("fastest plan", "cpu_seconds"),
         ("shortest path", "length_ratio"))
"""(goal, the per-map table's column that decides it, lower is better)."""


def _delivered(meth: str) -> str:
    if str(meth).startswith("ompl:"):
        return "simplified"
    return "smoothed" if meth in ("astar", "dijkstra") else "as searched"


def _med(rs: list[dict], key: str) -> float:
    v = [cost_value(r, key) for r in rs]
    v = [x for x in v if math.isfinite(x)]
    return float(np.median(v)) if v else math.nan


def _ms(v: float) -> str:
    return "-" if not math.isfinite(v) else f"{1e3 * v:.3g}"


def _n(v: float) -> str:
    return "-" if not math.isfinite(v) else f"{v:,.0f}"


def _ratio(s) -> str:
    if s.n == 0:
        return "-"
    txt = f"{s.estimate:.3g} [{s.low:.3g}, {s.high:.3g}]"
    return txt + (" (too few)" if s.too_few else "")


def delivered_table(rows: list[dict], markdown: bool = True,
                    comparisons: dict | None = None) -> str:
    """What the delivered path costs, per lattice, neighbour set and method.

    Medians over the queries every lattice solved with that neighbour set and method (the
    same queries for every row of a neighbour set and method); ratios are the paired
    Hodges-Lehmann ratios to cubic with their 95% interval
    (:func:`planner.bench.paired.compare_to_cubic`; ``comparisons`` holds them when already
    computed, keyed by (lattice, neighbours, method)).
    """
    head = ["lattice", "nbrs", "method", "solved", "delivered path", "CPU ms to path",
            "= search + smoothing ms", "checks to path", "= search + smoothing checks",
            "CPU time / cubic", "checks / cubic"]
    lines = []
    for lat, nb, meth in configs(rows):
        rs = [r for r in rows if (r["lattice"], r["neighbors"], r["method"]) == (lat, nb, meth)]
        common = common_queries(rows, nb, meth)
        ok = [r for r in rs if query_key(r) in common]
        c = None
        if lat != "cubic":
            c = (comparisons or {}).get((lat, nb, meth)) or compare_to_cubic(rows, lat, nb, meth)
        lines.append(dict(zip(head, [
            lat, nb, meth, f"{np.mean([bool(r.get('found')) for r in rs]):.0%}",
            _delivered(meth), _ms(_med(ok, "cpu_seconds")),
            f"{_ms(_med(ok, 'search_cpu_seconds'))} + {_ms(_med(ok, 'smooth_cpu_seconds'))}",
            _n(_med(ok, "cell_checks")),
            f"{_n(_med(ok, 'search_checks'))} + {_n(_med(ok, 'smooth_checks'))}",
            _ratio(c["cpu_seconds"]) if c else "1", _ratio(c["cell_checks"]) if c else "1",
        ], strict=True)))
    return format_table(lines, head, markdown=markdown)


def fair_queries_table(rows: list[dict], record: dict | None = None,
                       markdown: bool = True) -> str:
    """Per map and lattice: the sampled queries, the share whose start or goal the lattice
    blocks, and per neighbour set the share it ran but could not connect (no path; A* when
    run, else the first method), plus, from the sampler's record, the share of all
    candidates (free in some lattice) that it blocks."""
    head = ["map", "lattice", "queries", "endpoints blocked", "candidates blocked"]
    nbs = sorted({r["neighbors"] for r in rows if not str(r["method"]).startswith("ompl:")})
    head += [f"not connected ({nb})" for nb in nbs]
    cand: dict = defaultdict(lambda: [0, 0])
    for rec in (record or {}).values():
        dr = rec.get("dropped", {})
        total = dr.get("candidates free in some lattice")
        if total is None:
            continue
        for k, v in dr.items():
            if k.startswith("candidates blocked in "):
                c = cand[(rec.get("map"), k.removeprefix("candidates blocked in "))]
                c[0] += v
                c[1] += total
    lines = []
    for m in sorted({r["map"] for r in rows}):
        mrows = [r for r in rows if r["map"] == m and not str(r["method"]).startswith("ompl:")]
        meths = sorted({r["method"] for r in mrows})
        if not meths:  # only OMPL ran on this map: no lattice search to count
            continue
        meth = "astar" if "astar" in meths else meths[0]
        for lat in [c[0] for c in configs(mrows) if c[1:] == (nbs[0], meth)]:
            cells = [Path(m).name, lat]
            one = [r for r in mrows if (r["lattice"], r["neighbors"], r["method"])
                   == (lat, nbs[0], meth)]
            blocked = sum(bool(r.get("blocked")) for r in one)
            cb = cand.get((m, lat))
            cells += [str(len(one)), f"{blocked / len(one):.1%}" if one else "-",
                      f"{cb[0] / cb[1]:.1%}" if cb and cb[1] else "-"]
            for nb in nbs:
                rs = [r for r in mrows if (r["lattice"], r["neighbors"], r["method"])
                      == (lat, nb, meth) and not r.get("blocked")]
                lost = sum(not r.get("found") for r in rs)
                cells.append(f"{lost / len(rs):.1%}" if rs else "-")
            lines.append(dict(zip(head, cells, strict=True)))
    return format_table(lines, head, markdown=markdown)


def per_map_table(rows: list[dict], m: str, first: int = 1) -> tuple[list[dict], str]:
    """Numbered rows of one map: per configuration the success rate and, on the queries
    every configuration of the map solved, the medians of CPU time and cell checks to the
    delivered path and of the delivered length over the best on the query.

    Returns the records (with ``row``) and the Markdown table.
    """
    mrows = [r for r in rows if r["map"] == m and not str(r["method"]).startswith("ompl:")]
    keys = None
    for cfg in configs(mrows):
        k = {query_key(r) for r in mrows if (r["lattice"], r["neighbors"], r["method"]) == cfg
             and r.get("found")}
        keys = k if keys is None else keys & k
    keys = keys or set()
    recs = []
    for i, cfg in enumerate(configs(mrows)):
        rs = [r for r in mrows if (r["lattice"], r["neighbors"], r["method"]) == cfg]
        ok = [r for r in rs if query_key(r) in keys]
        recs.append({"row": first + i, "map": m, "lattice": cfg[0], "neighbors": cfg[1],
                     "method": cfg[2], "success": np.mean([bool(r.get("found")) for r in rs]),
                     "queries": len(ok), "cpu_seconds": _med(ok, "cpu_seconds"),
                     "cell_checks": _med(ok, "cell_checks"),
                     "length_ratio": _med(ok, "length_ratio")})
    head = ["row", "lattice", "nbrs", "method", "success", "queries all solved",
            "CPU ms to path", "checks to path", "delivered length / best"]
    lines = [dict(zip(head, [f"{Path(m).stem}-{r['row']}", r["lattice"], r["neighbors"],
                             r["method"], f"{r['success']:.0%}", str(r["queries"]),
                             _ms(r["cpu_seconds"]), _n(r["cell_checks"]),
                             f"{r['length_ratio']:.4f}" if math.isfinite(r["length_ratio"])
                             else "-"], strict=True)) for r in recs]
    return recs, format_table(lines, head, markdown=True)


def decision_table(recs: list[dict]) -> tuple[str, list[str]]:
    """Per map and goal, the row of :func:`per_map_table` with the lowest median, cited by
    its number (with its success rate when it is below the map's best: a configuration
    that fails queries others solve pays for it there); and the plain sentence for every
    map where cubic delivers the fastest plan."""
    head = ["map", *[g for g, _ in GOALS]]
    lines, plain = [], []
    for m in sorted({r["map"] for r in recs}):
        mr = [r for r in recs if r["map"] == m]
        best_success = max(r["success"] for r in mr)
        stem = Path(m).stem
        cells = [Path(m).name]
        for goal, key in GOALS:
            ok = [r for r in mr if math.isfinite(r[key])]
            if not ok:
                cells.append("-")
                continue
            b = min(ok, key=lambda r: r[key])
            val = {"cell_checks": f"{b[key]:,.0f} checks",
                   "cpu_seconds": f"{1e3 * b[key]:.3g} ms CPU",
                   "length_ratio": f"{b[key]:.4f} of best"}[key]
            short = (f"; solved {b['success']:.0%}, best {best_success:.0%}"
                     if b["success"] < best_success - 1e-12 else "")
            cells.append(f"{b['lattice']} {b['neighbors']} {b['method']} "
                         f"({stem}-{b['row']}: {val}{short})")
            if goal == "fastest plan" and b["lattice"] == "cubic":
                others = [r for r in ok if r["lattice"] != "cubic"]
                nxt = min(others, key=lambda r: r[key]) if others else None
                plain.append(
                    f"On {Path(m).name}, cubic delivers the fastest plan ({b['neighbors']} "
                    f"{b['method']}, row {stem}-{b['row']}, {1e3 * b[key]:.3g} ms median CPU)"
                    + (f"; the fastest other lattice, {nxt['lattice']} {nxt['neighbors']} "
                       f"{nxt['method']} (row {stem}-{nxt['row']}), takes "
                       f"{1e3 * nxt[key]:.3g} ms" if nxt else "") + ".")
        lines.append(dict(zip(head, cells, strict=True)))
    return format_table(lines, head, markdown=True), plain


def empty_group_lines(record: dict) -> list[str]:
    """A sentence naming the query groups that kept no query (their candidates count in the
    tables above; they have no runs), or nothing."""
    none = [g for g, rec in record.items() if not rec.get("kept")]
    if not none:
        return []
    return [f"Groups that kept no query ({len(none)} of {len(record)}; no start and goal "
            "pair passed the sampler, see each group's reasons in `report.md`): "
            + "; ".join(none) + ".", ""]
