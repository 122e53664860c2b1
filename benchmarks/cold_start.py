"""Cold start: the README's first command on a fresh install, and the same command warm.

Usage::

    python benchmarks/cold_start.py --install           # brand-new venv, pip install SRC
    python benchmarks/cold_start.py --install editable  # brand-new venv, pip install -e SRC
    python benchmarks/cold_start.py            # no install-time cache: every kernel compiles
    python benchmarks/cold_start.py --runs 3   # warm runs to take the median of
    python benchmarks/cold_start.py --smoke    # planner --help, the package's own cache

Each run is a new Python process (``python -m planner compare office``).

``--install``: what a fresh install sees. A brand-new virtual environment (no packages but
pip), ``pip install`` of a clean copy of the checkout with its dependencies from the package
index (pip's isolated build environment runs ``setup.py``, which compiles the kernels into the
package's numba cache: :mod:`planner._warm`), then the command from the venv's ``planner``
script with an empty HOME and no ``NUMBA_CACHE_DIR``; last, ``python -m planner._warm --check``
reports from numba's dispatcher statistics how many kernels were loaded and how many compiled.

Default: each run has its own ``NUMBA_CACHE_DIR`` (it takes precedence over the package's
cache); the first run starts from an empty directory: every kernel compiles, as on a machine
whose shipped cache does not match (another CPU or numba version, or ``PLANNER_NO_WARM=1``);
the warm runs reuse what it wrote.

Also prints the time of ``import planner`` alone, and the "compile s" / "search s" columns
the command reports (JIT time is reported apart from search time). Times are wall seconds
(what a user waits for at a first command) with the processes' CPU seconds beside them
(``os.times`` of the waited-for children). No assertions: this prints figures.
"""

from __future__ import annotations

import argparse
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import harness  # noqa: E402  (the sibling module)

ROOT = harness.ROOT
COMMAND = ["-m", "planner", "compare", "office"]
SMOKE_COMMAND = ["-m", "planner", "--help"]
CPU: list[float] = []  # CPU seconds of each timed() process, in order


def timed(args: list[str], cache: str | None, site: Path = ROOT,
          home: str | None = None) -> tuple[float, str]:
    """Wall seconds and stdout of ``python args`` importing planner from ``site``, with
    ``NUMBA_CACHE_DIR=cache`` (None: unset, numba's in-tree cache) and ``HOME=home``; its
    CPU seconds are appended to :data:`CPU`."""
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}
    env["PYTHONPATH"] = str(site)
    if cache is not None:
        env["NUMBA_CACHE_DIR"] = cache
    if home is not None:
        env.update(HOME=home, XDG_CACHE_HOME=os.path.join(home, ".cache"))
    t = time.perf_counter()
    out, cpu = harness.process_cpu(lambda: subprocess.run(
        [sys.executable, *args], capture_output=True, text=True, env=env, cwd=home or ROOT))
    secs = time.perf_counter() - t
    CPU.append(cpu)
    if out.returncode != 0:
        raise SystemExit(f"{' '.join(args)} failed ({out.returncode}): {out.stderr.strip()}")
    return secs, out.stdout


def import_time(cache: str | None, runs: int = 5, **kw) -> float:
    """Median seconds of ``import planner`` in a fresh process (interpreter start excluded)."""
    code = "import time; t = time.perf_counter(); import planner; print(time.perf_counter() - t)"
    return statistics.median(float(timed(["-c", code], cache, **kw)[1]) for _ in range(runs))


