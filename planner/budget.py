"""One memory budget for every step whose memory grows with the world box, the radius
stencil or the node count.

Each such step estimates its bytes first and calls :func:`require`, which refuses in one
line (``MapError`` / ``PlanError``) when the estimate is over the budget, before anything
is allocated. The budget is :func:`memory_budget`: ``PLANNER_MEMORY_BUDGET`` (bytes, or
with a suffix ``K``/``M``/``G``/``T``; the CLI's ``--memory-budget`` sets it) or else
:func:`default_memory_budget`, an eighth of the physical memory, lowered to half of an
address-space limit (``ulimit -v``) when one is set so the refusal comes before a
``MemoryError``. The budget is per step (one allocation and its scratch), not the total of
a run.
"""

from __future__ import annotations

import os
import re
import resource

from planner.errors import MapError, PlannerError

__all__ = ["ENV", "MEMORY_SHARE", "default_memory_budget", "env_token", "memory_budget",
           "parse_size", "require", "gb"]

ENV = "PLANNER_MEMORY_BUDGET"
MEMORY_SHARE = 0.125  # of physical memory: a step's peak is a few times its estimate
_UNITS = {"": 1, "b": 1, "k": 2**10, "m": 2**20, "g": 2**30, "t": 2**40}
_SIZE = re.compile(r"^\s*([0-9]*\.?[0-9]+(?:e[+-]?[0-9]+)?)\s*([kmgt]?)(?:i?b)?\s*$", re.I)


_ENV_KEY = os.environ.encodekey(ENV) if hasattr(os.environ, "encodekey") else None


def env_token() -> object:
    """A value that changes when ``PLANNER_MEMORY_BUDGET`` does (callers that remember a
    budget key on it). ``os.environ.get`` decodes the key and value on every call, which is
    a tenth of a short search's fixed cost; the mapping's raw store answers the same."""
    data = getattr(os.environ, "_data", None)
    if data is None or _ENV_KEY is None:  # pragma: no cover - another os.environ
        return os.environ.get(ENV)
    return data.get(_ENV_KEY)


def gb(nbytes: float) -> str:
    """``nbytes`` as ``"1.5 GB"`` (GiB, three significant digits)."""
    return f"{nbytes / 2**30:.3g} GB"


def parse_size(text: str | int | float) -> int:
    """Bytes from ``"4G"``, ``"512M"``, ``"1.5GB"``, ``"2e9"`` or a number (> 0).

    Raises
    ------
    PlannerError
        Not a positive size.
    """
    if isinstance(text, int | float) and not isinstance(text, bool):
        value, unit = float(text), ""
    else:
        m = _SIZE.match(str(text))
        if not m:
            raise PlannerError(f"expected a memory size such as 4G, 512M or 2e9 bytes, got "
                               f"{text!r}")
        value, unit = float(m.group(1)), m.group(2).lower()
    nbytes = value * _UNITS[unit]
    if not 1 <= nbytes < 2**63:
        raise PlannerError(f"expected a memory size of at least one byte, got {text!r}")
    return int(nbytes)


def _physical_memory() -> int:
    try:
        return os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
    except (ValueError, OSError, AttributeError):  # pragma: no cover - non-POSIX
        return 16 * 2**30


def default_memory_budget() -> int:
    """A safe share of this machine's memory (bytes): an eighth of the physical memory,
    at most half of the process's address-space limit when one is set."""
    share = int(MEMORY_SHARE * _physical_memory())
    try:
        soft, _ = resource.getrlimit(resource.RLIMIT_AS)
    except (ValueError, OSError):  # pragma: no cover - platform without RLIMIT_AS
        soft = resource.RLIM_INFINITY
    if soft != resource.RLIM_INFINITY and soft > 0:
        share = min(share, soft // 2)
    return max(1, share)


def memory_budget(override: int | None = None) -> int:
    """The budget in bytes: ``override`` if given, else ``PLANNER_MEMORY_BUDGET``, else
    :func:`default_memory_budget`."""
    if override is not None:
        return parse_size(override)
    text = os.environ.get(ENV, "").strip()
    if text:
        try:
            return parse_size(text)
        except PlannerError as exc:
            raise PlannerError(f"{ENV}: {exc}") from None
    return default_memory_budget()


def require(nbytes: float, what: str, budget: int | None = None,
            error: type[PlannerError] = MapError) -> None:
    """Refuse a step that needs ~``nbytes`` bytes over the budget, in one line.

    Parameters
    ----------
    nbytes : float
        Estimated bytes of the step (may be a float: estimates overflow int64).
    what : str
        What is built, e.g. ``"the inflation of radius 0.2 m"``.
    budget : int, optional
        Bytes allowed (default :func:`memory_budget`).
    error : type
        The exception raised (``MapError`` for maps, ``PlanError`` for queries).

    Raises
    ------
    PlannerError
        ``building {what} needs ~N GB, over the memory budget of M GB (--memory-budget)``.
    """
    limit = memory_budget(budget)
    if not nbytes <= limit:  # also refuses NaN estimates
        raise error(f"building {what} needs ~{gb(nbytes)}, over the memory budget of "
                    f"{gb(limit)} (--memory-budget)")
