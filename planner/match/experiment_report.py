"""The Fig. 6 report: per-method statistics with bootstrap intervals, the paired lattice
vs cubic comparison, the verdict on the paper's claim, the box plot and the trial tables.

Medians carry 95% BCa bootstrap intervals (``scipy.stats.bootstrap``); rates (outliers:
position error > 0.1 m; success: < 5 cm and < 1 degree) carry Wilson intervals. Lattices
are compared with cubic per trial: the median of the per-trial differences "method minus
cubic" in position error, and the mean difference of the outlier indicators, each with a
paired BCa interval. The verdict on "FCC lower position errors and better outlier
performance than cubic" is read from those two intervals: supported when the interval lies
below 0, contradicted when above, not shown when it contains 0.
"""

from __future__ import annotations

import csv
import json
import math
import warnings
from pathlib import Path

import numpy as np

from planner.bench.paired import wilson_interval
from planner.fsutil import atomic_path, write_text_atomic

__all__ = ["OUTLIER", "SUCCESS", "summarise", "format_report", "write_outputs", "write_plot"]

OUTLIER = 0.1  # m
SUCCESS = (0.05, 1.0)  # m, degrees
_CSV_FIELDS = ("trial", "pair", "group", "kind", "index", "method", "position_error",
               "rotation_error", "seconds", "initial_position_error", "initial_rotation_error")


def _ci(x: np.ndarray, stat, seed: int = 0) -> tuple[float, float]:
    """95% BCa bootstrap interval of ``stat`` over the 1-D sample ``x``: NaN for fewer than
    two values; a sample with one distinct value has the zero-width interval at it."""
    from scipy.stats import bootstrap

    x = np.asarray(x, dtype=float)
    if len(x) < 2:
        return math.nan, math.nan
    if np.ptp(x) == 0:
        return float(x[0]), float(x[0])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # degenerate resamples: NaN, handled below
        res = bootstrap((x,), stat, confidence_level=0.95, method="BCa", n_resamples=4000,
                        random_state=np.random.default_rng(seed))
    lo, hi = float(res.confidence_interval.low), float(res.confidence_interval.high)
    return (lo, hi) if math.isfinite(lo) and math.isfinite(hi) else (math.nan, math.nan)


def _median_ci(x) -> dict:
    x = np.asarray(x, dtype=float)
    lo, hi = _ci(x, np.median)
    return {"median": float(np.median(x)) if len(x) else math.nan, "ci": [lo, hi]}


def _rate(k: int, n: int) -> dict:
    return {"rate": k / n if n else math.nan, "ci": list(wilson_interval(k, n))}


def _by(rows: list[dict], method: str, kind: str) -> dict[str, dict]:
    return {r["trial"]: r for r in rows if r["method"] == method and r["kind"] == kind}


