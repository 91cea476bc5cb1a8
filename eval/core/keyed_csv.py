"""Results tables that several commands fill one dataset at a time (``regime.csv``,
``regime_sweep.csv``, ``dataset_spread.csv``): a command replaces its own datasets' rows and keeps
everyone else's."""

from __future__ import annotations

from pathlib import Path

import pandas as pd

from eval.core.result_files import write_csv


def upsert_csv(path: str | Path, rows: pd.DataFrame, key: str = "dataset") -> pd.DataFrame:
    """Write `rows` into the CSV at `path`, replacing the rows whose `key` values they carry and
    keeping the others (in their order, before the new ones); returns the whole table."""
    path = Path(path)
    if path.is_file():
        old = pd.read_csv(path, keep_default_na=False, na_values=[""])
        old = old[~old[key].isin(rows[key].unique())]
        rows = pd.concat([old, rows], ignore_index=True) if len(old) else rows
    write_csv(rows, path)
    return rows
