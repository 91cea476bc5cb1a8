"""Markdown cells of the studies' tables: a rate in percent, a value with its interval, a
signed difference interval. Rendering only; owns no statistics. Imports nothing from ``eval/``."""

from __future__ import annotations

import numpy as np

NO_VALUE = "–"


def cell(value: float | None, percent: bool = True, digits: int = 1) -> str:
    """``value`` as a cell: ×100 when ``percent``, ``digits`` decimals; "–" when missing.

    >>> cell(0.8123), cell(2.5, percent=False, digits=2), cell(float("nan"))
    ('81.2', '2.50', '–')
    """
    if value is None or not np.isfinite(value):
        return NO_VALUE
    return f"{100 * value:.{digits}f}" if percent else f"{value:.{digits}f}"


def ranged(value: float, low: float, high: float) -> str:
    """``v [lo, hi]`` in percent; ``v`` alone without an interval; "–" without a value.

    >>> ranged(0.5, 0.4, 0.6), ranged(0.5, float("nan"), 0.6)
    ('50.0 [40.0, 60.0]', '50.0')
    """
    if not np.isfinite(value):
        return NO_VALUE
    if np.isfinite(low) and np.isfinite(high):
        return f"{100 * value:.1f} [{100 * low:.1f}, {100 * high:.1f}]"
    return f"{100 * value:.1f}"


def has_interval(low: float, high: float) -> bool:
    """Whether both bounds of an interval are finite (one episode gives none)."""
    return bool(np.isfinite(low) and np.isfinite(high))


def signed_interval(low: float, high: float) -> str:
    """``[+lo, +hi]`` in percentage points (fractions in), one decimal.

    >>> signed_interval(-0.012, 0.034)
    '[-1.2, +3.4]'
    """
    return f"[{100 * low:+.1f}, {100 * high:+.1f}]"
