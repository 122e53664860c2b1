"""Cold start: a light ``import planner``, and an install-time warm-up that covers the README's
first command (no timing assertions: what is loaded and what is compiled)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from planner.lattice import Lattice
from planner.search import search
from planner.world import World

ROOT = Path(__file__).resolve().parents[1]


def _python(code: str) -> subprocess.CompletedProcess:
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          env=env, cwd=ROOT, timeout=900)


def test_import_planner_loads_no_heavy_dependency():
    res = _python("import sys, planner\n"
                  "heavy = ('numba', 'scipy', 'matplotlib', 'networkx', 'dask', 'ompl')\n"
                  "print(sorted({m.split('.')[0] for m in sys.modules} & set(heavy)))")
    assert res.returncode == 0, res.stderr[-2000:]
    assert res.stdout.strip() == "[]"


def test_public_names_still_resolve_after_a_light_import():
    res = _python("import planner, planner.lattice as L\n"
                  "print(L.Quantizer.__name__, planner.World.__name__,"
                  " planner.Lattice.named('fcc').quantize([[1.0, 2.0, 3.3]]).tolist())")
    assert res.returncode == 0, res.stderr[-2000:]
    fcc = Lattice.named("fcc").quantize([[1.0, 2.0, 3.3]]).tolist()
    assert res.stdout.strip().split(maxsplit=2) == ["Quantizer", "World", str(fcc)]


@pytest.mark.slow
def test_install_warm_up_covers_the_readme_first_command():
    """After ``planner._warm.warm()`` (what the build runs), ``planner compare office``
    compiles no kernel signature that the warm-up did not."""
    code = """
import json, sys
from numba.core.dispatcher import Dispatcher

def counts():
    out = {}
    for name, mod in list(sys.modules.items()):
        if name.startswith("planner"):
            for v in vars(mod).values():
                if isinstance(v, Dispatcher):
                    f = v.py_func
                    out[f"{f.__module__}.{f.__qualname__}"] = len(v.signatures)
    return out

from planner._warm import warm
warm()
before = counts()
from planner.cli import main
main(["compare", "office"])
after = counts()
print(json.dumps({k: n for k, n in after.items() if n > before.get(k, 0)}))
"""
    res = _python(code)
    assert res.returncode == 0, res.stderr[-2000:]
    assert json.loads(res.stdout.strip().splitlines()[-1]) == {}


def test_repeated_searches_on_a_large_dense_world_agree():
    """The cell -> node map of a dense world over 1M cells is reused between searches (and
    cleared after each): the same query twice, and its mirror, give the exact octile cost."""
    n = 127
    w = World(Lattice.named("cubic", 1.0), np.zeros((0, 3), np.int64),
              np.array([[0.0] * 3, [n - 1.0] * 3]))
    a, b = np.array([0, 0, 0]), np.array([n - 1, 60, 20])
    exact = 20 * np.sqrt(3) + 40 * np.sqrt(2) + (n - 1 - 60)
    costs = [search(w, a, b).cost, search(w, a, b).cost, search(w, b, a).cost]
    np.testing.assert_allclose(costs, exact, rtol=1e-12)
    assert w.storage == "dense"
