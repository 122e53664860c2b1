"""Compiled kernels follow their sources: editing a helper that a kernel calls from another
module (whose machine code the kernel's cache entry holds) gives the new result on the next
run, in a writable checkout and in a read-only one."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import planner

HELPER = '''from numba import njit


@njit(_nrt=False)
def answer():
    return {}
'''
KERNEL = '''from planner._numba import njit_cached
from planner._probe_helper import answer


@njit_cached
def probe():
    return answer()
'''


def _package(tmp_path: Path) -> Path:
    site = tmp_path / "site"
    shutil.copytree(Path(planner.__file__).parent, site / "planner",
                    ignore=shutil.ignore_patterns("__pycache__"))
    (site / "planner" / "_probe_helper.py").write_text(HELPER.format(1))
    (site / "planner" / "_probe_kernel.py").write_text(KERNEL)
    return site


def _probe(site: Path) -> int:
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}
    env["PYTHONPATH"] = str(site)
    out = subprocess.run([sys.executable, "-c",
                          "from planner._probe_kernel import probe; print(probe())"],
                         env=env, cwd=site, capture_output=True, text=True, check=True)
    return int(out.stdout)


def test_an_edited_helper_is_not_served_from_a_stale_cache(tmp_path):
    site = _package(tmp_path)
    assert _probe(site) == 1
    assert list((site / "planner" / "__pycache__").glob("_probe_kernel.probe-*.nbi"))
    assert _probe(site) == 1  # from the cache
    (site / "planner" / "_probe_helper.py").write_text(HELPER.format(2))
    assert _probe(site) == 2


def test_a_read_only_tree_with_a_stale_cache_compiles_afresh(tmp_path):
    site = _package(tmp_path)
    assert _probe(site) == 1
    (site / "planner" / "_probe_helper.py").write_text(HELPER.format(3))
    for p in sorted(site.rglob("*"), reverse=True):
        p.chmod(p.stat().st_mode & 0o555)
    try:
        assert _probe(site) == 3
    finally:
        for p in site.rglob("*"):
            p.chmod(p.stat().st_mode | 0o200)
