"""Atomic file output: write to a temporary file beside the target, then rename."""

from __future__ import annotations

import contextlib
import errno
import hashlib
import os
import tempfile
from collections.abc import Iterator
from pathlib import Path

NAME_MAX = 255  # bytes of one file name on the usual file systems (ext4, xfs, btrfs, tmpfs)
_RANDOM = 8  # characters mkstemp adds


def temp_prefix(name: str, suffix: str) -> str:
    """``.NAME.`` for a temporary file beside ``name``, NAME cut so that the temporary name
    (prefix, mkstemp's random characters, ``suffix``) fits in :data:`NAME_MAX` bytes."""
    room = NAME_MAX - 2 - _RANDOM - len(suffix.encode())
    cut = name.encode()[:max(room, 1)].decode(errors="ignore")
    return f".{cut}."


_STAGE: list | None = None  # (temporary path, target, clean-up) while outputs are staged


@contextlib.contextmanager
def staged_outputs() -> Iterator[None]:
    """Outputs of one command, all or nothing: inside the block every :func:`atomic_path`
    (and :func:`stage_rename`) output stays under its temporary name; when the block
    succeeds they are renamed into place (after checking that none of the targets is a
    folder), when it fails they are all removed, so no output is left from a command that
    failed at a later output."""
    global _STAGE
    outer, _STAGE = _STAGE, []
    staged = _STAGE
    try:
        yield
        for _, target, _ in staged:  # e.g. a folder where a CSV's JSON sidecar goes
            if Path(target).is_dir():
                raise IsADirectoryError(errno.EISDIR, "is a directory, not a file",
                                        str(target))
        while staged:
            tmp, target, clean = staged[0]
            try:
                os.replace(tmp, target)
            except OSError as exc:
                if exc.filename is None:  # a rename error names no file: name the output
                    raise OSError(exc.errno, exc.strerror or str(exc), str(target)) from exc
                raise
            staged.pop(0)
            if clean:
                clean()
    finally:
        _STAGE = outer
        for tmp, _, clean in staged:  # left: the block or a rename failed
            with contextlib.suppress(OSError):
                if Path(tmp).is_dir():
                    import shutil

                    shutil.rmtree(tmp)
                else:
                    os.unlink(tmp)
            if clean:
                with contextlib.suppress(OSError):
                    clean()


def stage_rename(src: Path, target: Path, clean=None) -> bool:
    """Rename ``src`` to ``target`` now, or (inside :func:`staged_outputs`) when every
    output of the command is written; ``clean`` runs after the rename. False: staged."""
    if _STAGE is None:
        os.replace(src, target)
        return True
    _STAGE.append((Path(src), Path(target), clean))
    return False


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike, keep_suffix: bool = False) -> Iterator[Path]:
    """Yield a temporary path in the target's folder; on success rename it over ``path``.

    On any exception the temporary file is removed and ``path`` is left untouched, so a
    failed or killed run never leaves a half-written output. ``keep_suffix``: the temporary
    name ends with the target's suffix too (``.x.gif.tmp.gif``), for writers that choose
    the format by the file name.
    """
    target = Path(path)
    target.parent.mkdir(parents=True, exist_ok=True)
    suffix = ".tmp" + (target.suffix if keep_suffix else "")
    fd, tmp = tempfile.mkstemp(prefix=temp_prefix(target.name, suffix), suffix=suffix,
                               dir=target.parent)
    os.close(fd)
    try:
        yield Path(tmp)
        os.chmod(tmp, file_mode())  # mkstemp makes 0600 files; outputs get the usual mode
        stage_rename(Path(tmp), target)
    except OSError as exc:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        if exc.filename is None:  # a write error (a full disk) names no file: name the output
            raise OSError(exc.errno, exc.strerror or str(exc), str(target)) from exc
        raise
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise


def file_mode() -> int:
    """0666 minus the process umask: the mode ``open(path, "w")`` would have given."""
    mask = os.umask(0)
    os.umask(mask)
    return 0o666 & ~mask


def write_text_atomic(path: str | os.PathLike, text: str) -> None:
    """Write ``text`` to ``path`` atomically."""
    with atomic_path(path) as tmp:
        tmp.write_text(text)


def sha256(path: str | os.PathLike) -> str:
    """Hex SHA-256 of a file's bytes."""
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def source_sha256(path: str | os.PathLike) -> str:
    """Hex SHA-256 of a map source: a file's bytes (:func:`sha256`), or for a folder (a
    rosbag2) the SHA-256 of one ``relative/path NUL file-sha256`` line per file, in sorted
    order, so renaming, adding or changing any file changes it."""
    p = Path(path)
    if not p.is_dir():
        return sha256(p)
    h = hashlib.sha256()
    for f in sorted(q for q in p.rglob("*") if q.is_file()):
        h.update(f"{f.relative_to(p).as_posix()}\0{sha256(f)}\n".encode())
    return h.hexdigest()
