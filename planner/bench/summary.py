"""Summaries of benchmark rows: per lattice x method statistics relative to cubic,
box plots in the style of the paper's Fig. 6, and a Markdown report that embeds them."""

from __future__ import annotations

import csv
import io
import math
from collections import defaultdict
from pathlib import Path

import numpy as np

from planner.analysis.metadata import metadata_markdown, run_metadata, suite_sha256
from planner.analysis.stats import STATISTICS_NOTE
from planner.analysis.style import LATTICE_COLORS, OTHER_COLOR
from planner.analysis.tables import format_table
from planner.bench import paired
from planner.bench.answer import (
    decision_table,
    delivered_table,
    empty_group_lines,
    fair_queries_table,
    per_map_table,
)
from planner.bench.figures import plot_tradeoffs
from planner.bench.orientation import rotation_spread
from planner.bench.paired import wilson_interval
from planner.bench.rows import unique_rows
from planner.fsutil import atomic_path, write_text_atomic
from planner.lattice import NAMED_LATTICES

LATTICE_ORDER = NAMED_LATTICES


def _group_key(r: dict) -> tuple:
    return (r["map"], r["cell_volume"], r["radius"], r.get("rotation", 0), r["query"])


def add_ratios(rows: list[dict]) -> list[dict]:
    """Set ``length_ratio``: delivered (smoothed) length over the best length any run found on the
    same query (same map, cell volume, radius and rotation); ``raw_length_ratio``: the raw
    (unsmoothed) length over that same best; and ``checks_vs_cubic``: cell checks over
    those of the cubic lattice with the same neighbours and method on the same query (the
    per-query pairing of the paper's Fig. 6, which does not mix maps of different sizes)."""
    cubic = {(*_group_key(r), r["neighbors"], r["method"]): r["cell_checks"] for r in rows
             if r["lattice"] == "cubic" and r.get("found") and r.get("cell_checks")}
    best: dict = defaultdict(lambda: math.inf)
    for r in rows:
        if r.get("found") and r.get("length_smoothed") is not None:
            best[_group_key(r)] = min(best[_group_key(r)], r["length_smoothed"], r["length"])
    for r in rows:
        b = best[_group_key(r)]
        ok = r.get("found") and r.get("length_smoothed") is not None and math.isfinite(b)
        r["length_ratio"] = r["length_smoothed"] / b if ok and b > 0 else None
        r["raw_length_ratio"] = r["length"] / b if ok and b > 0 else None
        c = cubic.get((*_group_key(r), r["neighbors"], r["method"]))
        r["checks_vs_cubic"] = (r["cell_checks"] / c if c and r.get("found")
                                and not str(r["method"]).startswith("ompl:") else None)
    return rows


def _label(r: dict) -> str:
    if str(r["method"]).startswith("ompl:"):
        return f"{r['method']} ({r['lattice']} world)"
    return f"{r['lattice']} {r['neighbors']} {r['method']}"


def _stats(vals: list[float]) -> tuple[float, float]:
    if not vals:
        return math.nan, math.nan
    q1, med, q3 = np.percentile(vals, [25, 50, 75])
    return float(med), float(q3 - q1)


