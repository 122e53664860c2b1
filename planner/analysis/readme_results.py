"""Write a results page from a benchmark run, so the page and the run cannot drift.

``planner bench`` writes ``results_section.md`` beside its ``report.md`` (the paired table
with intervals and p-values, the sentences generated from them, the rotation spread, the
dropped queries and the trade-off figures). This module writes it to a page of its own
(``benchmarks/results.md`` in the checkout), or, when the target already holds the markers::

    <!-- results:start -->
    ...generated, never edited by hand...
    <!-- results:end -->

puts it between them. Usage::

    python -m planner.analysis.readme_results results/full benchmarks/results.md

Figure links are rewritten relative to the target's folder.
"""

from __future__ import annotations

import os
import re
import sys
from pathlib import Path

from planner.errors import PlannerError
from planner.fsutil import write_text_atomic

__all__ = ["START", "END", "splice", "update_readme"]

START = "<!-- results:start -->"
END = "<!-- results:end -->"


def splice(readme: str, section: str) -> str:
    """``readme`` with the text between the markers replaced by ``section``.

    >>> splice("a\\n<!-- results:start -->\\nold\\n<!-- results:end -->\\nb", "new")
    'a\\n<!-- results:start -->\\nnew\\n<!-- results:end -->\\nb'
    """
    i, j = readme.find(START), readme.find(END)
    if i < 0 or j < 0 or j < i:
        raise PlannerError(f"README has no '{START}' ... '{END}' markers in that order")
    return readme[:i + len(START)] + "\n" + section.strip("\n") + "\n" + readme[j:]


def update_readme(run_dir: str | Path, readme: str | Path) -> Path:
    """Splice ``run_dir/results_section.md`` into ``readme`` (atomically; a new page when it
    does not exist); returns the path.

    Raises
    ------
    PlannerError
        No generated section in ``run_dir`` or no markers in the README.
    """
    run_dir, readme = Path(run_dir), Path(readme)
    src = run_dir / "results_section.md"
    if not src.is_file():
        raise PlannerError(f"{src}: no generated results section (run `planner bench` first)")
    section = src.read_text()
    rel = Path(os.path.relpath(run_dir.resolve(), readme.resolve().parent))
    section = re.sub(r"!\[([^\]]*)\]\(([^)/]+\.png)\)",
                     lambda m: f"![{m.group(1)}]({(rel / m.group(2)).as_posix()})", section)
    if readme.is_file():
        text = readme.read_text()
    else:
        text = (f"# Benchmark results\n\nGenerated from the run in `{rel.as_posix()}` by "
                f"`python -m planner.analysis.readme_results {rel.as_posix()} {readme.name}` "
                f"(from this folder); never edited by hand.\n\n{START}\n{END}\n")
    write_text_atomic(readme, splice(text, section))
    return readme


def main(argv: list[str] | None = None) -> int:
    args = sys.argv[1:] if argv is None else argv
    if len(args) != 2:
        print("usage: python -m planner.analysis.readme_results RUN_DIR PAGE.md",
              file=sys.stderr)
        return 2
    try:
        print(update_readme(*args))
    except (PlannerError, OSError) as exc:
        print(f"readme_results: {exc}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
