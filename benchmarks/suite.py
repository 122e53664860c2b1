"""Run a benchmark suite (also `planner bench`): which lattice for my map and planner?

    python benchmarks/suite.py quick              # bundled suite, ~2 minutes
    python benchmarks/suite.py full --jobs 2 --resume
    python benchmarks/suite.py my_suite.toml --scheduler tcp://host:8786

Rows are appended to OUT/results.jsonl as they finish; --resume skips finished runs.
Then OUT/summary.csv, OUT/*.png and OUT/report.md are (re)written.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from planner.bench import runner, summary
from planner.bench.suite import REPO, load_suite
from planner.errors import PlannerError
from planner.fsutil import write_text_atomic


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="planner bench", description=__doc__.splitlines()[0])
    ap.add_argument("suite", help="bundled suite name (quick, paper, full) or a TOML file")
    ap.add_argument("--out", default=None, help="output folder (default results/<suite>)")
    ap.add_argument("--jobs", type=int, default=1, help="local worker processes")
    ap.add_argument("--scheduler", default=None, help="Dask scheduler address tcp://host:port")
    ap.add_argument("--resume", action="store_true", help="keep finished rows, run the rest")
    ap.add_argument("--no-progress", action="store_true")
    ap.add_argument("--report-only", action="store_true",
                    help="no new runs: summarise the rows already in OUT/results.jsonl")
    a = ap.parse_args(argv)
    try:
        suite = load_suite(a.suite)
        out = Path(a.out or REPO / "results" / suite.name)
        if suite.kind == "paper":
            from planner.cli import _run_script

            return _run_script("paper", [*suite.paper_args, "--out", str(out)])
        if not suite.maps:
            raise PlannerError(f"suite {suite.name}: no map files found "
                               f"(skipped: {', '.join(suite.skipped) or 'none'})")
        log = (lambda m: print(m, file=sys.stderr)) if not a.no_progress else (lambda m: None)
        saved = out / "queries.json"
        if a.report_only and saved.is_file():  # no need to rebuild worlds and queries
            tasks, record = [], json.loads(saved.read_text())
        else:
            tasks, record = runner.plan_tasks(suite, log=log)
        out.mkdir(parents=True, exist_ok=True)
        write_text_atomic(saved, json.dumps(record, indent=1))
        if a.report_only:
            rows = runner.read_rows(out / "results.jsonl")
            if not rows:
                raise PlannerError(f"{out / 'results.jsonl'}: no finished runs to report")
        else:
            rows = runner.run(tasks, out / "results.jsonl", jobs=a.jobs,
                              scheduler=a.scheduler, resume=a.resume,
                              progress=not a.no_progress)
        summ = summary.summarize(rows)
        summary.write_csv(out / "summary.csv", summ)
        figs = summary.plot(rows, out)
        cmd = f"planner bench {a.suite}" + (f" --out {a.out}" if a.out else "")
        rep = summary.write_report(out, suite, rows, summ, record, figs, cmd)
    except PlannerError as exc:
        print(f"planner bench: error: {exc}", file=sys.stderr)
        return 2
    print(summary.format_summary(summ))
    print(f"\nreport: {rep}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
