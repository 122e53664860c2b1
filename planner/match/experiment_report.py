"""The Fig. 6 report: per-regime and per-method statistics with bootstrap intervals, the
paired lattice vs cubic comparison, the verdict on the paper's claim, where the lattice
matcher wins or loses against the registration anchors, the box plot and the trial tables.

Medians carry 95% BCa bootstrap intervals (``scipy.stats.bootstrap``); rates (outliers:
position error > 0.1 m; success: < 5 cm and < 1 degree) carry Wilson intervals. Lattices
are compared with cubic per trial: the median of the per-trial differences "method minus
cubic" in position error, and the mean difference of the outlier indicators, each with a
paired BCa interval. The verdict on "FCC lower position errors and better outlier
performance than cubic" is read from those two intervals: supported when the interval lies
below 0, contradicted when above, not shown when it contains 0. Per regime, the best
lattice (highest success rate, then lowest median position error, on the truth pairs) is
set against the best anchor by the same rule, and the report says plainly in which regimes
the lattice matcher wins and where it loses.
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
from planner.lattice import NAMED_LATTICES

__all__ = ["OUTLIER", "SUCCESS", "summarise", "format_report", "write_outputs", "write_plot"]

OUTLIER = 0.1  # m
SUCCESS = (0.05, 1.0)  # m, degrees
_LATTICES = frozenset(NAMED_LATTICES)
_CSV_FIELDS = ("trial", "regime", "pair", "group", "kind", "index", "method", "position_error",
               "rotation_error", "seconds", "initial_position_error", "initial_rotation_error",
               "source_points", "reference_points")


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


def _regime_of(row: dict) -> str:
    return row.get("regime", "default")


def _summarise_regime(rows: list[dict], methods: list[str]) -> dict:
    """``methods`` (truth pairs), ``groups`` (per pair source) and ``consistency`` (room
    residuals) of one regime's rows."""
    out: dict = {"methods": {}, "groups": {}, "consistency": {}}
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
                sel = [r for r in t if r["group"] == g]
                e = np.array([r["position_error"] for r in sel])
                a = np.array([r["rotation_error"] for r in sel])
                out["groups"].setdefault(g, {})[m] = {
                    "n": len(e), "median": float(np.median(e)),
                    "rotation_median": float(np.median(a)),
                    "success": float(((e < SUCCESS[0]) & (a < SUCCESS[1])).mean()),
                    "seconds": float(np.median([r["seconds"] for r in sel]))}
        c = list(_by(rows, m, "consistency").values())
        if c:
            res = np.array([r["position_error"] for r in c])
            out["consistency"][m] = {
                "n": len(c), "position_residual": _median_ci(res),
                "outliers": _rate(int((res > OUTLIER).sum()), len(c)),
                "rotation_residual": _median_ci([r["rotation_error"] for r in c]),
                "seconds": float(np.median([r["seconds"] for r in c]))}
    return out


def _paired(rows: list[dict], methods: list[str]) -> dict:
    out = {}
    base = _by(rows, "cubic", "truth")
    for m in methods:
        other = _by(rows, m, "truth")
        keys = sorted(set(base) & set(other))
        if m == "cubic" or not keys:
            continue
        d = np.array([other[k]["position_error"] - base[k]["position_error"] for k in keys])
        o = np.array([float(other[k]["position_error"] > OUTLIER)
                      - float(base[k]["position_error"] > OUTLIER) for k in keys])
        out[m] = {"n": len(keys), "position_difference": _median_ci(d),
                  "outlier_difference": {"mean": float(o.mean()), "ci": list(_ci(o, np.mean))}}
    return out


def _best(per: dict, names: list[str]) -> str | None:
    """The name with the highest success rate, then the lowest median position error."""
    cand = [n for n in names if n in per]
    if not cand:
        return None
    return min(cand, key=lambda n: (-per[n]["success"]["rate"],
                                    per[n]["position_error"]["median"]))


