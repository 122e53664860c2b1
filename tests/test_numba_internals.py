"""The numba internals the engine relies on, each exercised on its own.

The package reads a few parts of numba that are not public API (they are what lets a short
search cost microseconds rather than tens of them): a dispatcher's compiled entry point
(:mod:`planner._entry`), the MemInfo layout that :func:`planner._numba.borrow_fields`
reads, the experimental structref that holds a search's arrays, the dispatcher statistics
that :mod:`planner._warm` checks the install cache with, and llvmlite's name in the frames
of its Python callbacks (:mod:`planner._interrupt`). pyproject.toml bounds numba to the
releases these tests passed on; when a new release breaks one, the failure names what
disappeared and where the package uses it, instead of a crash deep inside a search.
"""

from __future__ import annotations

import numba
import numpy as np
import pytest
from numba import njit, types
from numba.experimental import structref

from planner._entry import entry_point, raw_entry_point
from planner._numba import borrow_fields

pytestmark = pytest.mark.filterwarnings("ignore::numba.NumbaExperimentalFeatureWarning")


def _gone(what: str, user: str) -> str:
    return (f"numba {numba.__version__}: {what} (used by {user}) is gone or changed; keep "
            "numba below this release in pyproject.toml, or port that module")


def test_dispatcher_entry_point_is_the_compiled_function():
    """planner._entry reads dispatcher.overloads[signature].entry_point."""
    @njit
    def add(a, b):
        return a + b

    for attr in ("typeof_pyval", "overloads", "compile"):
        assert hasattr(add, attr), _gone(f"Dispatcher.{attr}", "planner._entry")
    raw = raw_entry_point(add, (2, 3))
    assert raw is not add, _gone("Dispatcher.overloads[sig].entry_point", "planner._entry")
    assert raw(2, 3) == 5, _gone("Dispatcher.overloads[sig].entry_point", "planner._entry")
    assert entry_point(add, (2.0, 0.5))(2.0, 0.5) == 2.5


@structref.register
class _PairType(types.StructRef):
    def preprocess_fields(self, fields):
        return tuple((n, types.unliteral(t)) for n, t in fields)


class _Pair(structref.StructRefProxy):
    pass


structref.define_proxy(_Pair, _PairType, ["cells", "scale"])


@njit(_nrt=False)
def _read_borrowed(pair):
    cells, scale = borrow_fields(pair)
    return cells[2] * scale


def test_structref_fields_read_without_reference_counting():
    """planner._numba.borrow_fields reads a structref's payload through numba's MemInfo
    struct type (numba.core.runtime.nrtdynmod._meminfo_struct_type, field 3: the data
    pointer), as the search's Bound and D* Lite's ReplanState do."""
    pair = _Pair(np.arange(5, dtype=np.int64), 3)
    try:
        value = _read_borrowed(pair)
    except Exception as exc:  # a lowering error names numba's internals, not ours
        pytest.fail(_gone(f"structref/MemInfo lowering ({type(exc).__name__}: {exc})",
                          "planner._numba.borrow_fields"))
    assert value == 6, _gone("the MemInfo data pointer at field 3",
                             "planner._numba.borrow_fields")


def test_dispatcher_cache_statistics():
    """planner._warm --check counts cache hits and misses from dispatcher.stats."""
    @njit
    def one():
        return 1

    one()
    stats = getattr(one, "stats", None)
    for field in ("cache_hits", "cache_misses"):
        assert hasattr(stats, field), _gone(f"Dispatcher.stats.{field}", "planner._warm")
    assert one.py_func.__name__ == "one", _gone("Dispatcher.py_func", "planner._warm")


def test_llvmlite_callbacks_are_named_llvmlite():
    """planner._interrupt recognises a signal landing in llvmlite's Python callback by the
    callback's file name; the module it looks for must exist under that name."""
    import llvmlite.binding

    assert "llvmlite" in llvmlite.binding.__file__, _gone("llvmlite.binding's module path",
                                                          "planner._interrupt")


def test_prefetch_lowers_to_llvm_prefetch():
    """planner._numba.prefetch declares LLVM's ``llvm.prefetch.p0`` through
    numba.core.cgutils.get_or_insert_function (the heap's sift-down uses it); a prefetch
    changes no result, and the compiled code holds the prefetch instruction."""
    from numba.core import cgutils

    from planner._numba import prefetch

    assert hasattr(cgutils, "get_or_insert_function"), _gone(
        "numba.core.cgutils.get_or_insert_function", "planner._numba.prefetch")

    @njit(_nrt=False)
    def total(a):
        s = 0.0
        for i in range(a.shape[0]):
            prefetch(a, i + 8)  # past the end near the last items: a hint, never a fault
            s += a[i]
        return s

    a = np.arange(100.0)
    try:
        assert total(a) == a.sum()
    except Exception as exc:  # a lowering error names numba's internals, not ours
        pytest.fail(_gone(f"llvm.prefetch lowering ({type(exc).__name__}: {exc})",
                          "planner._numba.prefetch"))
    llvm = total.inspect_llvm(total.signatures[0])
    assert "llvm.prefetch" in llvm, _gone("the llvm.prefetch call", "planner._numba.prefetch")