def summarise(rows: list[dict], methods: list[str]) -> dict:
    """Statistics of the rows (see the module) as a JSON-ready dict: ``methods`` (truth
    pairs), ``groups`` (median position error per pair source), ``consistency`` (room
    residuals), ``paired`` (method minus cubic) and ``verdict``."""
    out: dict = {"methods": {}, "groups": {}, "consistency": {}, "paired": {}}
    for m in methods:
        t = list(_by(rows, m, "truth").values())
        if t:
            pos = np.array([r["position_error"] for r in t])
            rot = np.array([r["rotation_error"] for r in t])
            ok = (pos < SUCCESS[0]) & (rot < SUCCESS[1])
            out["methods"][m] = {
                "n": len(t), "position_error": _median_ci(pos),
                "rotation_error": _median_ci(rot),
                "outliers": _rate(int((pos > OUTLIER).sum()), len(t)),
                "success": _rate(int(ok.sum()), len(t)),
                "seconds": float(np.median([r["seconds"] for r in t]))}
            for g in sorted({r["group"] for r in t}):
                e = [r["position_error"] for r in t if r["group"] == g]
                out["groups"].setdefault(g, {})[m] = {"n": len(e),
                                                       "median": float(np.median(e))}
        c = list(_by(rows, m, "consistency").values())
        if c:
            res = np.array([r["position_error"] for r in c])
            out["consistency"][m] = {
                "n": len(c), "position_residual": _median_ci(res),
                "outliers": _rate(int((res > OUTLIER).sum()), len(c)),
                "rotation_residual": _median_ci([r["rotation_error"] for r in c]),
                "seconds": float(np.median([r["seconds"] for r in c]))}
    base = _by(rows, "cubic", "truth")
    for m in methods:
        other = _by(rows, m, "truth")
        keys = sorted(set(base) & set(other))
        if m == "cubic" or not keys:
            continue
        d = np.array([other[k]["position_error"] - base[k]["position_error"] for k in keys])
        o = np.array([float(other[k]["position_error"] > OUTLIER)
                      - float(base[k]["position_error"] > OUTLIER) for k in keys])
        out["paired"][m] = {"n": len(keys), "position_difference": _median_ci(d),
                            "outlier_difference": {"mean": float(o.mean()),
                                                   "ci": list(_ci(o, np.mean))}}
    out["verdict"] = _verdict(out["paired"].get("fcc"))
    return out


def _reading(ci: list[float], better: str, worse: str) -> str:
    lo, hi = ci
    if not (math.isfinite(lo) and math.isfinite(hi)):
        return "not shown (no interval)"
    if hi < 0:
        return f"supported ({better})"
    if lo > 0:
        return f"contradicted ({worse})"
    return "not shown (the 95% CI contains 0)"


def _verdict(p: dict | None) -> str:
    claim = ("the paper's claim (FCC lower position errors and better outlier performance "
             "than cubic)")
    if p is None:
        return f"Verdict on {claim}: not tested (FCC and cubic were not both run)."
    d, o = p["position_difference"], p["outlier_difference"]
    pos = _reading(d["ci"], "FCC lower", "FCC higher")
    out = _reading(o["ci"], "FCC fewer", "FCC more")
    return (f"Verdict on {claim}, paired over {p['n']} trials: lower position errors "
            f"{pos}, median FCC minus cubic {1e3 * d['median']:+.2f} mm "
            f"[{1e3 * d['ci'][0]:+.2f}, {1e3 * d['ci'][1]:+.2f}]; better outlier "
            f"performance {out}, outlier rate difference {o['mean']:+.3f} "
            f"[{o['ci'][0]:+.3f}, {o['ci'][1]:+.3f}].")


def _mci(s: dict, scale: float, digits: int) -> str:
    lo, hi = s["ci"]
    return f"{s['median'] * scale:.{digits}f} [{lo * scale:.{digits}f}, {hi * scale:.{digits}f}]"


def _pct(s: dict) -> str:
    return f"{100 * s['rate']:.0f}% [{100 * s['ci'][0]:.0f}, {100 * s['ci'][1]:.0f}]"