def _niche(regimes: dict, methods: list[str], what: str) -> dict:
    """Per regime, the best lattice against the best anchor on the truth pairs of
    ``regimes`` (described as ``what``); the regimes where the lattice matcher wins, and
    the sentence that says so."""
    lattices = [m for m in methods if m in _LATTICES]
    anchors = [m for m in methods if m not in _LATTICES]
    out: dict = {"regimes": {}, "wins": []}
    if not lattices or not anchors:
        out["text"] = "Where the lattice matcher wins: not tested (no anchor or no lattice)."
        return out
    parts = []
    for g, s in regimes.items():
        per = s["methods"]
        bl, ba = _best(per, lattices), _best(per, anchors)
        if bl is None or ba is None:
            continue
        win = _best(per, [bl, ba]) == bl
        out["regimes"][g] = {"lattice": bl, "anchor": ba, "lattice_wins": win}
        if win:
            out["wins"].append(g)

        def cell(m, per=per):
            return (f"{m} {100 * per[m]['success']['rate']:.0f}% / "
                    f"{1e3 * per[m]['position_error']['median']:.1f} mm / "
                    f"{per[m]['seconds']:.3f} s")
        verb = "the lattice matcher wins" if win else "the lattice matcher loses"
        ratio = per[bl]["seconds"] / max(per[ba]["seconds"], 1e-12)
        room = ""
        c = s["consistency"]
        cl = min((m for m in lattices if m in c), default=None,
                 key=lambda m: c[m]["position_residual"]["median"])
        ca = min((m for m in anchors if m in c), default=None,
                 key=lambda m: c[m]["position_residual"]["median"])
        if cl and ca:
            room = (f"; room A->B->A residual {cl} "
                    f"{1e3 * c[cl]['position_residual']['median']:.1f} mm against {ca} "
                    f"{1e3 * c[ca]['position_residual']['median']:.1f} mm")
        parts.append(f"{g}: {verb} ({cell(bl)} against {cell(ba)}, {ratio:.1f}x its CPU "
                     f"time{room})")
    head = ("The lattice matcher wins nowhere" if not out["wins"] else
            f"The lattice matcher wins in {', '.join(out['wins'])} only" if
            len(out["wins"]) < len(out["regimes"]) else "The lattice matcher wins everywhere")
    out["text"] = (f"{head} (best lattice against best anchor on the {what} by success, "
                   f"then median position error; success, median position error, median "
                   f"CPU s per match): " + "; ".join(parts) + ".")
    return out


def _reference_offset(rows: list[dict], methods: list[str]) -> dict | None:
    """The Velodyne pair's ``relative.txt`` against where the methods converge (default
    regime, successful trials): each method's median distance from it, and the largest
    distance between two methods' median estimates (componentwise medians)."""
    sel = [r for r in rows if r["group"] == "velodyne" and _regime_of(r) == "default"
           and "estimate" in r]
    if not sel:
        return None
    per, centres = {}, {}
    for m in methods:
        ok = [r for r in sel if r["method"] == m and r["position_error"] < SUCCESS[0]
              and r["rotation_error"] < SUCCESS[1]]
        if ok:
            per[m] = {"n": len(ok),
                      "position": float(np.median([r["position_error"] for r in ok])),
                      "rotation": float(np.median([r["rotation_error"] for r in ok]))}
            centres[m] = np.median([np.array(r["estimate"])[:3, 3] for r in ok], axis=0)
    if not per:
        return None
    c = list(centres.values())
    spread = max((float(np.linalg.norm(a - b)) for a in c for b in c), default=0.0)
    return {"methods": per, "spread": spread}