def fresh_install(runs: int, mode: str) -> int:
    """Install the checkout into a brand-new virtual environment, as the README says, and time
    the README's first command from it (``mode``: "wheel" = ``pip install SRC``, "editable" =
    ``pip install -e SRC``). Dependencies come from the package index, as on a user's machine."""
    with tempfile.TemporaryDirectory(prefix="planner_install_") as tmp:
        src, venv, home = (Path(tmp) / d for d in ("src", "venv", "home"))
        home.mkdir()
        # A clean copy: pip builds in the source folder, and an earlier build/ (with its
        # kernel cache) would make the build look cheap.
        shutil.copytree(ROOT, src, ignore=shutil.ignore_patterns(
            ".git", "build", "__pycache__", "*.egg-info", ".ci", "results", ".*cache"))
        env = {k: v for k, v in os.environ.items()
               if k not in ("NUMBA_CACHE_DIR", "PYTHONPATH", "VIRTUAL_ENV")}
        env.update(HOME=str(home), XDG_CACHE_HOME=str(home / ".cache"))
        t = time.perf_counter()
        subprocess.run([sys.executable, "-m", "venv", str(venv)], check=True, env=env)
        py = str(venv / "bin" / "python")
        subprocess.run([py, "-m", "pip", "install", "-q", "--upgrade", "pip"], check=True,
                       env=env)
        target = ["-e", str(src)] if mode == "editable" else [str(src)]
        subprocess.run([py, "-m", "pip", "install", "-q", *target], check=True, env=env)
        install = time.perf_counter() - t
        shipped = len(list((src if mode == "editable" else venv).rglob("*.nbi")))
        planner_cmd = [str(venv / "bin" / "planner"), *COMMAND[2:]]

        def run(cmd: list[str]) -> tuple[float, subprocess.CompletedProcess]:
            t0 = time.perf_counter()
            out = subprocess.run(cmd, capture_output=True, text=True, env=env, cwd=home)
            if out.returncode != 0:
                raise SystemExit(f"{' '.join(cmd)} failed ({out.returncode}): "
                                 f"{out.stderr.strip()[-2000:]}")
            return time.perf_counter() - t0, out

        cold, first = run(planner_cmd)
        warm = statistics.median(run(planner_cmd)[0] for _ in range(max(1, runs)))
        _, stats = run([py, "-m", "planner._warm", "--check", *COMMAND[2:]])
    print(f"command: planner {' '.join(COMMAND[2:])}  (brand-new venv, pip install "
          f"{' '.join(target[:-1] + ['SRC'])}, empty HOME, no NUMBA_CACHE_DIR, new process each)")
    print(f"venv + install with dependencies (kernels compiled into the package cache): "
          f"{install:.0f} s; {shipped} kernel cache indexes")
    print(f"first run after install: {cold:.1f} s")
    print(f"warm run (median of {max(1, runs)}): {warm:.1f} s")
    print(stats.stderr.strip().splitlines()[-1])
    print(harness.single_ratio("first run after install / warm run", cold, warm,
                               note="wall"))
    print("\nthe first run's table:")
    print(first.stdout.rstrip())
    return 0


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--runs", type=int, default=2, help="warm runs (median reported)")
    ap.add_argument("--install", nargs="?", const="wheel", choices=("wheel", "editable"),
                    help="install into a brand-new venv first (pip install SRC, or -e SRC with "
                         "'editable'); time the command from the install")
    harness.add_arguments(ap, repeat=None)
    a = ap.parse_args(argv)
    with harness.session("cold start: the README's first command", smoke=a.smoke):
        if a.install:
            return fresh_install(a.runs, a.install)
        if a.smoke:  # the package's own kernel cache, a command that loads no kernel
            return _runs(SMOKE_COMMAND, None, 1, "the package's kernel cache")
        with tempfile.TemporaryDirectory(prefix="planner_numba_") as cache:
            return _runs(COMMAND, cache, a.runs, "fresh NUMBA_CACHE_DIR: no install-time "
                         "cache")


def _runs(command: list[str], cache: str | None, runs: int, what: str) -> int:
    """Import time, a first run and ``runs`` warm runs of ``command`` (printed)."""
    imp = import_time(cache, runs=1 if cache is None else 5)
    CPU.clear()
    cold, table = timed(command, cache)
    warm_runs = [timed(command, cache)[0] for _ in range(max(1, runs))]
    cpu_cold, cpu_warm = CPU[0], statistics.median(CPU[1:])
    warm = statistics.median(warm_runs)
    imp_warm = import_time(cache, runs=1 if cache is None else 5)
    print(f"command: python {' '.join(command)}  ({what}; new process each)")
    print(f"import planner: {imp:.2f} s (first), {imp_warm:.2f} s (warm cache)")
    print(f"first run: {cold:.1f} s wall, {cpu_cold:.1f} s CPU")
    print(f"warm run (median of {max(1, runs)}): {warm:.1f} s wall, {cpu_warm:.1f} s CPU")
    print(harness.single_ratio("first run / warm run", cold, warm, note="wall"))
    print(harness.single_ratio("first run / warm run, CPU", cpu_cold, cpu_warm))
    if command == COMMAND:
        print("\nthe first run's table (compile s = the search kernels' compilation, kept out "
              "of search s):")
        print(table.rstrip())
    return 0


if __name__ == "__main__":
    sys.exit(main())
