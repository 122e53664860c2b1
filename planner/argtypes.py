"""Argument types of the ``planner`` command line: each parses one option's text into a value
or raises :class:`argparse.ArgumentTypeError` with a one-line message."""

from __future__ import annotations

import argparse
import math
import os
import re

import numpy as np

from planner.budget import parse_size
from planner.errors import PlannerError
from planner.lattice import NAMED_LATTICES, Lattice
from planner.lattice.paper import NAMED_LATTICES_2D
from planner.npyfile import read_array


def numbers(text: str, n: int, what: str) -> np.ndarray:
    """``n`` finite comma-separated numbers, shape (n,); ``what`` names them in the error."""
    try:
        v = np.array([float(t) for t in text.replace(" ", "").split(",")])
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected {what}, got {text!r}") from None
    if v.shape != (n,) or not np.isfinite(v).all():
        raise argparse.ArgumentTypeError(f"expected {what}, got {text!r}")
    return v


#: 2 when the command line names a 2D map (a map_server YAML, the bundled floorplan), so
#: that a malformed point asks for x,y; set by :func:`planner.cli.main` before parsing
MAP_DIM: int | None = None


def vec3(text: str) -> np.ndarray:
    """A point x,y,z in metres, shape (3,); x,y (shape (2,)) for a 2D map."""
    if MAP_DIM == 2:
        return numbers(text, 2 if text.count(",") < 2 else 3,
                       "two finite numbers x,y, comma-separated (a 2D map)")
    if text.count(",") == 1:  # x,y on a 2D map (the world checks the map is 2D)
        return numbers(text, 2, "three finite numbers x,y,z (x,y on a 2D map)")
    return numbers(text, 3, "three finite numbers x,y,z, comma-separated")


def bounds(text: str) -> np.ndarray:
    """A box xmin,ymin,zmin,xmax,ymax,zmax in metres, shape (2, 3)."""
    return numbers(text, 6, "six numbers xmin,ymin,zmin,xmax,ymax,zmax").reshape(2, 3)


def positive(text: str) -> float:
    """A finite number > 0."""
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not v > 0 or v == math.inf:
        raise argparse.ArgumentTypeError(f"expected a positive number, got {text!r}")
    return v


def nonneg(text: str) -> float:
    """A finite number >= 0."""
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not v >= 0 or v == math.inf:
        raise argparse.ArgumentTypeError(f"expected a non-negative number, got {text!r}")
    return v


def int_range(lo: int, hi: int | None = None):
    """A parser of integers in ``lo..hi`` (``hi`` None: no upper limit)."""
    def parse(text: str) -> int:
        try:
            v = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected an integer, got {text!r}") from None
        if v < lo or (hi is not None and v > hi):
            span = f"at least {lo}" if hi is None else f"in {lo}..{hi}"
            raise argparse.ArgumentTypeError(f"expected an integer {span}, got {text!r}")
        return v
    return parse


def size(text: str) -> int:
    """A byte count such as ``4G`` or ``512M``."""
    try:
        return parse_size(text)
    except PlannerError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def map_file(text: str) -> str:
    """A map file, or a bundled map by name (``office``) from any folder."""
    from planner.maps import resolve  # lazy: scipy

    return str(resolve(text))


def lattice_list(text: str) -> list[str]:
    """Comma-separated lattice names."""
    names = [s.strip().lower() for s in text.split(",") if s.strip()]
    if not names:
        raise argparse.ArgumentTypeError(f"expected lattice names from {', '.join(NAMED_LATTICES)}")
    bad = [n for n in names if n not in NAMED_LATTICES + NAMED_LATTICES_2D]
    if bad:
        raise argparse.ArgumentTypeError(
            f"unknown lattice {bad[0]!r}; expected names from {', '.join(NAMED_LATTICES)}")
    return names


def explore_lattices(text: str) -> list[str]:
    """Comma-separated lattice names, or ``all``."""
    return list(NAMED_LATTICES) if text.strip() == "all" else lattice_list(text)


def fov(text: str) -> tuple[float, float]:
    """A field of view ``h,v`` in degrees (0 < h <= 360, 0 <= v <= 90)."""
    h, v = numbers(text, 2, "field of view")
    if not (0 < h <= 360 and 0 <= v <= 90):
        raise argparse.ArgumentTypeError(f"field of view must be 0<h<=360, 0<=v<=90 degrees, "
                                         f"got {text!r}")
    return float(h), float(v)


