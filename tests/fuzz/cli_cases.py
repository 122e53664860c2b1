"""Seeded command-line corpus: every reader, saved worlds, suites, arguments and OS faults.

``cli_cases(root)`` writes its inputs under ``root`` and returns :class:`Run` items in a
fixed order: the reader corpus of ``make_corpus.py`` through ``plan`` / ``compare`` /
``world`` / ``bench`` (rotating), tampered saved worlds, complete files followed by
trailing data, malformed argument values, inputs whose sizes the memory budget must refuse,
and outputs that fail with an OS error. ``strict`` runs must be refused (exit 2, one line);
the others may also be usable files (exit 0 / 1: e.g. a byte flip inside a float).
"""

from __future__ import annotations

import bz2
import io
import lzma
import random
from dataclasses import dataclass
from pathlib import Path

import numpy as np

OFFICE_QUERY = ["--start", "1,1,1", "--goal", "7.6,7.8,0.8"]
SMALL_QUERY = ["--start", "0,0,0", "--goal", "1,1,1", "--radius", "0.1"]


@dataclass(frozen=True)
class Run:
    """One command line of the corpus."""

    category: str
    argv: tuple[str, ...]
    strict: bool  # must be refused: exit 2 with one line
    out: str | None = None  # an output that must not exist afterwards when refused
    fault: str | None = None  # an OS error every output rename raises (batch.py)
    name: str = ""  # a file the error line should name
    keep: tuple[str, str] | None = None  # (folder, snapshot): must be unchanged afterwards


def reader_runs(corpus, root: Path) -> list[Run]:
    """The reader corpus (``make_corpus.py``) through the command line, one command each."""
    cases = corpus.make_corpus(root / "readers") + corpus.make_entry_corpus(root / "entry")
    runs = []
    for i, case in enumerate(cases):
        out = root / "out" / f"r{i:04d}"
        if case.loader == "suite":
            runs.append(Run(f"reader:{case.reader}", ("bench", str(case.path), "--out",
                                                        str(out), "--no-progress"),
                            False, str(out), name=case.path.name))
            continue
        if case.loader == "scenarios":  # compare reads a .3dscen beside its .3dmap
            grid = case.path.parent / f"g{i:04d}.3dmap"
            grid.write_bytes(corpus.MAP3D)
            Path(str(grid) + ".3dscen").write_bytes(case.path.read_bytes())
            runs.append(Run("reader:3dscen", ("compare", str(grid), "--lattices", "cubic",
                                              "--radius", "0", "--cell-volume", "1"),
                            False, name=".3dscen"))
            continue
        m = str(case.path)
        if case.loader == "sidecar":
            cloud = case.path.with_suffix(".xyz")
            cloud.write_bytes(corpus.xyz_text())
            m = str(cloud)
        fmt = ("--format", case.format) if case.format else ()
        kind = i % 3
        if case.loader == "voxels":
            kind = 0
        if kind == 0:
            target = str(out) + ".csv"
            argv = ("plan", m, *SMALL_QUERY, *fmt, "--out", target)
        elif kind == 1:
            target = None
            argv = ("compare", m, *SMALL_QUERY, *fmt, "--lattices", "cubic,fcc")
        else:
            target = str(out) + ".npz"
            argv = ("world", m, "--radius", "0.1", *fmt, "--out", target)
        runs.append(Run(f"reader:{case.reader}", argv, case.loader == "voxels", target,
                        name=case.path.name))
    return runs


def _npz(arrays: dict) -> bytes:
    buf = io.BytesIO()
    np.savez(buf, **arrays)
    return buf.getvalue()


