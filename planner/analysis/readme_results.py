"""Regenerate the results page and the README's "Which lattice?" numbers from one benchmark
run, so that neither can drift from the run or from each other.

``planner bench`` writes, beside its ``report.md``, ``results_section.md`` (the results
page: provenance, time to the delivered path, paired table and sentences, queries each
lattice cannot run, orientation test, figures, per-map rows and decision table) and
``readme_section.md`` (the README block: the time to the delivered path, where checks and
time disagree, what the orientation test supports, the decision table). From the
checkout's root::

    python -m planner.analysis.readme_results RUN_DIR

copies the run's report and figures to ``benchmarks/figures/<suite>/`` (when the run is
not already there), writes ``benchmarks/results.md`` (the section between its
``<!-- results:start -->`` / ``<!-- results:end -->`` markers, the page created when
absent) and replaces the README's block between ``<!-- which-lattice:start -->`` and
``<!-- which-lattice:end -->``. Both are written atomically, after every input was read.
``--page`` and ``--readme`` name other targets; ``python -m
planner.analysis.readme_results RUN_DIR PAGE.md`` writes that one page only.
"""

from __future__ import annotations

import argparse
import os
import re
import shutil
import sys
from pathlib import Path

from planner.errors import PlannerError
from planner.fsutil import write_text_atomic

__all__ = ["START", "END", "README_START", "README_END", "splice", "update_readme",
           "regenerate", "block", "recorded_sha256"]

START = "<!-- results:start -->"
END = "<!-- results:end -->"
README_START = "<!-- which-lattice:start -->"
README_END = "<!-- which-lattice:end -->"
PUBLISHED = ("report.md", "results_section.md", "readme_section.md")


def splice(readme: str, section: str, start: str = START, end: str = END) -> str:
    """``readme`` with the text between the markers replaced by ``section``.

    >>> splice("a\\n<!-- results:start -->\\nold\\n<!-- results:end -->\\nb", "new")
    'a\\n<!-- results:start -->\\nnew\\n<!-- results:end -->\\nb'
    """
    i, j = readme.find(start), readme.find(end)
    if i < 0 or j < 0 or j < i:
        raise PlannerError(f"no '{start}' ... '{end}' markers in that order")
    return readme[:i + len(start)] + "\n" + section.strip("\n") + "\n" + readme[j:]


def block(text: str, start: str = README_START, end: str = README_END) -> str:
    """The text between the markers (stripped); PlannerError without them."""
    i, j = text.find(start), text.find(end)
    if i < 0 or j < 0 or j < i:
        raise PlannerError(f"no '{start}' ... '{end}' markers in that order")
    return text[i + len(start):j].strip("\n")


def recorded_sha256(page: str) -> tuple[str, str]:
    """(suite file name, sha256) a results page records ("suite file sha256: `...`")."""
    m = re.search(r"suite `[^`]*` \(([^)]*)\), suite file sha256: `([0-9a-f]+|unknown)`",
                  page)
    if not m:
        raise PlannerError("the page records no suite file sha256")
    return m.group(1), m.group(2)


def _section(run_dir: Path, name: str) -> str:
    src = run_dir / name
    if not src.is_file():
        raise PlannerError(f"{src}: no generated section (run `planner bench ... "
                           f"--report-only --out {run_dir}` with this version first)")
    return src.read_text()


def _relink(section: str, run_dir: Path, target: Path) -> str:
    rel = Path(os.path.relpath(run_dir.resolve(), target.resolve().parent))
    return re.sub(r"!\[([^\]]*)\]\(([^)/]+\.png)\)",
                  lambda m: f"![{m.group(1)}]({(rel / m.group(2)).as_posix()})", section)


