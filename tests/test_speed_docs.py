"""The speed figures of README.md ("Known limits") and benchmarks/README.md ("Search speed")
are generated from the committed ``benchmarks/speed.json`` by one command, so a hand edit of
either block fails here:

    python -m planner.analysis.speed_docs benchmarks/speed.json
"""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from planner.analysis.readme_results import block
from planner.analysis.speed_docs import (
    BENCH_END,
    BENCH_START,
    README_END,
    README_START,
    bench_block,
    load,
    readme_block,
    regenerate,
)
from planner.errors import PlannerError

ROOT = Path(__file__).resolve().parents[1]
RECORD = ROOT / "benchmarks" / "speed.json"
README = ROOT / "README.md"
BENCH = ROOT / "benchmarks" / "README.md"


def test_the_readme_speed_items_are_the_generators_output_for_the_committed_record():
    assert block(README.read_text(), README_START, README_END) == readme_block(load(RECORD))


def test_the_search_speed_section_is_the_generators_output_for_the_committed_record():
    assert block(BENCH.read_text(), BENCH_START, BENCH_END) == bench_block(load(RECORD))


def test_the_documents_name_the_command_that_made_the_record():
    rec = json.loads(RECORD.read_text())
    assert rec["command"].startswith("python benchmarks/search_speed.py ")
    assert not rec["smoke"]
    for doc, start, end in ((README, README_START, README_END),
                            (BENCH, BENCH_START, BENCH_END)):  # a wrapped line reads as one
        assert f"`{rec['command']}`" in " ".join(block(doc.read_text(), start, end).split())
    # the record is the harness's: every ratio the README quotes was printed as a ratio line
    assert "A* speed ours/floor Simple" in rec["ratios"]
    assert rec["ratios"]["A* speed ours/floor Simple"]["overall"] == pytest.approx(
        rec["figures"]["floor"]["Simple"]["speed"])


@pytest.fixture
def docs(tmp_path):
    """Copies of the README and the record (benchmarks/README.md's copy: BENCH.md)."""
    for src in (README, RECORD):
        shutil.copyfile(src, tmp_path / src.name)
    shutil.copyfile(BENCH, tmp_path / "BENCH.md")
    return tmp_path / "README.md", tmp_path / "speed.json"


def test_a_hand_edited_figure_is_found_and_regenerated(docs, tmp_path):
    readme, record = docs
    bench = tmp_path / "BENCH.md"
    text = readme.read_text()
    blk = block(text, README_START, README_END)
    edited = blk.replace("goal 0.9", "goal 0.8", 1)
    assert edited != blk
    readme.write_text(text.replace(blk, edited))
    assert regenerate(record, readme=readme, bench=bench, check=True) == [readme]
    assert readme.read_text() != README.read_text()  # --check writes nothing
    regenerate(record, readme=readme, bench=bench)
    assert readme.read_text() == README.read_text() and bench.read_text() == BENCH.read_text()


def test_a_smoke_record_is_refused_before_anything_is_written(docs, tmp_path):
    readme, record = docs
    rec = json.loads(record.read_text())
    rec["smoke"] = True
    record.write_text(json.dumps(rec))
    with pytest.raises(PlannerError, match="smoke run"):
        regenerate(record, readme=readme, bench=tmp_path / "BENCH.md")
    assert readme.read_text() == README.read_text()


def test_a_record_without_a_table_names_what_is_missing(docs):
    readme, record = docs
    rec = json.loads(record.read_text())
    del rec["figures"]["sight"]
    record.write_text(json.dumps(rec))
    with pytest.raises(PlannerError, match="no figure 'sight'"):
        regenerate(record, readme=readme, bench=readme)


def test_a_document_without_markers_is_refused_and_neither_is_written(docs, tmp_path):
    readme, record = docs
    bench = tmp_path / "BENCH.md"
    bench.write_text("# no markers\n")
    before = readme.read_text()
    with pytest.raises(PlannerError, match="speed:start"):
        regenerate(record, readme=readme, bench=bench)
    assert readme.read_text() == before and bench.read_text() == "# no markers\n"


def test_the_command_reports_a_missing_record_in_one_line(tmp_path):
    res = subprocess.run([sys.executable, "-m", "planner.analysis.speed_docs",
                          str(tmp_path / "nothing.json")], capture_output=True, text=True,
                         cwd=tmp_path)
    assert res.returncode == 2
    assert res.stderr.count("\n") == 1 and "nothing.json" in res.stderr


def test_check_exits_0_on_the_committed_documents():
    res = subprocess.run([sys.executable, "-m", "planner.analysis.speed_docs",
                          "benchmarks/speed.json", "--check"], capture_output=True, text=True,
                         cwd=ROOT)
    assert res.returncode == 0, res.stdout + res.stderr
