"""Regenerate the speed figures of README.md ("Known limits") and benchmarks/README.md
("Search speed") from one ``benchmarks/search_speed.py --json`` run, so that no speed figure
in them is typed by hand.

From the checkout's root::

    python benchmarks/search_speed.py --sample 200 --compare 0 --da1 0 --anyangle 20 \\
        --repeat 3 --json benchmarks/speed.json
    python -m planner.analysis.speed_docs benchmarks/speed.json

The second command replaces the README's block between ``<!-- speed-limits:start -->`` and
``<!-- speed-limits:end -->`` and benchmarks/README.md's block between
``<!-- speed:start -->`` and ``<!-- speed:end -->`` (both written atomically, after every
input was read and both blocks were made). ``--check`` writes nothing and exits 1 when a
document differs from what the JSON gives. The JSON is the harness's ``Record``
(``benchmarks/harness.py``): the command line, the header (machine, load, versions,
commit), every ``ratio`` line's figures and the tables' figures.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import textwrap
from pathlib import Path
from typing import Any

from planner.analysis.readme_results import block, splice
from planner.errors import PlannerError
from planner.fsutil import write_text_atomic

__all__ = ["README_START", "README_END", "BENCH_START", "BENCH_END", "REGENERATE",
           "SpeedRecord", "load", "readme_block", "bench_block", "regenerate"]

README_START = "<!-- speed-limits:start -->"
README_END = "<!-- speed-limits:end -->"
BENCH_START = "<!-- speed:start -->"
BENCH_END = "<!-- speed:end -->"
REGENERATE = "python -m planner.analysis.speed_docs benchmarks/speed.json"
OTHER = ("bcc", "fcc", "mcc", "hex")  # the non-cubic lattices, in the tables' order
PLAN_MAPS = ("office", "geb079", "DA1", "Complex")  # those in the record, in this order


class SpeedRecord:
    """One ``search_speed.py --json`` record (``data``: the harness's ``Record`` as a
    dict; ``source``: where it was read), read with errors that name the missing figure."""

    def __init__(self, data: dict, source: str):
        self.data, self.source = data, source

    def _need(self, where: dict, key: str, what: str) -> Any:
        if not isinstance(where, dict) or key not in where:
            raise PlannerError(f"{self.source}: no {what} '{key}' (a run of "
                               "`python benchmarks/search_speed.py ... --json PATH` with every "
                               "table: data present, no --no-* option)")
        return where[key]

    def fig(self, *keys: str) -> Any:
        """``figures[k0][k1]...``."""
        node = self._need(self.data, "figures", "section")
        for k in keys:
            node = self._need(node, k, "figure")
        return node

    def ratio(self, what: str) -> dict:
        return self._need(self._need(self.data, "ratios", "section"), what, "ratio line")

    def has(self, *keys: str) -> bool:
        node = self.data.get("figures", {})
        for k in keys:
            if not isinstance(node, dict) or k not in node:
                return False
            node = node[k]
        return True


def load(path: str | Path) -> SpeedRecord:
    """Read a ``--json`` record; PlannerError (one line) when it is unreadable, a smoke run,
    or not a ``search_speed.py`` run."""
    path = Path(path)
    try:
        data = json.loads(path.read_text())
    except OSError as exc:
        raise PlannerError(f"{path}: {exc.strerror or exc}") from None
    except json.JSONDecodeError as exc:
        raise PlannerError(f"{path}: not JSON ({exc.msg}, line {exc.lineno})") from None
    if not isinstance(data, dict) or "command" not in data or "header" not in data:
        raise PlannerError(f"{path}: not a benchmark record (`--json` of "
                           "benchmarks/search_speed.py)")
    if data.get("smoke"):
        raise PlannerError(f"{path}: a smoke run (tiny sizes, figures not meaningful); "
                           "rerun without --smoke")
    if "search_speed.py" not in data["command"]:
        raise PlannerError(f"{path}: a run of `{data['command']}`, not of "
                           "benchmarks/search_speed.py")
    return SpeedRecord(data, str(path))


def _f(v: float | None, spec: str = ".2f") -> str:
    return "n/a" if v is None or not math.isfinite(v) else format(v, spec)


def _span(values: list[float], spec: str = ".2f") -> str:
    """``lo-hi`` of the values as printed (one figure when they print alike)."""
    lo, hi = _f(min(values), spec), _f(max(values), spec)
    return lo if lo == hi else f"{lo}-{hi}"


def _and(words: list[str]) -> str:
    return words[0] if len(words) == 1 else ", ".join(words[:-1]) + " and " + words[-1]


def _places(maps: list[str]) -> str:
    """The floor table's maps as a sentence names them (the Warframe maps, geb079)."""
    wf = [m for m in maps if m != "geb079"]
    words = ([f"Warframe {_and(wf)}"] if wf else []) + (["geb079"] if "geb079" in maps
                                                        else [])
    return " and on ".join(words)


