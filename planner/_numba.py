"""One way to compile numba kernels: cached on disk where possible, in memory otherwise.

numba's ``cache=True`` needs a writable cache location (``__pycache__`` beside the source,
``NUMBA_CACHE_DIR`` or a user cache folder under HOME). On a read-only install with no
writable HOME it raises "no locator available" when the function is *defined*, which would
make ``import planner`` fail. :func:`njit_cached` falls back to compiling in memory.

Small helpers that hot loops call (node table, heuristics, line of sight, occupancy
lookups) are ordinary compiled functions declared ``_nrt=False``: they allocate nothing and
return scalars, so they need no reference counting, and without it a call costs about what
inlined code does (LLVM inlines them where it pays). numba's own ``inline="always"`` types
and lowers a copy of the helper's body at every call site: on every helper it made the
install-time compile (``planner._warm``) more than twice as long. Only the heap operations
keep it (:mod:`planner.search._heap`). A helper that allocates keeps the runtime
(``_nrt=True``, or inherits its caller's setting).

numba keys each cached kernel on its own source file only. A kernel that calls a helper
from another module holds the helper's machine code, so it would load stale code after that
helper changes (a checkout that was edited or moved to another commit). So the package
keeps one stamp of its kernel sources beside the in-tree cache: when the sources differ
from the stamp, the in-tree cache is cleared before any kernel is defined, and if it cannot
be cleared (a read-only tree), the kernels compile in memory. An installed package never
changes, so its shipped cache stays.
(A cache under ``NUMBA_CACHE_DIR`` is the user's to manage.)
"""

from __future__ import annotations

import hashlib
import os
import tempfile
from collections.abc import Callable
from pathlib import Path

from llvmlite import ir as llvm_ir
from numba import njit, types
from numba.core import cgutils
from numba.core.errors import NumbaError
from numba.core.runtime.nrtdynmod import _meminfo_struct_type
from numba.extending import intrinsic

__all__ = ["borrow_fields", "njit_cached", "prefetch"]

_ROOT = Path(__file__).resolve().parent
_STAMP = _ROOT / "__pycache__" / "kernels.stamp"


def _sources_digest() -> str:
    """Digest of the package's kernel sources: relative path and content of every ``.py``
    file that mentions numba (only those can define, or be called by, a kernel)."""
    h = hashlib.blake2b(digest_size=16)
    for p in sorted(_ROOT.rglob("*.py")):
        text = p.read_bytes()
        if b"numba" in text or b"njit" in text:
            h.update(p.relative_to(_ROOT).as_posix().encode())
            h.update(text)
    return h.hexdigest()


def _sync_cache() -> bool:
    """Clear the in-tree kernel cache if the sources changed since it was filled.

    Returns False when the cache is stale and cannot be cleared: then nothing is cached.
    """
    digest = _sources_digest()
    try:
        if _STAMP.read_text() == digest:
            return True
    except OSError:
        pass
    try:
        for p in _ROOT.rglob("*.nb[ic]"):
            p.unlink()
        _STAMP.parent.mkdir(exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=_STAMP.parent, prefix=".stamp-")
        with os.fdopen(fd, "w") as f:
            f.write(digest)
        os.replace(tmp, _STAMP)
    except OSError:
        return not any(_ROOT.rglob("*.nb[ic]"))
    return True


_CACHE = _sync_cache()


def njit_cached(fn: Callable | None = None, **options) -> Callable:
    """``numba.njit(cache=True, **options)`` when numba can cache ``fn``, else without cache.

    Use as ``@njit_cached`` or ``@njit_cached(nogil=True)``.
    """
    def wrap(f: Callable) -> Callable:
        if not _CACHE:
            return njit(cache=False, **options)(f)
        try:
            return njit(cache=True, **options)(f)
        except RuntimeError as exc:  # numba: "cannot cache function ...: no locator available"
            if "locator" not in str(exc):
                raise
            return njit(cache=False, **options)(f)

    return wrap if fn is None else wrap(fn)


@intrinsic
def borrow_fields(typingctx, ref):
    """The fields of the structref ``ref`` (``numba.experimental.structref``) as a tuple,
    read without counting a reference: only in kernels compiled ``_nrt=False``, which
    count none (refused elsewhere), while the caller holds ``ref``.

    Reading a field the usual way counts a reference to each array of its struct on entry
    and releases it after use: for the search's :class:`~planner.search.astar.bound.Bound`
    (about 50 arrays) some 150 atomic operations, a third of a one-move search's kernel
    call. The payload pointer is read from the MemInfo as numba's own
    ``NRT_MemInfo_data_fast`` reads it (its struct type, from numba)."""
    names = list(ref.field_dict)
    sig = types.Tuple([ref.field_dict[n] for n in names])(ref)

    def codegen(context, builder, sig, args):
        if context.enable_nrt:
            raise NumbaError("borrow_fields() is for kernels compiled with _nrt=False")
        mi = cgutils.create_struct_proxy(sig.args[0])(context, builder, value=args[0]).meminfo
        info = builder.bitcast(mi, _meminfo_struct_type.as_pointer())
        data = builder.load(cgutils.gep(builder, info, 0, 3, inbounds=True))
        valtype = sig.args[0].get_data_type()
        ptr = context.data_model_manager[valtype].get_value_type().as_pointer()
        dv = cgutils.create_struct_proxy(valtype)(context, builder, ref=builder.bitcast(data, ptr))
        return context.make_tuple(builder, sig.return_type, [getattr(dv, n) for n in names])

    return sig, codegen


@intrinsic
def prefetch(typingctx, arr, i):
    """Hint the CPU to load item ``i`` of the 1-D array ``arr`` into the cache (LLVM's
    ``llvm.prefetch``, read, high locality): no bounds check, no fault, no effect on the
    result. A sift-down prefetches the next level's keys while it compares this level's,
    so a long search's big heap waits on one cache miss per level instead of two."""
    if not isinstance(arr, types.Array) or arr.ndim != 1 or not isinstance(i, types.Integer):
        return None
    sig = types.void(arr, i)

    def codegen(context, builder, sig, args):
        aty, ity = sig.args
        ary = context.make_array(aty)(context, builder, args[0])
        idx = context.cast(builder, args[1], ity, types.intp)
        ptr = builder.gep(ary.data, [idx])
        i8p = llvm_ir.IntType(8).as_pointer()
        i32 = llvm_ir.IntType(32)
        fnty = llvm_ir.FunctionType(llvm_ir.VoidType(), [i8p, i32, i32, i32])
        fn = cgutils.get_or_insert_function(builder.module, fnty, "llvm.prefetch.p0")
        builder.call(fn, [builder.bitcast(ptr, i8p), i32(0), i32(3), i32(1)])
        return context.get_dummy_value()

    return sig, codegen