def _page_text(page: Path, run_dir: Path, section: str) -> str:
    if page.is_file():
        return splice(page.read_text(), section)
    rel = Path(os.path.relpath(run_dir.resolve(), page.resolve().parent))
    head = (f"# Benchmark results\n\nGenerated from the run in `{rel.as_posix()}` by "
            f"`python -m planner.analysis.readme_results` (from the checkout's root); never "
            f"edited by hand.\n\n{START}\n{END}\n")
    return splice(head, section)


def update_readme(run_dir: str | Path, readme: str | Path) -> Path:
    """Splice ``run_dir/results_section.md`` into the page ``readme`` (atomically; a new
    page when it does not exist); returns the path.

    Raises
    ------
    PlannerError
        No generated section in ``run_dir`` or no markers in an existing page.
    """
    run_dir, readme = Path(run_dir), Path(readme)
    section = _relink(_section(run_dir, "results_section.md"), run_dir, readme)
    try:
        text = _page_text(readme, run_dir, section)
    except PlannerError as exc:
        raise PlannerError(f"{readme}: {exc}") from None
    write_text_atomic(readme, text)
    return readme


def _suite_name(section: str) -> str:
    m = re.match(r"Suite `([^`]+)`", section)
    if not m:
        raise PlannerError("results_section.md names no suite")
    return m.group(1)


def regenerate(run_dir: str | Path, *, page: str | Path = "benchmarks/results.md",
               readme: str | Path = "README.md",
               publish: str | Path | None = None) -> list[Path]:
    """Publish a run: its report and figures to ``publish`` (default
    ``benchmarks/figures/<suite>`` beside ``page``), the results page ``page`` and the
    README's generated block. Every input is read and every target checked before anything
    is written. Returns the files written.
    """
    run_dir, page, readme = Path(run_dir), Path(page), Path(readme)
    results = _section(run_dir, "results_section.md")
    section = _section(run_dir, "readme_section.md")
    if not readme.is_file():
        raise PlannerError(f"{readme}: no such file (run from the checkout's root, or pass "
                           "--readme)")
    try:
        new_readme = splice(readme.read_text(), section, README_START, README_END)
    except PlannerError as exc:
        raise PlannerError(f"{readme}: {exc}") from None
    dest = Path(publish) if publish else page.parent / "figures" / _suite_name(results)
    same = dest.resolve() == run_dir.resolve()
    files = [] if same else [f for f in sorted(run_dir.glob("*.png"))] + [
        run_dir / n for n in PUBLISHED if (run_dir / n).is_file()]
    try:
        new_page = _page_text(page, dest, _relink(results, dest, page))
    except PlannerError as exc:
        raise PlannerError(f"{page}: {exc}") from None
    written = []
    if files:
        dest.mkdir(parents=True, exist_ok=True)
        for f in files:
            tmp = dest / f".{f.name}.tmp"
            shutil.copyfile(f, tmp)
            os.replace(tmp, dest / f.name)
            written.append(dest / f.name)
    write_text_atomic(page, new_page)
    write_text_atomic(readme, new_readme)
    return [*written, page, readme]


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(
        prog="python -m planner.analysis.readme_results",
        description="Regenerate benchmarks/results.md and the README's 'Which lattice?' "
                    "block from a planner bench run (run from the checkout's root).")
    ap.add_argument("run_dir", help="the folder of a planner bench run (--out)")
    ap.add_argument("page_only", nargs="?", default=None,
                    help="write only this results page (the old form)")
    ap.add_argument("--page", default="benchmarks/results.md")
    ap.add_argument("--readme", default="README.md")
    ap.add_argument("--publish", default=None,
                    help="folder for the report and figures (default: "
                         "benchmarks/figures/<suite>)")
    args = ap.parse_args(sys.argv[1:] if argv is None else argv)
    try:
        if args.page_only:
            print(update_readme(args.run_dir, args.page_only))
        else:
            for p in regenerate(args.run_dir, page=args.page, readme=args.readme,
                                publish=args.publish):
                print(p)
    except (PlannerError, OSError) as exc:
        print(f"readme_results: {exc}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
