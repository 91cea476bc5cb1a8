"""A study's result file read back for its report: a CSV under the results folder, empty cells
as missing values, or None when the study did not run (no file, no rows). Imports nothing from
``eval/``."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd


def read_result(
    results: str | Path, filename: str, allow_empty: bool = False
) -> pd.DataFrame | None:
    """``results/filename`` as a table (empty cells → NaN), or None when the file is absent or,
    unless ``allow_empty``, has no rows.

    >>> read_result("/nonexistent", "table_v2x.csv") is None
    True
    """
    path = Path(results) / filename
    if not path.is_file():
        return None
    table = pd.read_csv(path, keep_default_na=False, na_values=[""])
    return None if table.empty and not allow_empty else table


def bullets(lines: list[str]) -> list[str]:
    """Report lines as Markdown bullets, each closed with a full stop."""
    return [f"- {line}." for line in lines]


def numeric_column(table: pd.DataFrame, name: str) -> pd.Series:
    """Column ``name`` as floats, NaN where missing (a table written before the column)."""
    if name not in table:
        return pd.Series(np.nan, index=table.index)
    return pd.to_numeric(table[name], errors="coerce").astype(float)
