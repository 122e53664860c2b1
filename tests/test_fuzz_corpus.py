"""The project's fuzz corpus through the real command line: one clean line, never a crash.

``tests/fuzz/cli_cases.py`` generates (seeded) every reader's malformed inputs, tampered
saved worlds, complete files with trailing data, malformed arguments, inputs the memory
budget must refuse and outputs failing with OS errors; ``tests/fuzz/fault_cases.py`` adds
user folders, suite schemas, resume files, edited worlds beside their source, readers'
budgets and staged outputs (a case whose ``keep`` folder changed is a problem). They run
in two long-lived child processes (``tests/fuzz/batch.py``: ``planner.cli.main``
in-process per case) under a 3 GB address-space cap; a case still running after
:data:`HANG` seconds is a hang (its child is killed and another takes the rest). Every
run must exit 0, 1 or 2 without a traceback; an exit 2 prints exactly one
``planner: error:`` line and writes nothing; a ``strict`` case (everything but the
byte-level reader variants, some of which are still valid files) must exit 2. Counts per
category are printed (``pytest -s``).
"""

from __future__ import annotations

import json
import os
import random
import re
import subprocess
import sys
import threading
from collections import Counter
from pathlib import Path

import pytest
from test_fuzz_readers import corpus  # tests/fuzz/make_corpus.py, loaded once

sys.path.insert(0, str(Path(__file__).parent / "fuzz"))
import cli_cases  # noqa: E402 - tests/fuzz is not a package
import fault_cases  # noqa: E402

CAP = 3 * 2**30  # bytes of address space per child: an allocation past it is a MemoryError
HANG = 60  # seconds: a case still running after this is a hang (CI machines are shared)
WORKERS = 2
REPO = Path(__file__).resolve().parents[1]
ONE_LINE = re.compile(r"^planner( \w+)?: error: \S")


class _Child:
    """One ``batch.py`` process; restarted after a hang."""

    def __init__(self) -> None:
        env = dict(os.environ, PYTHONPATH=str(REPO))
        env.pop("PLANNER_MEMORY_BUDGET", None)
        self.proc = subprocess.Popen(
            [sys.executable, str(REPO / "tests" / "fuzz" / "batch.py"), str(CAP)],
            stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True, env=env)
        assert json.loads(self.proc.stdout.readline())["ready"]

    def run(self, case) -> dict | None:
        self.proc.stdin.write(json.dumps({"argv": list(case.argv), "fault": case.fault}) + "\n")
        self.proc.stdin.flush()
        got: list = []
        reader = threading.Thread(target=lambda: got.append(self.proc.stdout.readline()),
                                  daemon=True)
        reader.start()
        reader.join(HANG)
        if not got or not got[0]:  # a hang, or the child died (a crash)
            self.proc.kill()
            self.proc.wait()
            return None
        return json.loads(got[0])

    def close(self) -> None:
        self.proc.stdin.close()
        self.proc.wait(timeout=HANG)


