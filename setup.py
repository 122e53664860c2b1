"""Build hook (the project is declared in pyproject.toml): fill numba's kernel cache at install.

``pip install .``, ``pip install -e .`` and ``pip wheel .`` all run ``build_py``; after it,
:mod:`planner._warm` compiles the kernels of the README's commands once, in a subprocess,
into the ``__pycache__`` folders of the package being built (the wheel's tree, or the source
tree for an editable install). The first ``planner compare office`` after installing then
loads compiled kernels instead of spending tens of seconds compiling them. Nothing for the
user to run; if the warm-up cannot run (no numba at build time, an error, a read-only tree),
the install goes on and the kernels compile on first use as before.
``PLANNER_NO_WARM=1`` skips it.
"""

from __future__ import annotations

import os
import subprocess
import sys
import time

from setuptools import setup
from setuptools.command.build_py import build_py

HERE = os.path.dirname(os.path.abspath(__file__))


class BuildPyWarm(build_py):
    """``build_py``, then fill the numba cache of the built (or, editable, the source) tree."""

    def run(self) -> None:
        super().run()
        if os.environ.get("PLANNER_NO_WARM"):
            return
        root = HERE if getattr(self, "editable_mode", False) else os.path.abspath(self.build_lib)
        if not os.path.isfile(os.path.join(root, "planner", "_warm.py")):
            return
        # The in-tree cache (``__pycache__`` beside the sources) is the one that travels with
        # the package: no NUMBA_CACHE_DIR. No .pyc files: pip writes its own.
        env = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}
        # pip exposes its isolated build environment (numpy, scipy, numba) through PYTHONPATH:
        # the package root goes in front of it, never in its place.
        path = [root, *filter(None, os.environ.get("PYTHONPATH", "").split(os.pathsep))]
        env.update(PYTHONPATH=os.pathsep.join(path), PYTHONDONTWRITEBYTECODE="1")
        # said before the long step (pip shows it with -v; its default output only shows
        # "Building ..." until the build ends)
        print("planner: compiling the numba kernels into the package cache (2-3 minutes on "
              "two cores; PLANNER_NO_WARM=1 skips it and they compile on first use) ...",
              flush=True)
        t = time.perf_counter()
        try:
            res = subprocess.run([sys.executable, "-m", "planner._warm"], cwd=root, env=env,
                                 capture_output=True, text=True, timeout=1800)
            ok, why = res.returncode == 0, (res.stderr or "").strip().splitlines()[-1:]
        except (OSError, subprocess.TimeoutExpired) as exc:
            ok, why = False, [str(exc)]
        secs = time.perf_counter() - t
        if ok:
            print(f"planner: numba kernels compiled into the package cache ({secs:.0f} s)")
        else:
            print(f"planner: kernel cache not filled at install ({' '.join(why)}); the "
                  "kernels compile on first use instead", file=sys.stderr)


setup(cmdclass={"build_py": BuildPyWarm})
