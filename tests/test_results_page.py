"""benchmarks/results.md and the README's "Which lattice?" block come from one run by one
command, agree with each other, and name the bundled suite that produced them."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest

from planner.analysis.metadata import suite_sha256
from planner.analysis.readme_results import (
    README_END,
    README_START,
    START,
    block,
    recorded_sha256,
    regenerate,
)
from planner.bench.suite import SUITES
from planner.errors import PlannerError

ROOT = Path(__file__).resolve().parents[1]
PAGE = ROOT / "benchmarks" / "results.md"
README = ROOT / "README.md"


def _claims(readme_block: str) -> list[str]:
    """The README block's numbers: its table rows and its bullet sentences."""
    out = []
    for ln in readme_block.splitlines()[1:]:  # the first line is the provenance
        if ln.startswith("| ") and not ln.startswith("| ---"):
            out.append(ln)
        elif ln.startswith("- "):
            out.append(ln[2:])
    return out


def test_the_readme_numbers_are_the_results_page_numbers():
    page, blk = PAGE.read_text(), block(README.read_text())
    claims = _claims(blk)
    assert len(claims) > 5
    missing = [c for c in claims if c not in page]
    assert not missing, f"README block lines not in benchmarks/results.md: {missing[:3]}"
    sha = re.search(r"suite file sha256 `([0-9a-f]{12})`", blk).group(1)
    version = re.search(r"lattice-planner (\S+)\)", blk).group(1)
    assert recorded_sha256(page)[1].startswith(sha)
    assert f"lattice-planner {version}" in page  # (the page keeps the run's commit and date)


def test_the_results_page_was_made_by_the_bundled_suite_it_names():
    name, sha = recorded_sha256(PAGE.read_text())
    suite = SUITES / name
    assert suite.is_file(), f"results.md names {name}, which is not a bundled suite"
    assert sha == suite_sha256(suite), (
        f"{name} changed since benchmarks/results.md was made: rerun it and "
        "`python -m planner.analysis.readme_results RUN_DIR`")


def _run_dir(tmp_path: Path) -> Path:
    run = tmp_path / "run"
    run.mkdir()
    (run / "results_section.md").write_text(
        "Suite `quick`\n\n- suite `quick` (quick.toml), suite file sha256: `abc123`\n\n"
        "| a | b |\n\n![pareto](pareto.png)\n")
    (run / "readme_section.md").write_text("Generated (suite file sha256 `abc123`)\n\n| a | b |\n")
    (run / "report.md").write_text("# report\n")
    (run / "pareto.png").write_bytes(b"png")
    return run


def test_one_command_writes_the_page_the_readme_block_and_the_figures(tmp_path):
    run = _run_dir(tmp_path)
    repo = tmp_path / "repo"
    (repo / "benchmarks").mkdir(parents=True)
    readme = repo / "README.md"
    readme.write_text(f"# x\n\n## Which lattice?\n\n{README_START}\nold 0.66\n{README_END}"
                      "\n\nrest\n")
    written = regenerate(run, page=repo / "benchmarks" / "results.md", readme=readme)
    figs = repo / "benchmarks" / "figures" / "quick"
    assert (figs / "pareto.png").read_bytes() == b"png" and (figs / "report.md").is_file()
    assert readme in written
    text = readme.read_text()
    assert "old 0.66" not in text and "| a | b |" in text and text.endswith("rest\n")
    page = (repo / "benchmarks" / "results.md").read_text()
    assert "![pareto](figures/quick/pareto.png)" in page and START in page
    assert recorded_sha256(page) == ("quick.toml", "abc123")


def test_a_readme_without_markers_is_refused_before_anything_is_written(tmp_path):
    run = _run_dir(tmp_path)
    readme = tmp_path / "README.md"
    readme.write_text("# no markers\n")
    page = tmp_path / "benchmarks" / "results.md"
    with pytest.raises(PlannerError, match="which-lattice:start"):
        regenerate(run, page=page, readme=readme)
    assert not page.exists() and not (tmp_path / "benchmarks").exists()
    assert readme.read_text() == "# no markers\n"


def test_the_command_reports_a_missing_run_in_one_line(tmp_path):
    res = subprocess.run([sys.executable, "-m", "planner.analysis.readme_results",
                          str(tmp_path / "nothing")], capture_output=True, text=True,
                         cwd=tmp_path)
    assert res.returncode == 2
    assert res.stderr.count("\n") == 1 and "results_section.md" in res.stderr


def test_an_installed_package_records_its_version_not_unknown(tmp_path):
    import shutil

    import planner

    site = tmp_path / "site"
    shutil.copytree(ROOT / "planner", site / "planner",
                    ignore=shutil.ignore_patterns("__pycache__", "*.npz", "*.ply"))
    res = subprocess.run([sys.executable, "-c", "from planner.analysis.metadata import "
                          "row_commit; print(row_commit())"], capture_output=True, text=True,
                         cwd=tmp_path, env={"PYTHONPATH": str(site), "PATH": "/usr/bin:/bin"})
    assert res.returncode == 0, res.stderr
    assert res.stdout.strip() == f"version {planner.__version__} (installed package)"