def summarize(rows: list[dict]) -> list[dict]:
    """One row per (lattice, neighbours, method): success rate and median/IQR of the
    length ratio, cell checks, expansions and time, plus medians relative to cubic with
    the same neighbours and method."""
    rows = unique_rows(rows)  # two runs into one folder must not count a query twice
    add_ratios(rows)
    groups: dict = defaultdict(list)
    for r in rows:
        groups[(r["lattice"], r["neighbors"], r["method"])].append(r)
    out = []
    for (lat, nb, meth), rs in groups.items():
        found = [r for r in rs if r.get("found")]
        s = {"lattice": lat, "neighbors": nb, "method": meth, "runs": len(rs),
             "success": len(found) / len(rs),
             "collision_free": all(r.get("collision_free") for r in found)}
        for key in ("length_ratio", "raw_length_ratio", "cell_checks", "checks_vs_cubic",
                    "search_checks", "smooth_checks", "expansions", "seconds", "cpu_seconds",
                    "peak_bytes", "clearance"):
            med, iqr = _stats([r[key] for r in found if r.get(key) is not None])
            s[f"{key}_median"], s[f"{key}_iqr"] = med, iqr
        out.append(s)
    by = {(s["lattice"], s["neighbors"], s["method"]): s for s in out}
    for s in out:
        c = by.get(("cubic", s["neighbors"], s["method"]))
        for key in ("length_ratio", "cell_checks", "seconds", "cpu_seconds"):
            v, b = s[f"{key}_median"], c[f"{key}_median"] if c else math.nan
            s[f"{key}_vs_cubic"] = v / b if c and b and math.isfinite(b) else math.nan

    def order(s):
        lat = LATTICE_ORDER.index(s["lattice"]) if s["lattice"] in LATTICE_ORDER else 9
        return (s["method"].startswith("ompl:"), s["method"], s["neighbors"], lat)

    return sorted(out, key=order)


def format_summary(summary: list[dict], markdown: bool = False) -> str:
    """Table of :func:`summarize` rows (plain text, or Markdown for the report).

    Length ratios: the path's length over the shortest path any run found on the query, raw
    (as searched) and smoothed (line-of-sight shortcut for A*/Dijkstra, OMPL's simplified
    path; any-angle paths are their own smoothed path). ``checks/cubic``: median of the
    per-query ratios (see the paired table of the report for intervals). Cell checks and
    times are to the delivered path: search plus smoothing.
    """
    head = ["lattice", "nbrs", "method", "runs", "success", "raw len ratio (IQR)",
            "delivered len ratio (IQR)", "cell checks (IQR)", "checks/cubic", "CPU ms",
            "wall ms", "clear-ok"]
    lines = []
    for s in summary:
        lines.append(dict(zip(head, [
            s["lattice"], s["neighbors"], s["method"], str(s["runs"]), f"{s['success']:.0%}",
            f"{s['raw_length_ratio_median']:.3f} ({s['raw_length_ratio_iqr']:.3f})",
            f"{s['length_ratio_median']:.3f} ({s['length_ratio_iqr']:.3f})",
            f"{s['cell_checks_median']:,.0f} ({s['cell_checks_iqr']:,.0f})",
            _f(s["checks_vs_cubic_median"]), _ms(s["cpu_seconds_median"]),
            _ms(s["seconds_median"]),
            "yes" if s["collision_free"] else "NO",
        ], strict=True)))
    return format_table(lines, head, markdown=markdown)


def _ms(v: float) -> str:
    return f"{1e3 * v:.3g}" if isinstance(v, float) and math.isfinite(v) else "-"


def _f(v: float) -> str:
    return f"{v:.3f}" if isinstance(v, float) and math.isfinite(v) else "-"


def write_csv(path: Path, summary: list[dict]) -> None:
    buf = io.StringIO()
    if summary:
        w = csv.DictWriter(buf, fieldnames=list(summary[0]))
        w.writeheader()
        w.writerows(summary)
    write_text_atomic(path, buf.getvalue())


