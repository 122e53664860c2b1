"""Shared test settings: where the real data lives and how tests that need it are marked.

Real data is read from ``../shared/data`` relative to the repository root and never copied
into the repository; tests that need it use the ``real_data`` fixture (or the
``@pytest.mark.real_data`` marker) and are skipped cleanly when it is absent.

Two tiers: ``pytest`` runs the fast tier; tests marked ``@pytest.mark.slow`` (end-to-end
suites, signals, fuzz corpora through the CLI, read-only installs) run as well with
``pytest --slow`` (both tiers), or alone with ``pytest --slow -m slow``.
"""

from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DATA = (ROOT / ".." / "shared" / "data").resolve()


def pytest_addoption(parser):
    parser.addoption("--slow", action="store_true",
                     help="run the slow tier too (tests marked slow)")


def pytest_configure(config):
    config.addinivalue_line("markers", "real_data: needs ../shared/data (skipped when absent)")
    config.addinivalue_line("markers", "slow: slow tier, run with --slow")


def pytest_collection_modifyitems(config, items):
    if not config.getoption("--slow"):
        slow = [item for item in items if "slow" in item.keywords]
        if slow:
            config.hook.pytest_deselected(items=slow)
            items[:] = [item for item in items if "slow" not in item.keywords]
    if DATA.is_dir():
        return
    skip = pytest.mark.skip(reason="real data ../shared/data not present")
    for item in items:
        if "real_data" in item.keywords:
            item.add_marker(skip)


@pytest.fixture(scope="session")
def real_data() -> Path:
    """The real data folder; skips the test when it is absent."""
    if not DATA.is_dir():
        pytest.skip("real data ../shared/data not present")
    return DATA