def _ci(r: dict) -> str:
    """``median [95% CI low, high]`` as the harness prints it."""
    ci = (f"[95% CI {r['low']:.3g}, {r['high']:.3g}]" if r.get("low") is not None
          else "[no 95% CI: too few pairs]")
    return f"{r['median']:.3g} {ci}"


def _bullet(text: str) -> str:
    return textwrap.fill(text, width=90, initial_indent="* ", subsequent_indent="  ",
                         break_on_hyphens=False, break_long_words=False)


def _floor_maps(run: SpeedRecord) -> list[str]:
    return list(run.fig("floor"))


def _anyangle_worlds(run: SpeedRecord) -> list[str]:
    return list(run.fig("anyangle"))


def _weighted_worlds(run: SpeedRecord) -> list[str]:
    return list(run.fig("weighted"))


def _machine(run: SpeedRecord) -> str:
    """The run's CPU and cores (its load, commit and date stay in the record's header)."""
    return run.data["header"][0].removeprefix("machine: ").split("; load average")[0]


def readme_block(run: SpeedRecord) -> str:
    """The README's two "Known limits" speed items (Markdown bullets)."""
    maps = _floor_maps(run)
    speeds = [run.fig("floor", m, "speed") for m in maps]
    medians = [run.ratio(f"A* speed ours/floor {m}")["median"] for m in maps]
    lower = max(medians) < min(speeds)
    aa = [run.ratio(f"Lazy Theta*/A* time, {w}")["median"] for w in _anyangle_worlds(run)]
    wt = [run.ratio(f"weighted-theta/A* time, {w}")["median"] for w in _weighted_worlds(run)]
    fc = run.fig("fixed_cost")
    plans = [fc[f"plan_{k}_us"] for k in ("array", "tuple", "list")]
    one = (f"Speed against a C++ A* compiled at run time and called in the same process, "
           f"each figure with its method in [benchmarks/README.md](benchmarks/README.md) "
           f"(\"Search speed\"): our A* runs at {_and([_f(s) for s in speeds])} of the "
           f"strongest such floor's expansions per second on cubic-26 over all queries on "
           f"{_places(maps)} (goal 0.9; the median of the per-query ratios is "
           + (f"lower, {_span(medians)}: short queries weigh our per-call cost"
              if lower else _span(medians))
           + f"), Lazy Theta* at {_span(aa, '.1f')}x A*'s time and `weighted-theta` at "
           f"{_span(wt, '.1f')}x (medians of the per-query ratios; goal 2); a `search()` "
           f"call on a prebuilt world costs {_f(fc['search_us'], '.1f')} us with a one-move "
           f"query (goal 5), a `plan()` call {_span(plans, '.1f')} us with array, tuple or "
           f"list endpoints (goal 15). Measured by `{run.data['command']}` "
           f"(on {_machine(run)}; the run's load and commit: the record's header); "
           f"`{REGENERATE}` rewrites this item and the next from that "
           "run's record.")
    sight = [run.fig("sight", k, "vs_cubic") for k in OTHER]
    maps = _plan_maps(run)
    lazy = {m: [run.fig("plan", m, k, "lazy_vs_cubic") for k in OTHER] for m in maps}
    smooth = {m: [run.fig("plan", m, k, "astar_smooth_vs_cubic") for k in ("bcc", "mcc")]
              for m in maps}
    share = [1 - run.fig("plan", m, k, "smooth_s") / run.fig("plan", m, k, "astar_smooth_s")
             for m in maps for k in ("bcc", "mcc")]
    per_map = "; ".join(
        f"on {_plan_place(m)}: Lazy Theta* {_span(lazy[m])}x, A* plus smoothing BCC "
        f"{_f(smooth[m][0])} and MCC {_f(smooth[m][1])}" for m in maps)
    two = ("Sight lines on the non-cubic lattices (Theta*, Lazy Theta*, `weighted-theta`, "
           "shortcutting) step from Voronoi cell to Voronoi cell through the facet the "
           "segment leaves by, each step also looking up its mirror image through the "
           "segment's midpoint (the cell the walk from the other end would reach), its exit "
           f"times integer keys that name their facet: {_span(sight)}x the cubic "
           "integer walk's time per cell looked up (goal 1.5x). Time against cubic-26's on "
           "the same queries (sums over the queries; goals: Lazy Theta* 1.5x on every "
           f"lattice, A* plus smoothing 0.8 on BCC and MCC): {per_map}; the search is "
           f"{_span([100 * s for s in share], '.0f')}% of A* plus smoothing")
    if all(run.has("plan", m, "cubic", "astar_search_s") for m in maps):
        exp, cost = _per_expansion(run, maps, ("bcc", "mcc"), "astar")
        lexp, lcost = _per_expansion(run, maps, OTHER, "lazy")
        excess = _path_excess()
        two += (f". A time ratio is an expansions ratio times a cost-per-expansion ratio: "
                f"BCC and MCC A* expand {_span(exp)}x cubic-26's nodes at {_span(cost)}x its "
                f"cost per expansion, the non-cubic Lazy Theta* {_span(lexp)}x at "
                f"{_span(lcost)}x; the path metrics of BCC's and MCC's 14 moves stray further "
                f"from the straight line than cubic-26's (up to {_f(excess['bcc'])}x and "
                f"{_f(excess['mcc'])}x its length, against {_f(excess['cubic'])}x)")
    two += " (the same run's per-lattice tables)."
    return _bullet(one) + "\n" + _bullet(two)


