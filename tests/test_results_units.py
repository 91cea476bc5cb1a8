"""One unit convention in machine-readable results: every rate in every committed results CSV is
a fraction in [0, 1] (a difference of two in [-1, 1]); percent is for printing only."""

from __future__ import annotations

import re
from pathlib import Path

import pandas as pd
import pytest

RESULTS = Path(__file__).resolve().parents[1] / "results"
RATES = {"accuracy", "balanced_accuracy", "precision", "recall", "f1", "ap", "share", "rho"}
DIFFERENCES = {"diff"}  # paired differences: in [-1, 1]


def _base(column: str) -> str:
    """The metric a column holds: ``paper_f1_pooled_mean`` -> ``f1``."""
    base = re.sub(r"^(paper_|val_)", "", column)
    base = re.sub(r"(_mean|_std|_spread|_ci_low|_ci_high)$", "", base)
    return re.sub(r"_pooled$", "", base)


CSVS = sorted(RESULTS.rglob("*.csv"))


def test_there_are_results_to_check():
    assert len(CSVS) >= 15 and (RESULTS / "table1.csv") in CSVS


@pytest.mark.parametrize("path", CSVS, ids=lambda p: str(p.relative_to(RESULTS)))
def test_rate_columns_are_fractions(path):
    table = pd.read_csv(path)
    paired = {"diff", "ci_low", "ci_high"} <= set(table.columns)
    for column in table.select_dtypes("number").columns:
        values = table[column].dropna()
        if paired and column in ("diff", "ci_low", "ci_high"):
            assert values.between(-1, 1).all(), (path.name, column)
        elif _base(column) in RATES:
            low = -1 if column == "rho" or column.startswith("rho") else 0
            assert values.between(low, 1).all(), (path.name, column, values.max())


def test_the_column_names_say_what_they_hold():
    for name in ("table1.csv", "table_external.csv"):
        columns = set(pd.read_csv(RESULTS / name).columns)
        assert {"f1_mean", "precision_mean", "recall_mean", "f1_pooled_mean"} <= columns, name
