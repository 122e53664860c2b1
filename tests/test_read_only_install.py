"""A read-only install works: the package copied to a folder nobody can write, HOME pointing
to a read-only folder and no NUMBA_CACHE_DIR, so numba has no cache location and every kernel
compiles in memory. compare, explore and the PCD and OctoMap readers (each with kernels of
its own) then run there and give what they give in a normal install."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from test_io import write_bt, write_pcd

import planner
from planner.analysis.compare import compare
from planner.explore import explore
from planner.io import load_points

pytestmark = pytest.mark.slow  # every kernel compiles again in the child

RUN = """
import json, sys
from planner.analysis.compare import compare
from planner.explore import explore
from planner.io import load_points
rows = compare("office", lattices=["cubic", "fcc"], cell_volume=0.01, radius=0.1,
               progress=False)
r = explore("office", (2.5, 2.5, 1.2), (4.0, 2.5, 1.2), lattice="fcc", radius=0.25,
            cell_volume=0.05, max_steps=200)
print(json.dumps({"compare": [[row["lattice"], row["found"], row["length"]] for row in rows],
                  "explore": [r.status, len(r.trajectory), r.distance],
                  "pcd": load_points(sys.argv[1]).tolist(),
                  "bt": load_points(sys.argv[2]).tolist()}))
"""


def _results(pcd: Path, bt: Path) -> dict:
    rows = compare("office", lattices=["cubic", "fcc"], cell_volume=0.01, radius=0.1,
                   progress=False)
    r = explore("office", (2.5, 2.5, 1.2), (4.0, 2.5, 1.2), lattice="fcc", radius=0.25,
                cell_volume=0.05, max_steps=200)
    return json.loads(json.dumps({
        "compare": [[row["lattice"], row["found"], row["length"]] for row in rows],
        "explore": [r.status, len(r.trajectory), r.distance],
        "pcd": load_points(pcd).tolist(), "bt": load_points(bt).tolist()}))


def _read_only(folder: Path) -> None:
    for p in sorted(folder.rglob("*"), reverse=True) + [folder]:
        p.chmod(p.stat().st_mode & 0o555)


def _writable(folder: Path) -> None:
    for p in [folder, *folder.rglob("*")]:
        p.chmod(p.stat().st_mode | 0o200)


def test_compare_explore_and_kernel_readers_run_from_a_read_only_install(tmp_path):
    site, home = tmp_path / "site", tmp_path / "home"
    shutil.copytree(Path(planner.__file__).parent, site / "planner",
                    ignore=shutil.ignore_patterns("__pycache__"))
    home.mkdir()
    # Tests often run as root, for whom file modes do not bind: a regular file named
    # __pycache__ in every package folder and an impossible XDG cache path leave numba no
    # writable cache location either way.
    for d in [site / "planner", *(p for p in (site / "planner").rglob("*") if p.is_dir())]:
        (d / "__pycache__").write_text("")
    pcd, bt = tmp_path / "cloud.pcd", tmp_path / "map.bt"
    write_pcd(pcd, np.random.default_rng(3).uniform(0, 2, (200, 3)), "binary_compressed")
    write_bt(bt, occupied=[(16, (32768, 32768, 32768)), (15, (32770, 32768, 32768))],
             free=[(16, (32768, 32769, 32768))], res=0.25)
    _read_only(site)
    _read_only(home)
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}
    env.update(PYTHONPATH=str(site), HOME=str(home), XDG_CACHE_HOME="/proc/no-such-cache",
               MPLCONFIGDIR=str(tmp_path / "mpl"))
    try:
        res = subprocess.run([sys.executable, "-c", RUN, str(pcd), str(bt)], cwd=tmp_path,
                             env=env, capture_output=True, text=True, timeout=1800)
    finally:
        _writable(site)
        _writable(home)
    assert res.returncode == 0, res.stderr[-2000:]
    got = json.loads(res.stdout.strip().splitlines()[-1])
    assert got == _results(pcd, bt)
    assert got["explore"][0] == "reached" and all(found for _, found, _ in got["compare"])
