"""How a calibrated acceptance threshold τ is printed and stored: with enough significant digits
that a tiny τ never reads as ``0.000`` (a matcher whose scores are not on [0, 1] would otherwise
seem to accept everything), and never rounded away in a results CSV."""

from __future__ import annotations

import math

import pandas as pd

TAU_COLUMNS = ("tau",)


def tau_text(tau: float | None, missing: str = "–") -> str:
    """τ for a table cell: 3 significant digits (``0.473``, ``1.24e-07``); ``missing`` for none."""
    if tau is None or (isinstance(tau, float) and math.isnan(tau)) or pd.isna(tau):
        return missing
    tau = float(tau)
    return f"{tau:.3f}" if tau == 0 or abs(tau) >= 0.01 else f"{tau:.3g}"


def rounded(table: pd.DataFrame, digits: int = 6) -> pd.DataFrame:
    """``table`` with every numeric column rounded to ``digits`` decimals except τ's, which keep
    their full value (a τ of 3e-9 would otherwise be stored as 0)."""
    keep = set(TAU_COLUMNS)
    return table.round({c: digits for c in table.columns if c not in keep})