def _plan_maps(run: SpeedRecord) -> list[str]:
    """The planning tables' maps in the record (office and geb079 at least)."""
    maps = [m for m in PLAN_MAPS if run.has("plan", m)]
    for m in ("office", "geb079"):
        if m not in maps:
            run.fig("plan", m)  # the error that names it
    return maps


def _plan_place(m: str) -> str:
    """The planning table's map as a sentence names it."""
    return {"office": "the office", "geb079": "geb079"}.get(
        m, f"Warframe {m} (2-voxel cells, radius 1 voxel)")


def _per_expansion(run: SpeedRecord, maps: list[str], names, method: str
                   ) -> tuple[list[float], list[float]]:
    """Per map and lattice of ``names``: expansions / cubic's and time per expansion /
    cubic's, of A*'s search (``method`` "astar") or of Lazy Theta* ("lazy")."""
    secs = "astar_search_s" if method == "astar" else "lazy_s"
    exp, cost = [], []
    for m in maps:
        c = run.fig("plan", m, "cubic")
        for k in names:
            p = run.fig("plan", m, k)
            e = p[f"{method}_expansions"] / c[f"{method}_expansions"]
            exp.append(e)
            cost.append(p[secs] / c[secs] / e)
    return exp, cost


def _path_excess() -> dict[str, float]:
    """Per named lattice, :func:`planner.search.moves.path_excess` of its full move set."""
    from planner.lattice import NAMED_LATTICES, Lattice  # (numba: only this figure needs it)
    from planner.search.moves import path_excess  # (numba, scipy: only this figure)

    return {name: path_excess(Lattice.named(name, 1.0)) for name in NAMED_LATTICES}


