"""Every command and Python snippet in README.md runs as written.

Each ``bash`` block runs as one shell script (``set -e``) and each ``python`` block as one
script, in a scratch folder laid out like a checkout (``../shared/data`` reachable, the
bundled maps by name), so the README's relative paths mean what they say. Blocks that use
the real data skip when it is absent. The two set-up commands (install, ``pytest``) are not
rerun from here: CI runs them, and the last test checks that ``.ci/run`` does.
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"
DATA = ROOT.parent / "shared" / "data"
SETUP_COMMANDS = ('pip install -e ".[dev,robot]"', "pytest")


def code_blocks() -> list[tuple[int, str, str]]:
    """(line number, language, code) of every fenced block in README.md."""
    blocks, lang, start, buf = [], None, 0, []
    for no, line in enumerate(README.read_text().splitlines(), 1):
        fence = re.match(r"^```(\w*)\s*$", line)
        if fence and lang is None:
            lang, start, buf = fence.group(1) or "text", no, []
        elif fence:
            blocks.append((start, lang, "\n".join(buf) + "\n"))
            lang = None
        elif lang is not None:
            buf.append(line)
    assert lang is None, f"README.md: block opened at line {start} is never closed"
    return blocks


def _is_setup(code: str) -> bool:
    lines = [ln.strip() for ln in code.splitlines() if ln.strip() and not ln.startswith("#")]
    return bool(lines) and all(any(ln.startswith(c) for c in SETUP_COMMANDS) for ln in lines)


def _commands(code: str) -> int:
    """Command lines of a bash block (continuation lines count with their command)."""
    lines = [ln for ln in code.splitlines() if ln.strip() and not ln.lstrip().startswith("#")]
    return sum(1 for k, ln in enumerate(lines) if k == 0 or not lines[k - 1].endswith("\\"))


def _tier(no: int, lang: str, code: str):
    """Blocks on the real data or running more than three commands: the slow tier."""
    slow = "../shared/data" in code or (lang == "bash" and _commands(code) > 3)
    return pytest.param(no, lang, code, id=f"line{no}",
                        marks=[pytest.mark.slow] if slow else [])


RUNNABLE = [_tier(no, lang, code) for no, lang, code in code_blocks()
            if lang in ("bash", "python") and not _is_setup(code)]


@pytest.fixture
def checkout(tmp_path: Path) -> Path:
    """A scratch folder where ``../shared/data`` and ``maps/`` resolve as in the checkout."""
    work = tmp_path / "repo"
    work.mkdir()
    if DATA.is_dir():
        (tmp_path / "shared").mkdir()
        (tmp_path / "shared" / "data").symlink_to(DATA)
    (work / "maps").symlink_to(ROOT / "maps")
    return work


@pytest.mark.parametrize("no,lang,code", RUNNABLE)
def test_readme_block_runs_as_written(no: int, lang: str, code: str, checkout: Path):
    if "../shared/data" in code and not DATA.is_dir():
        pytest.skip("the block uses ../shared/data, which is absent")
    env = dict(os.environ, MPLBACKEND="Agg")
    env.pop("PYTHONPATH", None)
    # the package under test, the way the README's install makes it importable
    env["PYTHONPATH"] = str(ROOT)
    bindir = Path(sys.executable).parent
    env["PATH"] = f"{bindir}{os.pathsep}{env.get('PATH', '')}"
    if lang == "bash":
        if shutil.which("planner", path=env["PATH"]) is None:
            pytest.skip("no planner command on PATH (install the package)")
        cmd = ["bash", "-euo", "pipefail", "-c", code]
    else:
        cmd = [sys.executable, "-c", code]
    res = subprocess.run(cmd, cwd=checkout, env=env, capture_output=True, text=True,
                         timeout=900)
    assert res.returncode == 0, (
        f"README.md line {no} ({lang}) failed with exit {res.returncode}:\n"
        f"{res.stderr[-3000:]}")


def test_ci_runs_the_readme_set_up_commands():
    blocks = [code for _, lang, code in code_blocks() if lang == "bash" and _is_setup(code)]
    assert blocks, "README.md has no set-up block"
    ci = (ROOT / ".ci" / "run").read_text()
    for code in blocks:
        for line in code.splitlines():
            for part in (p.strip() for p in line.split("&&")):
                # the first command runs under numba's cache statistics there
                want = (f"python -m planner._warm --check {part.removeprefix('planner ')}"
                        if part.startswith("planner ") else part)
                assert want in ci, f".ci/run does not run the README's {part!r}"
