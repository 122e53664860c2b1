"""Does the answer depend on the map's orientation? A permutation test of rotation labels.

Per map and configuration, the statistic is the spread (largest minus smallest) of the
per-rotation medians of the per-query log ratio against cubic (delivered cell checks, or
CPU time). Shuffling the rotation labels among the map's queries (within each cell volume
and radius, whose ratios differ for other reasons) gives its distribution when orientation
does not matter; the p-value is the share of shuffles whose spread is at least the
observed one. A claim that "the answer depends on orientation" is made only for the
configurations where that test rejects.

Examples
--------
Three rotations of six queries whose log ratios move with the rotation, and the same
values with labels that do not follow them:

>>> import numpy as np
>>> rot = np.repeat([0, 1, 2], 6)
>>> d = rot + np.tile(np.linspace(0, 0.5, 6), 3)
>>> spread, p = rotation_test(d, rot, np.zeros(18), n_perm=999, seed=0)
>>> round(spread, 2), p < 0.01
(2.0, True)
>>> rotation_test(d, np.tile([0, 1, 2], 6), np.zeros(18), n_perm=999, seed=0)[1] > 0.05
True
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from planner.analysis.stats import format_p
from planner.analysis.tables import format_table
from planner.bench.paired import configs, cost_value, query_key

__all__ = ["rotation_test", "rotation_spread"]


def _spread(d: np.ndarray, labels: np.ndarray, uniq: np.ndarray) -> float:
    meds = [np.median(d[labels == u]) for u in uniq]
    return float(max(meds) - min(meds))


def rotation_test(d, rotations, strata, *, n_perm: int = 999,
                  seed: int = 0) -> tuple[float, float]:
    """(spread, p): the range of per-rotation medians of ``d`` (shape (n,)) and the
    permutation p-value of rotation labels shuffled within ``strata`` (shape (n,)).

    p = (1 + shuffles with a spread >= the observed) / (1 + n_perm); NaN with fewer than
    two rotations.
    """
    d = np.asarray(d, dtype=float)
    rot = np.asarray(rotations)
    strata = np.asarray([str(s) for s in strata])
    uniq = np.unique(rot)
    if len(uniq) < 2:
        return math.nan, math.nan
    obs = _spread(d, rot, uniq)
    rng = np.random.default_rng(seed)
    blocks = [np.flatnonzero(strata == s) for s in np.unique(strata)]
    hits = 0
    perm = rot.copy()
    for _ in range(n_perm):
        for b in blocks:
            perm[b] = rng.permutation(rot[b])
        hits += _spread(d, perm, uniq) >= obs - 1e-12
    return obs, (1 + hits) / (1 + n_perm)


def rotation_spread(rows: list[dict], markdown: bool = True,
                    metrics: tuple[str, ...] = ("cell_checks", "cpu_seconds"),
                    alpha: float = 0.05) -> tuple[str, list[str]]:
    """Per map and configuration: success per rotation, the range of per-rotation medians
    of the paired ratios (delivered checks, CPU time) and their permutation p-values; and
    the sentences that state what the test supports.

    Returns
    -------
    table : str
    prose : list of str
        One sentence per map: which configurations' ratios depend on orientation (p <
        ``alpha``) and how many tests were made (about ``alpha`` of them reject by chance).
    """
    head = ["map", "lattice", "nbrs", "method", "rotations", "success min-max"]
    for m in metrics:
        name = "checks" if m == "cell_checks" else "CPU time"
        head += [f"{name}/cubic per-rotation medians", f"{name}: p (shuffled rotations)"]
    idx = {(r["lattice"], r["neighbors"], r["method"], query_key(r)): r for r in rows}
    lines, prose = [], []
    for m in sorted({r["map"] for r in rows}):
        mrows = [r for r in rows if r["map"] == m]
        rots = sorted({r.get("rotation", 0) for r in mrows})
        tested, claims = 0, []
        for lat, nb, meth in configs(mrows):
            rs = [r for r in mrows if (r["lattice"], r["neighbors"], r["method"])
                  == (lat, nb, meth)]
            succ = [np.mean([bool(r.get("found")) for r in rs if r.get("rotation", 0) == k])
                    for k in rots if any(r.get("rotation", 0) == k for r in rs)]
            cells = [Path(m).name, lat, nb, meth, str(len(succ)),
                     f"{min(succ):.0%}-{max(succ):.0%}" if succ else "-"]
            for metric in metrics:
                if lat == "cubic":
                    cells += ["-", "-"]
                    continue
                d, rot, strata = [], [], []
                for r in rs:
                    c = idx.get(("cubic", nb, meth, query_key(r)))
                    v = cost_value(r, metric) / cost_value(c, metric)
                    if math.isfinite(v) and v > 0:
                        d.append(math.log(v))
                        rot.append(r.get("rotation", 0))
                        strata.append((r["cell_volume"], r["radius"]))
                spread, p = (rotation_test(d, rot, strata) if len(set(rot)) > 1
                             else (math.nan, math.nan))
                if math.isfinite(p):
                    tested += 1
                    meds = [math.exp(np.median([x for x, k in zip(d, rot, strict=True)
                                                if k == u])) for u in sorted(set(rot))]
                    cells += [f"{min(meds):.2f}-{max(meds):.2f}", format_p(p)]
                    if p < alpha:
                        what = "checks" if metric == "cell_checks" else "CPU time"
                        claims.append(f"{lat} {nb} {meth} ({what}, {format_p(p)})")
                else:
                    cells += ["-", "-"]
            lines.append(dict(zip(head, cells, strict=True)))
        if tested:
            name = Path(m).name
            if claims:
                prose.append(f"- {name}: the ratio to cubic depends on orientation for "
                             f"{', '.join(claims)}: {len(claims)} of {tested} tests reject "
                             f"at {alpha:g} (about {alpha * tested:.1f} would by chance).")
            else:
                prose.append(f"- {name}: no configuration's per-rotation medians spread more "
                             f"than shuffling the rotation labels gives ({tested} tests, "
                             f"none with p < {alpha:g}); orientation is not shown to matter.")
    return format_table(lines, head, markdown=markdown), prose