def plot(rows: list[dict], out_dir: Path) -> list[Path]:
    """Box plots (length ratio, cell checks, time) and success rates; returns the PNGs."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    add_ratios(rows)
    labels = sorted({_label(r) for r in rows}, key=lambda s: (
        s.startswith("ompl"), s.split()[-1], s.split()[1] if len(s.split()) > 2 else "",
        LATTICE_ORDER.index(s.split()[0]) if s.split()[0] in LATTICE_ORDER else 9))
    colours = LATTICE_COLORS
    files = []
    metrics = [("raw_length_ratio", "raw path length / best length on the query", False,
                "raw_length_ratio"),
               ("length_ratio", "delivered path length / best length on the query", False,
                "length_ratio"),
               ("checks_vs_cubic", "cell checks to the delivered path / cubic's", True,
                "checks_vs_cubic"),
               ("cell_checks", "cell checks to the delivered path per query", True,
                "cell_checks"),
               ("cpu_seconds", "CPU time to the delivered path per query (s)", True, "time")]
    for key, ylabel, log, name in metrics:
        data = [[r[key] for r in rows if _label(r) == lab and r.get("found")
                 and r.get(key) is not None] for lab in labels]
        keep = [i for i, d in enumerate(data) if d]
        if not keep:  # nothing found: no figure (boxplot([]) would still draw one box)
            continue
        fig, ax = plt.subplots(figsize=(max(7, 0.55 * len(labels) + 2), 5))
        bp = ax.boxplot([data[i] for i in keep], whis=1.5, patch_artist=True,
                        medianprops={"color": "black", "linewidth": 1.5})  # visible on every box
        for patch, i in zip(bp["boxes"], keep, strict=True):
            patch.set_facecolor(colours.get(labels[i].split()[0], "white"))
            patch.set_alpha(0.6)
        ax.set_xticks(range(1, len(keep) + 1), [labels[i] for i in keep], rotation=60,
                      ha="right", fontsize=8)
        if log:
            ax.set_yscale("log")
        ax.set_ylabel(ylabel)
        ax.set_title(f"{ylabel} (whiskers 1.5 IQR)")
        ax.grid(axis="y", alpha=0.3)
        fig.tight_layout()
        p = out_dir / f"{name}.png"
        with atomic_path(p) as tmp:
            fig.savefig(tmp, dpi=110, format="png")
        plt.close(fig)
        files.append(p)
    fig, ax = plt.subplots(figsize=(max(7, 0.55 * len(labels) + 2), 4))
    counts = [(sum(bool(r.get("found")) for r in rows if _label(r) == lab),
               sum(_label(r) == lab for r in rows)) for lab in labels]
    rates = np.array([k / n for k, n in counts])
    lo, hi = np.array([wilson_interval(k, n) for k, n in counts]).T
    x = np.arange(len(labels))
    ax.bar(x, rates, color=[colours.get(lab.split()[0], OTHER_COLOR) for lab in labels])
    ax.errorbar(x, rates, yerr=np.clip([rates - lo, hi - rates], 0, None), fmt="none",
                ecolor="black", capsize=3, lw=1)
    for xi, (k, n) in zip(x, counts, strict=True):
        ax.text(xi, 1.02, f"{k}/{n}", ha="center", va="bottom", fontsize=7)
    ax.set_xticks(x, labels, rotation=60, ha="right", fontsize=8)
    ax.set_ylim(0, 1.12)
    ax.set_ylabel("success rate")
    ax.set_title("fraction of queries solved (solved/n above each bar; 95% Wilson interval)")
    fig.tight_layout()
    p = out_dir / "success.png"
    with atomic_path(p) as tmp:
        fig.savefig(tmp, dpi=110, format="png")
    plt.close(fig)
    files.append(p)
    return files + plot_tradeoffs(rows, out_dir)




DROP_PREFIXES = ("candidates ", "kept but blocked in ")
"""Sampler counts that are not drops (per-lattice blocked shares, see
:func:`planner.bench.queries.sample_queries`)."""


def provenance(suite, rows: list[dict], command: str, *, jobs: int = 1) -> dict:
    """What a results page records about the run that made it: package version, commit
    (the report's and the rows'), the suite file and its SHA-256, date, statistics."""
    meta = run_metadata(jobs)
    src = getattr(suite, "source", "")
    return {"suite": suite.name, "suite_file": Path(src).name if src else "",
            "suite_sha256": suite_sha256(src) if src and Path(src).is_file() else "unknown",
            "version": meta["version"], "commit": meta["commit"],
            "rows_commits": sorted({r["commit"] for r in rows if r.get("commit")}),
            "date": meta["date"], "command": command, "statistics": STATISTICS_NOTE,
            "cpu": f"{meta['cpu']} ({meta['cpu_count']} cores), jobs {meta['jobs']}"}


def provenance_lines(prov: dict) -> list[str]:
    """The provenance as Markdown bullets (the ``suite file sha256`` line is what the
    consistency test reads)."""
    ran = ", ".join(prov["rows_commits"]) or "not recorded"
    return [f"- suite `{prov['suite']}` ({prov['suite_file']}), suite file sha256: "
            f"`{prov['suite_sha256']}`",
            f"- lattice-planner {prov['version']}, commit `{prov['commit']}` (report; rows "
            f"run at {ran}), date {prov['date']}",
            f"- regenerated by `{prov['command']}`; CPU: {prov['cpu']}",
            f"- statistics: {prov['statistics']}"]


def _answer_sections(rows: list[dict], record: dict) -> dict:
    """The generated Markdown pieces every page shares."""
    add_ratios(rows)
    comparisons: dict = {}
    table, prose = paired.paired_table(rows, comparisons=comparisons)
    rot_table, rot_prose = rotation_spread(rows)
    recs, maps = [], []
    for m in sorted({r["map"] for r in rows}):
        rs, text = per_map_table(rows, m)
        recs += rs
        maps += [f"{Path(m).name} (rows numbered `{Path(m).stem}-N`; medians over the "
                 f"{rs[0]['queries'] if rs else 0} queries every configuration solved):", "",
                 text, ""]
    decision, plain = decision_table(recs)
    n_q = len({paired.query_key(r) for r in rows})
    names = ", ".join(sorted({Path(r["map"]).name for r in rows}))
    rots = len({r.get("rotation", 0) for r in rows})
    disagree = [p.split("**")[3] for p in prose if p.count("**") >= 4]
    return {
        "delivered": "\n".join([
            f"{n_q} queries over {names} ({rots} rotation(s) per map). What the user pays "
            "for the path whose length is compared (the delivered path: A* and Dijkstra "
            "paths smoothed by line-of-sight shortcutting, any-angle paths as searched): "
            "CPU time and cell checks of the search plus the smoothing, medians over the "
            "queries every lattice solved with that neighbour set and method; ratios to "
            "cubic are paired Hodges-Lehmann ratios with a 95% interval.", "",
            delivered_table(rows, comparisons=comparisons)]),
        "disagree": disagree,
        "paired": "\n".join([STATISTICS_NOTE, "", table, "", *prose]),
        "fair": "\n".join([
            "Queries are sampled where at least one lattice has both ends free and some "
            "lattice connects them; every lattice runs every query. `endpoints blocked`: "
            "share of the queries whose start or goal this lattice blocks (a failure of "
            "this lattice); `candidates blocked`: the same share among all sampled "
            "candidates free in some lattice; `not connected`: share of the queries it "
            "ran without finding a path. Paired ratios use only the queries every lattice "
            "solved.", "", fair_queries_table(rows, record)]),
        "orientation": "\n".join([
            "Per map and configuration: the range of the per-rotation medians of the "
            "paired ratio to cubic, and the permutation test of rotation labels (shuffled "
            "within cell volume and radius, 999 shuffles).", "", rot_table, "", *rot_prose]),
        "orientation_prose": rot_prose,
        "maps": "\n".join(maps),
        "decision": "\n".join([
            "Per map and goal, the configuration with the lowest median on the queries "
            "every configuration of the map solved (its success rate beside it when below "
            "the map's best); each cell cites its row of the per-map tables.", "",
            decision, "", *[f"- {p}" for p in plain]]),
    }


def write_report(out_dir: Path, suite, rows: list[dict], summary: list[dict], record: dict,
                 figures: list[Path], command: str, *, partial: str | None = None,
                 jobs: int = 1) -> Path:
    """Markdown report embedding the figures; returns its path.

    It leads with the time to the delivered path and ends with the decision table; beside
    it the run folder gets ``results_section.md`` (the results page) and
    ``readme_section.md`` (the README's "Which lattice?" block), see
    :mod:`planner.analysis.readme_results`. ``partial`` (why the suite is incomplete) puts
    a PARTIAL flag at the top.
    """
    unsafe = [r for r in rows if r.get("found") and r.get("collision_free") is False]
    title = f"# Benchmark suite `{suite.name}`" + (" (PARTIAL)" if partial else "")
    lines = [title, ""]
    if partial:
        lines += [f"**PARTIAL RESULTS**: {partial}.", ""]
    prov = provenance(suite, rows, command, jobs=jobs)
    parts = _answer_sections(rows, record)
    lines += [f"Regenerate with `{command}`.", "",
              metadata_markdown(run_metadata(jobs), rows), *provenance_lines(prov)[:1], "",
              f"{len(rows)} runs; {sum(bool(r.get('found')) for r in rows)} found a path; "
              f"{len(unsafe)} paths violated the robot clearance against the raw obstacles.", ""]
    if suite.skipped:
        lines += [f"Skipped (files absent): {', '.join(suite.skipped)}", ""]
    rot = getattr(suite, "rotation", "none")
    lines += [f"Rotations: `{rot}`, {len({r.get('rotation', 0) for r in rows})} per map "
              "(the lattice turned by R^T in the map's frame, i.e. the map by R; the same "
              "sample for every lattice, neighbour set and method).", ""]
    lines += ["## Time to the delivered path", "", parts["delivered"], "",
              "## Lattice vs cubic (paired per query)", "", parts["paired"], "",
              "## Queries each lattice cannot run", "", parts["fair"], "",
              "## Does the answer depend on orientation?", "", parts["orientation"], "",
              "## Summary (medians; ratios relative to cubic with the same neighbours "
              "and method)", "", format_summary(summary, markdown=True), ""]
    maps = sorted({r["map"] for r in rows})
    if len(maps) > 1:  # the pooled medians above mix maps of very different sizes
        for m in maps:
            lines += [f"### {Path(m).name}", "",
                      format_summary(summarize([r for r in rows if r["map"] == m]),
                                     markdown=True), ""]
    lines += ["Length ratios: raw (as searched) and delivered (shortcut A*/Dijkstra paths; "
              "any-angle paths unchanged) path length over the shortest path any run found on "
              "that query; `cubic face astar` is cubic-6, whose delivered path is cubic-6 + "
              "shortcut, the cheapest honest competitor. Cell checks and times: search plus "
              "smoothing. Clearance is measured against the raw obstacle points, not the "
              "voxels.", ""]
    for f in figures:
        lines += [f"![{f.stem}]({f.name})", ""]
    lines += ["## Queries", ""] + _query_lines(record) + [""]
    lines += ["## Which lattice for which goal", "", parts["maps"], parts["decision"], ""]
    p = out_dir / "report.md"
    write_text_atomic(p, "\n".join(lines))
    write_text_atomic(out_dir / "results_section.md", results_section(
        suite, rows, record, figures, command, partial=partial, parts=parts, prov=prov))
    write_text_atomic(out_dir / "readme_section.md", readme_section(
        suite, rows, command, partial=partial, parts=parts, prov=prov))
    return p


def _query_lines(record: dict) -> list[str]:
    """One markdown table: a row per query group (queries kept / wanted, candidates dropped
    per reason), and a total row."""
    reasons = sorted({k for rec in record.values() for k in rec["dropped"]
                      if not k.startswith(DROP_PREFIXES)})
    head = ["group", "kept / wanted"] + [f"dropped: {k}" for k in reasons]
    out = [_cells(head), "|" + "---|" * len(head)]
    total = defaultdict(int)
    kept = wanted = 0
    for group, rec in record.items():
        out.append(_cells([group, f"{rec['kept']}/{rec['wanted']}"]
                          + [rec["dropped"].get(k, 0) for k in reasons]))
        kept, wanted = kept + rec["kept"], wanted + rec["wanted"]
        for k, v in rec["dropped"].items():
            if not k.startswith(DROP_PREFIXES):
                total[k] += v
    if len(record) > 1:
        out.append(_cells(["all", f"{kept}/{wanted}"] + [total[k] for k in reasons]))
    return out


def _cells(values: list) -> str:
    return "| " + " | ".join(str(v) for v in values) + " |"


def results_section(suite, rows: list[dict], record: dict, figures: list[Path], command: str,
                    *, partial: str | None = None, fig_prefix: str = "",
                    parts: dict | None = None, prov: dict | None = None) -> str:
    """The results page (``benchmarks/results.md``), generated from the rows (see
    :mod:`planner.analysis.readme_results`): provenance, the time to the delivered path,
    the paired table and its sentences, the queries each lattice cannot run, the
    orientation test, the trade-off figures, and the per-map rows and decision table."""
    parts = parts or _answer_sections(rows, record)
    prov = prov or provenance(suite, rows, command)
    lines = [f"Suite `{suite.name}`" + (" (PARTIAL)" if partial else ""), "",
             *provenance_lines(prov), "",
             "### Time to the delivered path", "", parts["delivered"], "",
             "### Lattice vs cubic (paired per query)", "", parts["paired"], "",
             "### Queries each lattice cannot run", "", parts["fair"], "",
             "### Does the answer depend on orientation?", "", parts["orientation"], ""]
    for f in figures:
        if f.stem in ("pareto", "success_vs_resolution", "time_vs_length", "checks_vs_cubic"):
            lines += [f"![{f.stem}]({fig_prefix}{f.name})", ""]
    lines += ["Queries dropped while sampling (all groups):", "",
              *_query_lines({"all groups": _total_record(record)}), "",
              *empty_group_lines(record),
              "### Which lattice for which goal", "", parts["maps"], parts["decision"], ""]
    return "\n".join(lines)


def readme_section(suite, rows: list[dict], command: str, *, partial: str | None = None,
                   parts: dict | None = None, prov: dict | None = None) -> str:
    """The README's "Which lattice?" block: the time to the delivered path, where checks and
    time disagree, what the orientation test supports, and the decision table, with the
    provenance line that names the results page (every number is in
    ``benchmarks/results.md`` too)."""
    parts = parts or _answer_sections(rows, {})
    prov = prov or provenance(suite, rows, command)
    lines = [f"Generated from a run of the suite `{suite.name}`"
             + (" (PARTIAL)" if partial else "") + f" (suite file sha256 "
             f"`{prov['suite_sha256'][:12]}`, lattice-planner {prov['version']}) by `python -m "
             "planner.analysis.readme_results RUN_DIR`; the full tables, statistics and "
             "figures are in [benchmarks/results.md](benchmarks/results.md).", "",
             parts["delivered"], ""]
    if parts["disagree"]:
        lines += ["Where cell checks and time point opposite ways:", "",
                  *[f"- {d}" for d in parts["disagree"]], ""]
    lines += ["Orientation:", "", *parts["orientation_prose"], "",
              "Which lattice for which goal (rows of the per-map tables in "
              "[benchmarks/results.md](benchmarks/results.md)):", "",
              parts["decision"].split("\n\n", 1)[1]]
    return "\n".join(lines).rstrip("\n") + "\n"


def _total_record(record: dict) -> dict:
    kept = sum(rec["kept"] for rec in record.values())
    wanted = sum(rec["wanted"] for rec in record.values())
    dropped: dict = defaultdict(int)
    for rec in record.values():
        for k, v in rec["dropped"].items():
            dropped[k] += v
    return {"kept": kept, "wanted": wanted, "dropped": dict(dropped)}