def _row(what: str, figure: str) -> str:
    return f"| {what} | {figure} |"


def _floor_row(run: SpeedRecord) -> str:
    maps = _floor_maps(run)
    rows = {m: run.fig("floor", m) for m in maps}
    chk = run.fig("floor_checked")
    long_min = next((r["long_min_expansions"] for r in rows.values()
                     if "long_min_expansions" in r), None)
    counts = ", ".join(f"{m} {rows[m]['long_queries']}" for m in maps)
    long = (f"the long queries (at least {long_min:,} floor expansions; {counts})" if long_min
            else f"the long queries (`cpp_anchor.py`'s `LONG` floor expansions or more; "
                 f"{counts})")
    where = ("all 10,000 queries per Warframe map" if chk["all_warframe"]
             else f"{chk['queries_per_warframe_map']} queries per Warframe map")
    if chk["geb079_queries"]:
        where += f", {chk['geb079_queries']} on geb079 at 0.08 m"
    what = ("A*, cubic-26, ours / the strongest C++ floor (`cpp_anchor.py`'s rows, in "
            f"process; {where}; each map's longest axis fastest for both sides), expansions "
            "per second")
    fig = ("all queries (sum / sum): "
           + ", ".join(f"{m} {_f(rows[m]['speed'])}" for m in maps)
           + f"; {long}: " + ", ".join(_f(rows[m]["long_speed"]) for m in maps)
           + "; median of the per-query ratios "
           + ", ".join(f"{m} {_ci(run.ratio(f'A* speed ours/floor {m}'))}" for m in maps)
           + f" (goal 0.9); {chk['mismatches']} cost mismatches (ours, the floor and the "
           "listed Warframe optimum); expansion ratio ours / the floor's "
           + ", ".join(_f(rows[m]["exp_ratio"], ".3f") for m in maps))
    return _row(what, fig)


def _lattice_row(run: SpeedRecord) -> str | None:
    if not run.has("lattice_expansion", "cubic"):
        return None
    lat = run.fig("lattice_expansion")
    names = [k for k in lat if k != "cubic"]
    what = ("A* per expansion by lattice on geb079 at the same cell volume (0.08^3 m^3; the "
            "cubic queries' ends quantized on each lattice, a query whose ends are blocked "
            "there left out), ns per expansion / cubic's")
    fig = ("sum / sum: " + ", ".join(f"{k} {_f(lat[k]['vs_cubic'])}" for k in names)
           + f" (cubic {_f(lat['cubic']['ns_per_expansion'], '.0f')} ns per expansion, "
           f"{lat['cubic']['queries']} queries); median of the per-query ratios "
           + ", ".join(f"{k} {_ci(run.ratio(f'A* ns per expansion {k}/cubic, geb079'))}"
                       for k in names) + " (goal 1.3)")
    return _row(what, fig)


def _fixed_row(run: SpeedRecord) -> str:
    fc = run.fig("fixed_cost")
    what = (f"fixed cost per call on a prebuilt world, one-move query (median per call over "
            f"batches of {fc['batch']}; {fc['calls']:,} calls)")
    fig = (f"`search()` {_f(fc['search_us'])} us (goal 5; its engine call, "
           f"`SearchResult.seconds`, {_f(fc['engine_us'])} us; from a cell to itself "
           f"{_f(fc['same_us'])} us; taking turns between two worlds {_f(fc['turns_us'])} "
           f"us); `plan()` with tuple endpoints "
           f"{_f(fc['plan_tuple_us'], '.1f')} us, list {_f(fc['plan_list_us'], '.1f')} us, "
           f"float64 array {_f(fc['plan_array_us'], '.1f')} us (goal 15 each)")
    return _row(what, fig)