def _generator_file(text: str) -> np.ndarray:
    """The matrix of a ``.npy`` file through the checked reader (declared size against the
    file and the budget, no pickles, no trailing data): real, finite, 2x2 or 3x3."""
    try:
        with open(text, "rb") as f:
            g = read_array(f, os.fstat(f.fileno()).st_size, text)
    except OSError as exc:
        raise argparse.ArgumentTypeError(f"{text}: cannot read a matrix: "
                                         f"{exc.strerror or exc}") from None
    except PlannerError as exc:
        raise argparse.ArgumentTypeError(" ".join(str(exc).split())) from None
    if g.dtype.kind not in "iuf" or g.shape not in ((2, 2), (3, 3)):
        raise argparse.ArgumentTypeError(f"{text}: a generator is a real 2x2 or 3x3 matrix, "
                                         f"got {g.dtype} of shape {g.shape}")
    g = g.astype(np.float64)
    if not np.isfinite(g).all():
        raise argparse.ArgumentTypeError(f"{text}: generator entries must be finite")
    return g


def generator(text: str):
    """A custom lattice: ``"a,b,c;d,e,f;g,h,i"`` (rows of G) or a ``.npy`` file."""
    if text.endswith(".npy"):
        g = _generator_file(text)
    else:
        rows = [r for r in text.split(";") if r.strip()]
        try:
            g = np.array([[float(t) for t in r.split(",")] for r in rows])
        except ValueError:
            raise argparse.ArgumentTypeError(
                f"expected rows 'a,b,c;d,e,f;g,h,i', got {text!r}") from None
    try:
        with np.errstate(over="raise", invalid="raise"):  # 1e300 entries: no overflow warning
            return Lattice(g, name="custom")
    except PlannerError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None
    except FloatingPointError:
        raise argparse.ArgumentTypeError(f"{text}: generator entries too large (its "
                                         f"determinant overflows)") from None


def pose6(text: str) -> np.ndarray:
    """A pose x,y,z (m),roll,pitch,yaw (degrees), shape (6,)."""
    return numbers(text, 6, "six numbers x,y,z,roll,pitch,yaw")


# -- the command line before argparse reads it ----------------------------------------
# options whose values may start with "-" (negative coordinates)
_VECTOR_OPTIONS = ("--start", "--goal", "--bounds", "--generator", "--init")
# options of every command, accepted before or after the command name
_GLOBAL_OPTIONS = ("--memory-budget", "--max-expansions")
_NUMBERISH = re.compile(r"^-[0-9.]")


def _join_negative_values(argv: list[str]) -> list[str]:
    """``--start -2.96,-0.05,1`` -> ``--start=-2.96,-0.05,1`` (argparse would read the value
    as an option)."""
    out, i = [], 0
    while i < len(argv):
        a = argv[i]
        if a in _VECTOR_OPTIONS and i + 1 < len(argv) and _NUMBERISH.match(argv[i + 1]):
            out.append(f"{a}={argv[i + 1]}")
            i += 2
            continue
        out.append(a)
        i += 1
    return out


def _hoist_global_options(argv: list[str]) -> list[str]:
    """Move :data:`_GLOBAL_OPTIONS` (with their values) in front of the command name, so
    ``planner plan map --memory-budget 2G`` works as ``planner --memory-budget 2G plan``."""
    head, rest, i = [], [], 0
    while i < len(argv):
        a = argv[i]
        if a == "--":
            rest += argv[i:]
            break
        if a.split("=", 1)[0] in _GLOBAL_OPTIONS:
            take = 1 if "=" in a or i + 1 == len(argv) else 2
            head += argv[i:i + take]
            i += take
            continue
        rest.append(a)
        i += 1
    return head + rest


def names_2d_map(arg: str) -> bool:
    """``arg`` names a 2D map (a map_server YAML or the bundled floorplan): the parser's
    messages about points then ask for x,y."""
    return arg == "floorplan" or arg.lower().endswith((".yaml", ".yml"))


def command_line(argv: list[str]) -> list[str]:
    """``argv`` as argparse should read it: negative vector values joined to their option,
    the global options moved in front of the command name."""
    return _hoist_global_options(_join_negative_values(argv))
