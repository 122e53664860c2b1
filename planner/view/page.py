"""Writing a :class:`planner.view.scene.Scene` as one self-contained HTML file.

The page embeds three.js (r147, MIT, shipped in ``planner/view/assets`` with its licence) and
its OrbitControls, so it opens with no network. Arrays are embedded as base64 of their raw
little-endian bytes: cells as int16 lattice indices when they fit (6 bytes a cell, turned
into metres by the page with the generator), else int32; raw points and paths as float32
metres. When drawn, the page sets ``document.body.dataset.ready = "1"`` and exposes
``window.viewState`` (``paths[i].screen``: the CSS-pixel position of each path vertex;
``errors``: uncaught script errors) for automated checks.
"""

from __future__ import annotations

import base64
import json
import os
import re
from importlib import resources

import numpy as np

from planner.fsutil import atomic_path
from planner.view.scene import Scene

__all__ = ["render_html", "write_html"]

_STYLES = {"blocked cells": "cells", "unknown cells": "unknown", "raw points": "raw"}


def _b64(a: np.ndarray, dtype) -> str:
    return base64.b64encode(np.ascontiguousarray(a, dtype=np.dtype(dtype).newbyteorder("<"))
                            .tobytes()).decode("ascii")


def _layer(layer) -> dict:
    out = {"name": layer.name, "shown": layer.shown, "total": layer.total,
           "style": _STYLES.get(layer.name, "cells"),
           # raw points of a dense cloud hide the cells: off until asked for
           "visible": layer.name != "raw points"}
    if layer.cells is not None:
        c = np.asarray(layer.cells)
        small = not len(c) or int(np.abs(c).max()) < 2**15
        out.update(kind="cells16" if small else "cells32",
                   data=_b64(c, np.int16 if small else np.int32))
    else:
        out.update(kind="points", data=_b64(layer.points, np.float32))
    return out


def _asset(name: str) -> str:
    return (resources.files("planner.view") / "assets" / name).read_text(encoding="utf-8")


def render_html(scene: Scene) -> str:
    """The page's text (module docstring)."""
    data = {
        "title": scene.title, "generator": np.asarray(scene.generator, float).tolist(),
        "cell_size": scene.cell_size, "bounds": np.asarray(scene.bounds, float).tolist(),
        "layers": [_layer(x) for x in scene.layers],
        "paths": [{"label": p.label, "data": _b64(p.points, np.float32)} for p in scene.paths],
        "start": None if scene.start is None else [float(v) for v in scene.start],
        "goal": None if scene.goal is None else [float(v) for v in scene.goal],
        "notes": scene.notes,
    }
    # "</" inside a script would end it early
    blob = json.dumps(data, separators=(",", ":")).replace("</", "<\\/")
    title = (scene.title.replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;"))
    fill = {"__TITLE__": title, "__THREE__": _asset("three.min.js"),
            "__ORBIT__": _asset("OrbitControls.js"), "__DATA__": blob}
    # one pass, so a placeholder-like string inside the inserted text is left alone
    return re.sub("|".join(fill), lambda m: fill[m.group(0)], _asset("template.html"))


def write_html(path: str | os.PathLike, scene: Scene) -> None:
    """Write the page to ``path`` atomically."""
    with atomic_path(path) as tmp:
        tmp.write_text(render_html(scene), encoding="utf-8")
