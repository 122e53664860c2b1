"""What a report records about the run that made it: commit, package versions, CPU, date."""

from __future__ import annotations

import datetime
import functools
import os
import platform
import subprocess
from collections import Counter
from importlib import metadata
from pathlib import Path

_PACKAGES = ("lattice-planner", "numpy", "scipy", "numba", "matplotlib", "ompl", "dask",
             "distributed", "plyfile")


@functools.cache
def _commit() -> str:
    """The source checkout's commit (``+dirty`` with local changes), or, for an installed
    package (no checkout to ask), its version: ``"version 0.4.0 (installed package)"``;
    read once per process, so a row records the code that ran it."""
    root = Path(__file__).resolve().parents[2]
    if not (root / "pyproject.toml").is_file() or not (root / "planner").is_dir():
        # site-packages may sit inside another repo: its commit is not this package's
        return f"version {package_version()} (installed package)"
    try:
        sha = subprocess.run(["git", "-C", str(root), "rev-parse", "--short=12", "HEAD"],
                             capture_output=True, text=True, timeout=5, check=True).stdout.strip()
        dirty = subprocess.run(["git", "-C", str(root), "status", "--porcelain", "-uno"],
                               capture_output=True, text=True, timeout=5).stdout.strip()
    except (OSError, subprocess.SubprocessError):
        return "unknown (not a git checkout)"
    return sha + ("+dirty" if dirty else "") if sha else "unknown"


def package_version() -> str:
    """This package's version (``planner.__version__``, the one source of it)."""
    from planner import __version__  # at call time: never read from a half-imported package

    return str(__version__)


def suite_sha256(path: str | Path) -> str:
    """SHA-256 (hex) of a suite file's bytes, the identity a results page records."""
    import hashlib

    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def _cpu() -> str:
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def run_metadata(jobs: int = 1) -> dict:
    """Commit, package versions, CPU, worker count and UTC date of this run.

    >>> sorted(run_metadata(jobs=2))
    ['commit', 'cpu', 'cpu_count', 'date', 'jobs', 'packages', 'python', 'version']
    """
    versions = {}
    for name in _PACKAGES:
        try:
            versions[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            continue
    return {
        "version": package_version(),
        "commit": _commit(),
        "packages": versions,
        "python": platform.python_version(),
        "cpu": _cpu(),
        "cpu_count": os.cpu_count(),
        "jobs": int(jobs),
        "date": datetime.datetime.now(datetime.UTC).strftime("%Y-%m-%d %H:%M UTC"),
    }


def row_commit() -> str:
    """The commit a benchmark row records (:func:`_commit`, cached per process)."""
    return _commit()


def metadata_markdown(meta: dict, rows: list[dict] | None = None) -> str:
    """The metadata as Markdown bullet lines for a report; with ``rows``, also the commits
    that ran them (they differ from the report's when a run was resumed or the checkout
    changed while it ran)."""
    pk = ", ".join(f"{k} {v}" for k, v in meta["packages"].items())
    ran = Counter(r.get("commit", "not recorded") for r in rows or [])
    by = "; rows run by " + ", ".join(f"`{c}` ({n})" for c, n in ran.most_common()) \
        if ran else ""
    return "\n".join([
        f"- lattice-planner {meta.get('version', '?')}, commit: `{meta['commit']}` (this "
        f"report){by}; date: {meta['date']}",
        f"- CPU: {meta['cpu']} ({meta['cpu_count']} cores), jobs: {meta['jobs']}",
        f"- Python {meta['python']}; {pk}",
    ])