def _anyangle_row(run: SpeedRecord) -> str:
    ws, ww = _anyangle_worlds(run), _weighted_worlds(run)
    aa, wt = run.fig("anyangle"), run.fig("weighted")
    n = max(aa[w]["queries"] for w in ws)
    what = (f"any-angle against A* (cubic-26, the same queries, up to {n} per world), time "
            "per query; `weighted-theta` (Lazy Theta*, heuristic x1.03) length / Lazy "
            "Theta* length per query")
    fig = ("Lazy Theta* / A*, median of the per-query ratios: "
           + ", ".join(f"{w} {_ci(run.ratio(f'Lazy Theta*/A* time, {w}'))}" for w in ws)
           + " (goal 2); median ms A* / Lazy Theta*: "
           + ", ".join(f"{w} {_f(aa[w]['astar_median_ms'])} / {_f(aa[w]['lazy_median_ms'])}"
                       for w in ws)
           + "; `weighted-theta` / A*: "
           + ", ".join(f"{w} {_ci(run.ratio(f'weighted-theta/A* time, {w}'))}" for w in ww)
           + " (goal 2), its expansions "
           + _and([_f(wt[w]["weighted_expansions_over_astar"]) for w in ww])
           + " of A*'s (median per query); length `weighted-theta` / Lazy Theta*: max "
           + _and([_f(wt[w]["length_max"], ".4f") for w in ww]) + ", median "
           + _and([_f(wt[w]["length_median"], ".4f") for w in ww]) + ", "
           + _and([f"{wt[w]['within_half_percent']} of {wt[w]['queries']}" for w in ww])
           + " within 0.5% (goal: every query)")
    return _row(what, fig)


def _sight_row(run: SpeedRecord) -> str:
    sight = run.fig("sight")
    names = [k for k in sight if k != "cubic"]
    c = sight["cubic"]
    what = (f"sight walk per lattice: {c['lines']:,} random centre-to-centre lines of 2-40 "
            "cells in an empty box at unit cell volume (`planner.search.sight_many`, "
            f"batches of {c['batch']:,} lines, one call each), ns per cell looked up / the "
            "cubic integer walk's")
    fig = ("sum / sum: " + ", ".join(f"{k} {_f(sight[k]['vs_cubic'])}" for k in names)
           + f" (cubic {_f(c['ns_per_cell'], '.1f')} ns per cell); median of the per-batch "
           "ratios " + ", ".join(f"{k} {_ci(run.ratio(f'sight walk ns per cell {k}/cubic'))}"
                                 for k in names) + " (goal 1.5)")
    return _row(what, fig)


def _plan_row(run: SpeedRecord, m: str) -> str:
    p = run.fig("plan", m)
    names = [k for k in p if k != "cubic"]
    c = p["cubic"]
    what = (f"planning per lattice on {_plan_place(m)} (cell volume {c['cell_volume']:.3g} m^3, "
            f"{c['queries']} queries solved on every lattice): A* + smoothing (`search` + "
            "`shortcut`) and Lazy Theta*, time / cubic-26's on the same queries")
    share = ", ".join(f"{k} {_f(100 * p[k]['smooth_s'] / p[k]['astar_smooth_s'], '.0f')}%"
                      for k in p)
    fig = ("A* + smoothing, sum / sum: "
           + ", ".join(f"{k} {_f(p[k]['astar_smooth_vs_cubic'])}" for k in names)
           + " (goal BCC and MCC 0.8); median of the per-query ratios "
           + ", ".join(f"{k} {_ci(run.ratio(f'A*+smoothing time {k}/cubic, {m}'))}"
                       for k in names)
           + f"; the smoothing's share of it {share}. Lazy Theta*, sum / sum: "
           + ", ".join(f"{k} {_f(p[k]['lazy_vs_cubic'])}" for k in names)
           + " (goal 1.5); median of the per-query ratios "
           + ", ".join(f"{k} {_ci(run.ratio(f'Lazy Theta* time {k}/cubic, {m}'))}"
                       for k in names))
    if "astar_search_s" in c:
        exp, cost = _per_expansion(run, [m], names, "astar")
        lexp, lcost = _per_expansion(run, [m], names, "lazy")
        fig += (". Expansions / cubic's and time per expansion / cubic's: A* "
                + ", ".join(f"{k} {_f(e)}, {_f(t)}" for k, e, t in zip(names, exp, cost,
                                                                       strict=True))
                + "; Lazy Theta* "
                + ", ".join(f"{k} {_f(e)}, {_f(t)}" for k, e, t in zip(names, lexp, lcost,
                                                                       strict=True)))
    return _row(what, fig)