def summarise(rows: list[dict], methods: list[str]) -> dict:
    """Statistics of the rows (see the module) as a JSON-ready dict: per regime
    ``regimes[name]`` with ``methods`` (truth pairs), ``groups`` (per pair source) and
    ``consistency`` (room residuals); the default regime's ``paired`` (method minus cubic)
    and ``verdict``; ``niche`` (where the lattice matcher wins) and ``reference`` (the
    Velodyne reference's offset)."""
    names = list(dict.fromkeys(_regime_of(r) for r in rows))
    regimes = {g: _summarise_regime([r for r in rows if _regime_of(r) == g], methods)
               for g in names}
    first = "default" if "default" in regimes else (names[0] if names else "default")
    out: dict = {"regimes": regimes,
                 "paired": _paired([r for r in rows if _regime_of(r) == first], methods),
                 "paired_regime": first}
    out["verdict"] = _verdict(out["paired"].get("fcc"))
    # The headline: pairs whose truth is exact (the Velodyne reference is itself measured,
    # some 15-25 mm from where the methods converge), when there are any.
    exact = [r for r in rows if r["group"] != "velodyne"]
    if any(r["kind"] == "truth" for r in exact):
        regimes_exact = {g: _summarise_regime([r for r in exact if _regime_of(r) == g],
                                              methods) for g in names}
        out["niche"] = _niche(regimes_exact, methods, "pairs with exact truth")
        velodyne = [r for r in rows if r["group"] == "velodyne"]
        if velodyne:
            out["niche_velodyne"] = _niche(
                {g: _summarise_regime([r for r in velodyne if _regime_of(r) == g], methods)
                 for g in names}, methods, "Velodyne pair (measured reference)")
    else:
        out["niche"] = _niche(regimes, methods, "truth pairs")
    out["reference"] = _reference_offset(rows, methods)
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
    """The Markdown tables and the verdict lines of :func:`summarise`'s result."""
    lines = []
    for g, reg in summary["regimes"].items():
        if not reg["methods"]:
            continue
        lines += [f"Regime {g}, truth pairs:", "",
                  "| method | trials | success < 5 cm and < 1 deg [95% CI] | median position "
                  "error, mm [95% CI] | median rotation error, deg [95% CI] | outliers > 0.1 m "
                  "[95% CI] | median CPU s per match |", "|---|---|---|---|---|---|---|"]
        for m, s in reg["methods"].items():
            lines.append(f"| {m} | {s['n']} | {_pct(s['success'])} | "
                         f"{_mci(s['position_error'], 1e3, 1)} | "
                         f"{_mci(s['rotation_error'], 1, 3)} | {_pct(s['outliers'])} | "
                         f"{s['seconds']:.3f} |")
        lines.append("")
    methods = list(dict.fromkeys(m for reg in summary["regimes"].values()
                                 for m in reg["methods"]))
    if any(reg["groups"] for reg in summary["regimes"].values()):
        lines += ["Success % / median position error (mm) per regime and source:", "",
                  "| regime | source | trials | " + " | ".join(methods) + " |",
                  "|---|---|---|" + "---|" * len(methods)]
        for g, reg in summary["regimes"].items():
            for src, per in reg["groups"].items():
                n = next(iter(per.values()))["n"]
                cells = [f"{100 * per[m]['success']:.0f} / {1e3 * per[m]['median']:.1f}"
                         if m in per else "-" for m in methods]
                lines.append(f"| {g} | {src} | {n} | " + " | ".join(cells) + " |")
        lines.append("")
    if any(reg["consistency"] for reg in summary["regimes"].values()):
        lines += ["Consistency (room pair, no ground truth): A->B composed with B->A "
                  "should be the identity:", "",
                  "| regime | method | trials | median residual, mm [95% CI] | median "
                  "residual, deg [95% CI] | residual > 0.1 m [95% CI] | median CPU s per "
                  "match |", "|---|---|---|---|---|---|---|"]
        for g, reg in summary["regimes"].items():
            for m, s in reg["consistency"].items():
                lines.append(f"| {g} | {m} | {s['n']} | "
                             f"{_mci(s['position_residual'], 1e3, 2)} | "
                             f"{_mci(s['rotation_residual'], 1, 3)} | {_pct(s['outliers'])} | "
                             f"{s['seconds']:.3f} |")
        lines.append("")
    if summary["paired"]:
        lines += [f"Paired per trial ({summary['paired_regime']} regime), method minus "
                  "cubic:", "",
                  "| method | trials | median position difference, mm [95% CI] | outlier "
                  "rate difference [95% CI] |", "|---|---|---|---|"]
        for m, p in summary["paired"].items():
            o = p["outlier_difference"]
            lines.append(f"| {m} | {p['n']} | {_mci(p['position_difference'], 1e3, 2)} | "
                         f"{o['mean']:+.3f} [{o['ci'][0]:+.3f}, {o['ci'][1]:+.3f}] |")
        lines.append("")
    ref = summary.get("reference")
    if ref:
        per = ", ".join(f"{m} {1e3 * v['position']:.1f} mm / {v['rotation']:.2f} deg"
                        for m, v in ref["methods"].items())
        lines += [f"Velodyne reference (relative.txt) against where each method converges "
                  f"(default regime, successful trials, median): {per}; the methods' median "
                  f"positions lie within {1e3 * ref['spread']:.1f} mm of each other.", ""]
    niche = [summary["niche"]["text"], ""]
    if "niche_velodyne" in summary:
        niche += ["On the Velodyne pair alone: " + summary["niche_velodyne"]["text"], ""]
    return "\n".join(lines + niche + [summary["verdict"]]) + "\n"


def write_plot(rows: list[dict], methods: list[str], path: str | Path) -> None:
    """Box plots per method (whiskers 1.5 IQR) of the position and rotation errors of the
    truth pairs in the default regime (the first regime run when it was not), and of the
    consistency residuals when there are any; the format from the
    suffix of ``path`` (.png, .pdf, .svg), written atomically."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    names = list(dict.fromkeys(_regime_of(r) for r in rows))
    first = "default" if "default" in names else (names[0] if names else "default")
    rows = [r for r in rows if _regime_of(r) == first]
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
    fig.suptitle(f"Scan matching from random initial errors, {first} regime (same draws "
                 "for every method)")
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
