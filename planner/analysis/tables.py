"""One table formatter for every printed or reported table (plain text or Markdown)."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

__all__ = ["format_table", "format_value"]


def format_value(v: object) -> str:
    """A table cell: strings as given, integers exact, other numbers to 4 significant digits
    (values >= 1e5 in millions, ``12.3M``).

    >>> [format_value(v) for v in ("fcc", 12, 0.70710678, 2.5e6, 1234.5, 1e-5)]
    ['fcc', '12', '0.7071', '2.5M', '1234', '1.000e-05']
    """
    if isinstance(v, str):
        return v
    if v is None:
        return "-"
    if isinstance(v, bool | np.bool_):
        return "yes" if v else "no"
    if isinstance(v, int | np.integer):
        return str(int(v))
    x = float(v)
    if x != x:
        return "-"
    if abs(x) >= 1e5:
        return f"{x / 1e6:.1f}M"
    if abs(x) >= 1e3:
        return f"{x:.0f}"
    return f"{x:.4g}" if abs(x) >= 1e-3 or x == 0 else f"{x:.3e}"


def format_table(rows: Sequence[dict], columns: Sequence[str] | None = None, *,
                 headers: Sequence[str] | None = None, markdown: bool = False) -> str:
    """Aligned table of ``rows`` (dicts sharing keys), first column left-aligned.

    Parameters
    ----------
    rows : sequence of dict
        Cell values; non-strings go through :func:`format_value`.
    columns : sequence of str, optional
        Keys to show, in order (default: the first row's keys).
    headers : sequence of str, optional
        Column titles (default: the keys).
    markdown : bool
        A GitHub Markdown table (for reports) instead of plain text (for terminals).

    Examples
    --------
    >>> print(format_table([{"lattice": "fcc", "n": 12}, {"lattice": "cubic", "n": 6}]))
    lattice   n
    -------  --
    fcc      12
    cubic     6
    >>> print(format_table([{"a": "x", "b": 0.5}], markdown=True))
    | a | b |
    | --- | ---: |
    | x | 0.5 |
    """
    if not rows:
        return ""
    cols = list(columns) if columns is not None else list(rows[0])
    head = list(headers) if headers is not None else cols
    body = [[format_value(r.get(c, "")) for c in cols] for r in rows]
    if markdown:
        lines = ["| " + " | ".join(head) + " |",
                 "| " + " | ".join("---" if j == 0 else "---:" for j in range(len(cols))) + " |"]
        return "\n".join(lines + ["| " + " | ".join(b) + " |" for b in body])
    cells = [head, *body]
    widths = [max(len(line[j]) for line in cells) for j in range(len(cols))]
    out = []
    for i, line in enumerate(cells):
        parts = [s.ljust(w) if j == 0 else s.rjust(w)
                 for j, (s, w) in enumerate(zip(line, widths, strict=True))]
        out.append("  ".join(parts).rstrip())
        if i == 0:
            out.append("  ".join("-" * w for w in widths))
    return "\n".join(out)
