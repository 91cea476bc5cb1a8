"""The verdict on a stated goal, read off an interval rather than a point estimate.

A goal ``value ≥ bar`` (or ``value ≤ bar``) is *met* only when the whole interval clears the
bar, *not met* when the whole interval misses it, and *not shown* when the interval crosses it
(the data cannot tell). Without an interval (one episode, nothing scored) the verdict is
*not shown* too: a point estimate alone never meets a goal. Every "met / not met" line of the
README and the study tables goes through :func:`verdict` and :func:`goal_line`
(docs/evaluation.md, "Goals and their intervals").
"""

from __future__ import annotations

import math

MET, NOT_MET, NOT_SHOWN = "met", "not met", "not shown"


def verdict(low: float, high: float, bar: float, at_least: bool = True) -> str:
    """:data:`MET`, :data:`NOT_MET` or :data:`NOT_SHOWN` for the goal ``value ≥ bar``
    (``at_least``) or ``value ≤ bar`` given the interval [low, high] of the value."""
    if not (_finite(low) and _finite(high)):
        return NOT_SHOWN
    if at_least:
        return MET if low >= bar else NOT_MET if high < bar else NOT_SHOWN
    return MET if high <= bar else NOT_MET if low > bar else NOT_SHOWN


def goal_line(
    goal: str,
    value: float,
    low: float,
    high: float,
    bar: float,
    at_least: bool = True,
    scale: float = 100.0,
    digits: int = 1,
    unit: str = "",
    detail: str = "",
) -> str:
    """``goal: <verdict> — <value> [<low>, <high>]<unit> (<detail>)``: one README goal line;
    values are multiplied by ``scale`` (100: percent points) for printing."""
    state = verdict(low, high, bar, at_least)
    shown = f"{_fmt(value, scale, digits)}{unit}"
    if _finite(low) and _finite(high):
        shown += f" [{_fmt(low, scale, digits)}, {_fmt(high, scale, digits)}]"
    else:
        shown += " (no interval)"
    return f"{goal}: {state} — {shown}" + (f" ({detail})" if detail else "")


def _finite(x) -> bool:
    try:
        return math.isfinite(float(x))
    except (TypeError, ValueError):
        return False


def _fmt(x: float, scale: float, digits: int) -> str:
    return "–" if not _finite(x) else f"{scale * float(x):.{digits}f}"
