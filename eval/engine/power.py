"""What a two-view table's sample can resolve: the half-widths of its intervals against the power
goals (the best-against-runner-up difference within ±5 points in every condition, every single
row's F1 within ±8 points). A design property of the split sizes, read off the written tables;
stated as measured half-widths, not as a verdict."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from eval.engine.power_analysis import GOAL

DIFFERENCE_GOAL_PP = 100 * GOAL
"""Half-width goal (percentage points) of the best-against-runner-up F1 interval per condition;
the clusters it needs: :mod:`eval.engine.power_analysis` (``power_analysis.csv``)."""
ROW_GOAL_PP = 8.0
"""Half-width goal (percentage points) of every single row's F1 interval."""
REFERENCE_ROWS = ("oracle", "prior")


def _half_widths(low: pd.Series, high: pd.Series) -> np.ndarray:
    return 100 * (high.to_numpy(dtype=float) - low.to_numpy(dtype=float)) / 2


def power_line(results: str | Path, name: str) -> str | None:
    """One report line for ``results/table_<name>.csv`` and its ``_intervals.csv``: per preset
    the best-against-runner-up half-width, the widest single-row F1 half-width and how many rows
    exceed :data:`ROW_GOAL_PP` (None without both files)."""
    results = Path(results)
    table_path, interval_path = results / f"table_{name}.csv", results / f"table_{name}_intervals.csv"  # fmt: skip
    if not table_path.is_file() or not interval_path.is_file():
        return None
    table, intervals = pd.read_csv(table_path), pd.read_csv(interval_path)
    rows = table[~table["matcher"].isin(REFERENCE_ROWS)].dropna(subset=["f1_low", "f1_high"])
    if rows.empty or intervals.empty:
        return None
    diff = _half_widths(intervals["ci_low"], intervals["ci_high"])
    per_preset = ", ".join(
        f"`{p}` {h:.1f}" for p, h in zip(intervals["preset"], diff, strict=True) if np.isfinite(h)
    )
    above = [str(p) for p, h in zip(intervals["preset"], diff, strict=True) if h > DIFFERENCE_GOAL_PP]  # fmt: skip
    row_half = _half_widths(rows["f1_low"], rows["f1_high"])
    widest = int(np.argmax(row_half))
    over = int((row_half > ROW_GOAL_PP).sum())
    return (
        f"Power (goals: best − runner-up F1 interval within ±{DIFFERENCE_GOAL_PP:g} points in "
        f"every preset, every row's F1 interval within ±{ROW_GOAL_PP:g}): best − runner-up "
        f"half-widths {per_preset} points"
        + (
            f" — wider than ±{DIFFERENCE_GOAL_PP:g} in {', '.join(f'`{p}`' for p in above)}"
            if above
            else " — all within"
        )  # fmt: skip
        + f"; widest row ±{row_half[widest]:.1f} (`{rows['matcher'].iloc[widest]}`, "
        f"`{rows['preset'].iloc[widest]}`), {over} of {len(rows)} rows wider than "
        f"±{ROW_GOAL_PP:g} (measured half-widths, not a verdict)"
    )


__all__ = ["DIFFERENCE_GOAL_PP", "ROW_GOAL_PP", "power_line"]
