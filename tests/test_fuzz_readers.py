"""Every reader on a fuzz corpus of malformed inputs: a one-line MapError or a valid result.

The corpus (``tests/fuzz/make_corpus.py``: truncations, byte flips, header lies, absurd
values, wrong JSON types, empty files, directories) is generated into a temporary folder; on
top, hypothesis writes random bytes after a valid header for each binary reader.
"""

from __future__ import annotations

import importlib.util
import re
import sys
from collections import Counter
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from planner.errors import MapError
from planner.io import Obstacles, Scenarios, load_obstacles, load_scenarios, load_sidecar

# numpy warnings must not precede the one error line either.
pytestmark = pytest.mark.filterwarnings("error::RuntimeWarning")

_spec = importlib.util.spec_from_file_location(
    "make_corpus", Path(__file__).parent / "fuzz" / "make_corpus.py")
corpus = importlib.util.module_from_spec(_spec)
sys.modules["make_corpus"] = corpus  # dataclasses look their module up there
_spec.loader.exec_module(corpus)


def _load(case):
    if case.loader == "scenarios":
        return load_scenarios(case.path)
    if case.loader == "sidecar":
        return load_sidecar(case.path, **case.kwargs)
    return load_obstacles(case.path, case.format, **case.kwargs)


def _check_valid(got) -> None:
    if isinstance(got, Obstacles):
        for arr in (got.points, got.boxes, got.free_boxes):
            assert np.isfinite(arr).all()
        assert len(got.points) + len(got.boxes) > 0
    elif isinstance(got, Scenarios):
        assert len(got) > 0 and np.isfinite(got.costs).all()
    else:
        assert isinstance(got, dict)


def _outcome(case) -> str:
    """'error' (a clean one-line MapError naming a file) or 'loaded' (a valid result)."""
    try:
        got = _load(case)
    except MapError as exc:
        msg = str(exc)
        assert msg and "\n" not in msg, msg
        assert case.path.name in msg or re.search(r"[\w.-]+\.(pgm|xyz|json)\b", msg), msg
        return "error"
    _check_valid(got)
    return "loaded"


def test_fuzz_corpus_gives_map_errors_or_valid_maps(tmp_path):
    cases = corpus.make_corpus(tmp_path)
    assert len(cases) >= 200
    counts = Counter()
    for case in cases:
        counts[case.reader, _outcome(case)] += 1  # any other exception fails the test
    # Nearly every case is malformed; the few that load are legal (e.g. a flipped float byte).
    errors = sum(n for (_, kind), n in counts.items() if kind == "error")
    assert errors >= 0.8 * len(cases), counts
    for reader in ("ply", "pcd", "xyz", "npy", "bt", "3dmap", "3dscen", "poses", "rosmap",
                   "sidecar", "empty", "directory"):
        assert counts[reader, "error"] > 0, reader


def test_the_corpus_is_deterministic(tmp_path):
    a = corpus.make_corpus(tmp_path / "a")
    b = corpus.make_corpus(tmp_path / "b")
    assert [c.path.name for c in a] == [c.path.name for c in b]
    assert all(x.path.is_dir() or x.path.read_bytes() == y.path.read_bytes()
               for x, y in zip(a, b, strict=True)
               if x.path.suffix.lower() not in (".las", ".laz", ".e57"))


SEEDS = {
    "b.ply": (corpus.ply_binary(), b"end_header\n"),
    "b.pcd": (corpus.pcd("binary"), b"DATA binary\n"),
    "c.pcd": (corpus.pcd("binary_compressed"), b"DATA binary_compressed\n"),
    "m.bt": (corpus.octomap(), b"data\n"),
    "a.npy": (corpus.npy(corpus.PTS), b"\n"),
}


@pytest.mark.parametrize("name", sorted(SEEDS))
@settings(max_examples=40, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(body=st.binary(max_size=200), keep=st.integers(0, 64))
def test_random_bytes_after_a_valid_header(tmp_path, name, body, keep):
    seed, marker = SEEDS[name]
    head = seed.index(marker) + len(marker)
    path = tmp_path / name
    path.write_bytes(seed[:head + keep] + body)
    _outcome(corpus.Case(path, name))