def bench_block(run: SpeedRecord) -> str:
    """benchmarks/README.md's generated "Search speed" section: provenance and table."""
    head = run.data["header"]
    intro = (f"Generated from `benchmarks/speed.json` by `{REGENERATE}` (from the "
             "checkout's root); never edited by hand. The run: "
             f"`{run.data['command']}` on {_machine(run)} with "
             f"{head[1].split('; commit')[0]}. Thread CPU time per call, the sides of each "
             "comparison taking turns query by query (batch by batch for the sight walk), "
             f"each its fastest of {run.fig('floor_checked', 'repeat')} rounds; \"median of the "
             "per-query ratios\" is the Hodges-Lehmann median of the paired ratios with its "
             "95% signed-rank interval, as the `ratio` lines print it (`harness.py`).")
    rows = [_floor_row(run), _lattice_row(run), _fixed_row(run), _anyangle_row(run),
            _sight_row(run), *(_plan_row(run, m) for m in _plan_maps(run))]
    return "\n".join([intro, "", "| what | figure |", "|---|---|",
                      *(r for r in rows if r is not None)])


def regenerate(record: str | Path, *, readme: str | Path = "README.md",
               bench: str | Path = "benchmarks/README.md", check: bool = False
               ) -> list[Path]:
    """Rewrite both documents' generated blocks from the ``--json`` ``record``.

    Every input is read and both blocks made before anything is written. Returns the
    documents written (``check``: the documents that differ, nothing written).
    """
    run = load(record)
    new_blocks = {Path(readme): (readme_block(run), README_START, README_END),
                  Path(bench): (bench_block(run), BENCH_START, BENCH_END)}
    texts = {}
    for path, (text, start, end) in new_blocks.items():
        if not path.is_file():
            raise PlannerError(f"{path}: no such file (run from the checkout's root)")
        old = path.read_text()
        try:
            same = block(old, start, end) == text
            texts[path] = (old, splice(old, text, start, end), same)
        except PlannerError as exc:
            raise PlannerError(f"{path}: {exc}") from None
    if check:
        return [p for p, (_, _, same) in texts.items() if not same]
    for path, (_, new, _) in texts.items():
        write_text_atomic(path, new)
    return list(texts)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(
        prog="python -m planner.analysis.speed_docs",
        description="Rewrite the speed figures of README.md and benchmarks/README.md from "
                    "a `benchmarks/search_speed.py --json` record (run from the checkout's "
                    "root).")
    ap.add_argument("record", help="the JSON written by search_speed.py --json")
    ap.add_argument("--readme", default="README.md")
    ap.add_argument("--bench", default="benchmarks/README.md")
    ap.add_argument("--check", action="store_true",
                    help="write nothing; exit 1 when a document differs from the record")
    args = ap.parse_args(sys.argv[1:] if argv is None else argv)
    try:
        paths = regenerate(args.record, readme=args.readme, bench=args.bench,
                           check=args.check)
    except (PlannerError, OSError) as exc:
        print(f"speed_docs: {exc}", file=sys.stderr)
        return 2
    for p in paths:
        print(f"{p}: differs from {args.record}" if args.check else p)
    return 1 if args.check and paths else 0


if __name__ == "__main__":
    raise SystemExit(main())