def _run_all(cases: list) -> list[dict | None]:
    results: list = [None] * len(cases)

    def work(k: int) -> None:
        child = _Child()
        for i in range(k, len(cases), WORKERS):
            results[i] = child.run(cases[i])
            if results[i] is None:
                child = _Child()
        child.close()

    threads = [threading.Thread(target=work, args=(k,)) for k in range(WORKERS)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    return results


# A usable map with a bad query names the endpoint; a map naming another file (a ROS map's
# image, a pose list's scan, a sidecar's cloud) may name that one.
QUERY = re.compile(r"^planner: error: (start|goal) \(")
NAMED = re.compile(r"[\w.-]+\.(pgm|xyz|json|toml|3dscen|3dmap|ya?ml)\b")


def _names(case, line: str) -> bool:
    if case.name in line or Path(case.name).stem in line or case.category == "oserror":
        return True
    if not case.strict and QUERY.search(line):  # a usable file: the query is what is wrong
        return True
    # a suite names its map (which may be anything: "/proc")
    return case.category in ("reader:suite",) or case.category.startswith("reader:") and bool(
        QUERY.search(line) or NAMED.search(line))


def _problem(case, got: dict | None) -> str | None:
    if got is None:
        return "hang or crash"
    err = got["stderr"]
    if "Traceback" in err or "MemoryError" in err or got["rc"] not in (0, 1, 2):
        return f"exit {got['rc']}: {err[-400:]!r}"
    if got["maxrss"] > CAP:
        return f"peak memory {got['maxrss']} bytes over the cap"
    if case.keep and fault_cases.snapshot(Path(case.keep[0])) != case.keep[1]:
        return f"{case.keep[0]}: files the user did not name were changed"
    if case.category == "outputs2:long" and got["rc"] != 0:
        return f"a valid output name refused: {err[-300:]!r}"
    if case.category == "outputs2:long" and [p for p in Path(case.out).parent.iterdir()
                                             if p.name.startswith(".")]:
        return "a temporary file was left"
    if got["rc"] != 2:
        return "accepted although it must be refused" if case.strict else None
    lines = err.strip().splitlines()
    if len(lines) != 1 or not ONE_LINE.match(lines[0]):
        return f"not one error line: {err[-400:]!r}"
    if case.name and not _names(case, lines[0]):
        return f"error does not name {case.name}: {lines[0]!r}"
    if case.out:
        out = Path(case.out)
        left = [p.name for p in out.parent.glob(f".{out.name}.*")] if out.parent.is_dir() else []
        if out.exists() and (out.is_file() or any(out.iterdir())) or left:
            return f"{out.name} (or a temporary file) written although the run failed"
    return None


@pytest.fixture(scope="module")
def fault_runs(tmp_path_factory) -> list:
    """The fault classes of ``tests/fuzz/fault_cases.py``."""
    return fault_cases.fault_runs(corpus, tmp_path_factory.mktemp("faults"),
                                  random.Random(46))


@pytest.fixture(scope="module")
def runs(tmp_path_factory, fault_runs) -> list:
    import planner
    from planner.world.file import save_world

    root = tmp_path_factory.mktemp("fuzz")
    rng = random.Random(25)
    cloud = root / "seed.xyz"
    cloud.write_bytes(corpus.xyz_text())
    seed_world = root / "seed_world.npz"
    save_world(planner.build_world(str(cloud), "fcc", cell_volume=0.05, radius=0.1),
               seed_world)
    for sub in ("readers", "entry", "worlds", "trailing", "args", "budget", "os", "out"):
        (root / sub).mkdir(exist_ok=True)
    return (cli_cases.reader_runs(corpus, root)
            + cli_cases.world_runs(seed_world, root / "worlds", rng)
            + cli_cases.trailing_runs(corpus, root / "trailing")
            + cli_cases.argument_runs(root / "args", rng)
            + cli_cases.budget_runs(corpus, root / "budget")
            + cli_cases.os_error_runs(corpus, root / "os")
            + fault_runs)


def test_the_corpus_is_seeded(tmp_path):
    a = cli_cases.argument_runs(tmp_path, random.Random(25))
    b = cli_cases.argument_runs(tmp_path, random.Random(25))
    assert [r.argv for r in a] == [r.argv for r in b]


def _check_all(runs: list, level: int = 1) -> Counter:
    """Run every case; assert no problem; the counts per class (the category's first
    ``level`` parts) and exit status, printed (``pytest -s``)."""
    results = _run_all(runs)
    counts, problems = Counter(), []
    for case, got in zip(runs, results, strict=True):
        group = ":".join(case.category.split(":")[:level])
        counts[group, "hang" if got is None else got["rc"]] += 1
        why = _problem(case, got)
        if why:
            problems.append(f"[{case.category}] {' '.join(case.argv)[:160]}: {why}")
    summary = ", ".join(f"{g} rc={rc}: {n}" for (g, rc), n in sorted(counts.items(),
                                                                       key=str))
    print(f"\n{len(runs)} cases: {summary}")
    assert not problems, "\n".join(problems[:80]) + f"\n({len(problems)} problems)"
    return counts


@pytest.mark.slow
def test_every_case_is_one_clean_line_or_a_usable_file(runs):
    assert len(runs) >= 1000, len(runs)
    counts = _check_all(runs)
    refused = sum(n for (_, rc), n in counts.items() if rc == 2)
    assert refused >= 0.85 * len(runs), counts


@pytest.mark.slow
def test_the_fault_classes_alone(fault_runs):
    """The classes of ``tests/fuzz/fault_cases.py`` by themselves (a shorter run of the
    same checks: ``pytest tests/test_fuzz_corpus.py --slow -s -k fault_classes``)."""
    assert len(fault_runs) >= 300, len(fault_runs)
    _check_all(fault_runs, level=2)