def format_report(summary: dict) -> str:
    """The Markdown tables and the verdict line of :func:`summarise`'s result."""
    lines = ["| method | trials | median position error, mm [95% CI] | median rotation "
             "error, deg [95% CI] | outliers > 0.1 m [95% CI] | success < 5 cm and < 1 deg "
             "[95% CI] | median s per match |", "|---|---|---|---|---|---|---|"]
    for m, s in summary["methods"].items():
        lines.append(f"| {m} | {s['n']} | {_mci(s['position_error'], 1e3, 1)} | "
                     f"{_mci(s['rotation_error'], 1, 3)} | {_pct(s['outliers'])} | "
                     f"{_pct(s['success'])} | {s['seconds']:.3f} |")
    if summary["groups"]:
        methods = list(summary["methods"])
        lines += ["", "Median position error (mm) per source:", "",
                  "| source | trials | " + " | ".join(methods) + " |",
                  "|---|---|" + "---|" * len(methods)]
        for g, per in summary["groups"].items():
            n = next(iter(per.values()))["n"]
            cells = [f"{1e3 * per[m]['median']:.1f}" if m in per else "-" for m in methods]
            lines.append(f"| {g} | {n} | " + " | ".join(cells) + " |")
    if summary["paired"]:
        lines += ["", "Paired per trial, method minus cubic:", "",
                  "| method | trials | median position difference, mm [95% CI] | outlier "
                  "rate difference [95% CI] |", "|---|---|---|---|"]
        for m, p in summary["paired"].items():
            o = p["outlier_difference"]
            lines.append(f"| {m} | {p['n']} | {_mci(p['position_difference'], 1e3, 2)} | "
                         f"{o['mean']:+.3f} [{o['ci'][0]:+.3f}, {o['ci'][1]:+.3f}] |")
    if summary["consistency"]:
        lines += ["", "Consistency (room pair, no ground truth): A->B composed with B->A "
                  "should be the identity:", "",
                  "| method | trials | median residual, mm [95% CI] | median residual, deg "
                  "[95% CI] | residual > 0.1 m [95% CI] | median s per match |",
                  "|---|---|---|---|---|---|"]
        for m, s in summary["consistency"].items():
            lines.append(f"| {m} | {s['n']} | {_mci(s['position_residual'], 1e3, 2)} | "
                         f"{_mci(s['rotation_residual'], 1, 3)} | {_pct(s['outliers'])} | "
                         f"{s['seconds']:.3f} |")
    return "\n".join(lines + ["", summary["verdict"]]) + "\n"


def write_plot(rows: list[dict], methods: list[str], path: str | Path) -> None:
    """Box plots per method (whiskers 1.5 IQR) of the position and rotation errors of the
    truth pairs, and of the consistency residuals when there are any; the format from the
    suffix of ``path`` (.png, .pdf, .svg), written atomically."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    panels = [("truth", "position_error", 1e3, "position error (mm)"),
              ("truth", "rotation_error", 1.0, "rotation error (deg)")]
    if any(r["kind"] == "consistency" for r in rows):
        panels.append(("consistency", "position_error", 1e3, "room A->B->A residual (mm)"))
    fig, axes = plt.subplots(1, len(panels), figsize=(4.2 * len(panels), 4.0))
    for ax, (kind, key, scale, label) in zip(np.atleast_1d(axes), panels, strict=True):
        data = [[r[key] * scale for r in rows if r["method"] == m and r["kind"] == kind]
                for m in methods]
        shown = [(m, d) for m, d in zip(methods, data, strict=True) if d]
        if shown:
            ax.boxplot([d for _, d in shown], whis=1.5)
            ax.set_xticks(range(1, len(shown) + 1), [m for m, _ in shown])
            if min(min(d) for _, d in shown) > 0:
                ax.set_yscale("log")
        ax.set_ylabel(label)
        ax.grid(True, axis="y", alpha=0.3)
    fig.suptitle("Scan matching from random initial errors (same draws for every method)")
    fig.tight_layout()
    with atomic_path(path, keep_suffix=True) as tmp:
        fig.savefig(tmp)
    plt.close(fig)


def write_outputs(rows: list[dict], methods: list[str], out: str | Path,
                  plot: str | Path | None = None) -> dict:
    """Summarise ``rows`` and write ``out``/table.md, summary.json, trials.csv and the
    box plot (``plot``, default ``out``/fig6.png), each atomically. Returns the summary."""
    out = Path(out)
    summary = summarise(rows, methods)
    write_text_atomic(out / "table.md", format_report(summary))
    write_text_atomic(out / "summary.json", json.dumps(summary, indent=1))
    with atomic_path(out / "trials.csv") as tmp, open(tmp, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=_CSV_FIELDS, extrasaction="ignore")
        w.writeheader()
        w.writerows(rows)
    write_plot(rows, methods, plot or out / "fig6.png")
    return summary