def world_runs(seed_world: Path, root: Path, rng: random.Random) -> list[Run]:
    """Tampered saved worlds through ``plan``: every one must be refused."""
    from planner.world.check import digest

    raw = seed_world.read_bytes()
    with np.load(seed_world, allow_pickle=False) as z:
        good = {k: z[k] for k in z.files}
    b = good["blocked"]
    edits = {  # each edit is applied with the stored digest kept, and with it recomputed
        "emptied": {"blocked": b[:0]}, "radius5": {"radius": np.array(5.0)},
        "float_cells": {"blocked": b.astype(np.float64)}, "unsorted": {"blocked": b[::-1]},
        "dim5": {"dim": np.array(5)}, "bcc_label": {"lattice": np.array("bcc")},
        "nan_gen": {"generator": np.full((3, 3), np.nan)},
        "flat_gen": {"generator": np.zeros((3, 3))},
        "bounds_flip": {"bounds": good["bounds"][::-1].copy()},
        "bounds_shape": {"bounds": good["bounds"].ravel()},
        "neg_radius": {"radius": np.array(-1.0)}, "nan_radius": {"radius": np.array(np.nan)},
        "policy": {"unknown_policy": np.array("maybe")},
        "unknown_neg": {"unknown": np.array([-5], np.int64)},
        "unknown_unsorted": {"unknown": np.array([9, 3], np.int64)},
        "unknown_float": {"unknown": np.array([1.5])},
        "cells_far": {"blocked": (b.astype(np.int32) + 5000)},
        "cells_wide": {"blocked": np.zeros((2, 4), np.int16)},
        "radius_str": {"radius": np.array("x")}, "dim_float": {"dim": np.array(3.0)},
        "sha_bad": {"source_sha256": np.array("zz")},
        "version_str": {"version": np.array("2")}, "version_99": {"version": np.array(99)},
        "format": {"format": np.array("other")}, "lattice_int": {"lattice": np.array(3)},
    }
    out_runs, files = [], []
    for name, change in edits.items():
        for redigest in (False, True):
            d = {**good, **change}
            if redigest:
                d["digest"] = np.array(digest(d))
            files.append((f"{name}{'_d' if redigest else ''}", _npz(d)))
    # Edited values with the digest recomputed to match are a well-formed world: the digest
    # catches damage and edits by tools that do not know it, it is no signature.
    well_formed = {"w_emptied_d.npz", "w_radius5_d.npz"}
    for key in sorted(good):
        files.append((f"no_{key}", _npz({k: v for k, v in good.items() if k != key})))
    files.append(("extra_key", _npz({**good, "more": np.zeros(3)})))
    files.append(("pickled", _npz({**good, "source": np.array([None], dtype=object)})))
    cut = sorted({0, 1, 22, len(raw) // 3, len(raw) // 2, len(raw) - 100, len(raw) - 1})
    files += [(f"cut{c}", raw[:c]) for c in cut]
    for k in range(20):  # byte flips: in the zip structure, a header or the data
        flipped = bytearray(raw)
        for _ in range(rng.randint(1, 3)):
            flipped[rng.randrange(len(raw))] = rng.randrange(256)
        if bytes(flipped) != raw:
            files.append((f"flip{k}", bytes(flipped)))
            if _same_members(bytes(flipped), raw):  # a field the zip reader ignores
                well_formed.add(f"w_flip{k}.npz")
    huge = raw.replace(b"'shape': (", b"'shape': (4000000000000, ", 1)
    files += [("huge_shape", huge), ("garbage", b"PK\x03\x04 not a zip"), ("text", b"hello"),
              ("trailing", raw + b"\x00" * 64)]
    for name, data in files:
        p = root / f"w_{name}.npz"
        p.write_bytes(data)
        out_runs.append(Run("world", ("plan", str(p), *SMALL_QUERY[:4]),
                            p.name not in well_formed, name=p.name))
    return out_runs


def trailing_runs(corpus, root: Path) -> list[Run]:
    """Complete files of every fixed-size format with data after them: refused."""
    seeds = {"npy": corpus.npy(corpus.PTS), "bt": corpus.octomap(),
             "pcd": corpus.pcd("binary_compressed"), "xyz.bz2": bz2.compress(corpus.xyz_text()),
             "xyz.xz": lzma.compress(corpus.xyz_text())}
    tails = [b"\x01", b"garbage after the end", b"\x00" * 4096]
    runs = []
    for ext, data in seeds.items():
        for k, tail in enumerate(tails + [data]):  # the last: the whole file again
            if ext.startswith("xyz") and tail == data:
                continue  # concatenated streams are one valid multi-stream file
            if ext == "pcd" and not tail.strip(b"\0"):
                continue  # NUL padding after the block is what PCL itself writes
            p = root / f"t{k}.{ext}"
            p.write_bytes(data + tail)
            runs.append(Run("trailing", ("plan", str(p), *SMALL_QUERY), True, name=p.name))
    for ext in ("las", "laz"):
        las = root / f"seed.{ext}"
        if _write_las(las):
            for k, tail in enumerate(tails + [las.read_bytes()]):
                p = root / f"t{k}.{ext}"
                p.write_bytes(las.read_bytes() + tail)
                runs.append(Run("trailing", ("plan", str(p), *SMALL_QUERY), True, name=p.name))
    return runs


def _write_las(path: Path) -> bool:
    try:
        import laspy
        if path.suffix == ".laz":
            import lazrs  # noqa: F401
    except ImportError:  # the robot extra is not installed: no LAS / LAZ seed
        return False
    las = laspy.LasData(laspy.LasHeader(point_format=3, version="1.4"))
    las.x, las.y, las.z = (np.array([1.0, 2.0, 3.0]),) * 3
    las.write(str(path))
    return True


_BAD_NUMBERS = ["1e300", "1e-300", "nan", "inf", "-inf", "-1", "0", "x", "", "1,2"]


def argument_runs(root: Path, rng: random.Random) -> list[Run]:
    """Malformed option values on the bundled office map: refused before any work."""
    runs = []

    def add(*argv: str, out: str | None = None) -> None:
        runs.append(Run("args", argv, True, out))

    for v in _BAD_NUMBERS:
        add("plan", "office", *OFFICE_QUERY, "--cell-volume", v)
        if v not in ("0", "1e-300"):  # a point robot and a tiny one are fine
            add("plan", "office", *OFFICE_QUERY, "--radius", v)
    for v in ["-1e300,-1e300,-1e300,1e300,1e300,1e300", "1,1,1,0,0,0", "nan,0,0,1,1,1",
              "0,0,0,1,1", "0,0,0,1,1,1,1", "a,b,c,d,e,f"]:
        add("plan", "office", *OFFICE_QUERY, f"--bounds={v}")
    for v in ["face+", "face+x", "full+-1", "face++1", "face+ 1", "edge", "face+1000",
              "full+1e3", ""]:
        add("plan", "office", *OFFICE_QUERY, "--neighbors", v)
    for v in ["1,2", "1,2,3,4", "nan,0,0", "1e300,0,0", "x"]:
        add("plan", "office", "--start", v, "--goal", "7.6,7.8,0.8")
    for v in ["0", "-5", "x", "1e300T", "nan"]:
        add("--memory-budget", v, "plan", "office", *OFFICE_QUERY)
    for v in ["0", "-1", "1.5", "x"]:
        add("plan", "office", *OFFICE_QUERY, "--max-expansions", v)
    for v in ["astra", "ompl:nope", ""]:
        add("plan", "office", *OFFICE_QUERY, "--method", v)
    for v in ["cubic,fcc2", "", ","]:
        add("compare", "office", *OFFICE_QUERY, "--lattices", v)
    for v in ["1,2;3", "1,0,0;0,1,0;0,0,0", "nan,0,0;0,1,0;0,0,1", "x.npy"]:
        add("plan", "office", *OFFICE_QUERY, "--generator", v)
    for v in ["999", "1e300", "-1", "x"]:
        add("lattices", "--points", v)
    for opt, vals in (("--fov", ["0,30", "400,30", "360,100", "x"]),
                      ("--sensor-range", ["0", "-1", "inf", "nan"]),
                      ("--resolution", ["0", "-3", "nan"]), ("--max-steps", ["0", "-1"])):
        for v in vals:
            add("explore", "office", *OFFICE_QUERY, opt, v)
    for name in ["x.txt", "x", str(root), "/proc/x.csv"]:
        add("plan", "office", *OFFICE_QUERY, "--out", name)
    for v in ["0", "-1", "x"]:
        add("bench", "quick", "--jobs", v)
    add("plan", "no_such_map.ply", *OFFICE_QUERY)
    add("plan", str(root), *OFFICE_QUERY)
    add("plan", "office", "--start", "1,1,1")
    add("nonsense")
    # random option soup: a value where another is expected, options doubled or cut
    opts = ["--radius", "--cell-volume", "--bounds", "--neighbors", "--lattice", "--method"]
    for _ in range(10):
        argv = ["plan", "office", *OFFICE_QUERY]
        for _ in range(rng.randint(1, 3)):
            argv += [rng.choice(opts), rng.choice(_BAD_NUMBERS[:8] + ["face+", "bcc2"])]
        add(*argv)
    return runs


def budget_runs(corpus, root: Path) -> list[Run]:
    """Inputs whose declared sizes the memory budget must refuse, in one line."""
    d1 = root / "d1.bt"  # one coarse occupied leaf beside a free one (issue's case)
    d1.write_bytes(b"# Octomap OcTree binary file\nid OcTree\nsize 3\nres 0.1\ndata\n\x09\x00")
    big = root / "big.npy"
    big.write_bytes(corpus.npy(corpus.PTS).replace(b"(4, 3)", b"(400000000000, 3)"))
    suite = root / "rot.toml"
    suite.write_text(corpus.SUITE.replace("queries = 1", "queries = 1000000\n"
                                          "rotations = 1000000\nrotation = \"yaw\""))
    runs = [Run("budget", ("world", str(d1), "--radius", "0.2", "--lattice", "cubic",
                           "--out", str(root / "d1.npz")), True, str(root / "d1.npz"), "d1.bt"),
            Run("budget", ("plan", str(big), *SMALL_QUERY), True, name="big.npy"),
            Run("budget", ("bench", str(suite), "--out", str(root / "rot"), "--no-progress"),
                True, str(root / "rot"), "rot.toml"),
            Run("budget", ("lattices", "--points", "100000000000"), True),
            Run("budget", ("stats", "--samples", "100000000000", "--out",
                           str(root / "stats")), True, str(root / "stats")),
            Run("budget", ("explore", "office", *OFFICE_QUERY, "--resolution", "1e-6"), True),
            Run("budget", ("--memory-budget", "1M", "plan", "office", *OFFICE_QUERY), True)]
    for v in ["1e9", "1e12"]:  # a huge suite rotation count or any-size TOML integer
        s = root / f"rot{v}.toml"
        rot = f"queries = 1\nrotations = {int(float(v))}"
        s.write_text(corpus.SUITE.replace("queries = 1", rot))
        runs.append(Run("budget", ("bench", str(s), "--out", str(root / f"o{v}"),
                                   "--no-progress"), True, str(root / f"o{v}"), s.name))
    return runs


def os_error_runs(corpus, root: Path) -> list[Run]:
    """Outputs that fail: a read-only or missing place, and renames failing with ENOSPC,
    EACCES or EROFS. Refused in one line; nothing (not even a temporary file) is left."""
    cloud = root / "cloud.xyz"
    cloud.write_bytes(corpus.xyz_text())
    suite = root / "os_suite.toml"
    (root / "suite_map.xyz").write_bytes(corpus.xyz_text())
    suite.write_text(corpus.SUITE)
    runs = []
    for fault in ("enospc", "eacces", "erofs"):
        d = root / f"os_{fault}"
        d.mkdir()
        runs += [Run("oserror", ("world", str(cloud), "--radius", "0.1", "--out",
                                 str(d / "w.npz")), True, str(d / "w.npz"), fault),
                 Run("oserror", ("plan", str(cloud), *SMALL_QUERY, "--out", str(d / "p.csv")),
                     True, str(d / "p.csv"), fault),
                 Run("oserror", ("plan", str(cloud), *SMALL_QUERY, "--out", str(d / "p.json")),
                     True, str(d / "p.json"), fault)]
    for target in ["/proc/planner/w.npz", "/proc/w.npz", "/dev/null/w.npz"]:
        runs.append(Run("oserror", ("world", str(cloud), "--radius", "0.1", "--out", target),
                        True))
    runs.append(Run("oserror", ("bench", str(suite), "--out", "/proc/planner-bench",
                                "--no-progress"), True))
    return runs


def _same_members(data: bytes, raw: bytes) -> bool:
    """``data`` reads as the same members as the archive ``raw`` (a changed byte the zip
    reader never uses, e.g. in a local header's extra field: the same file)."""
    import zipfile

    def members(b: bytes):
        with zipfile.ZipFile(io.BytesIO(b)) as z:
            return {i.filename: z.read(i) for i in z.infolist()}

    try:
        return members(data) == members(raw)
    except Exception:  # noqa: BLE001 - any failure to read: not the same file
        return False
