"""Claims as data: every comparative statement of the report, built from a results folder's
files into ``claims.csv`` (:mod:`eval.protocol.claims`: the record and its columns).

:func:`write_claims` is what ``make reproduce`` calls after the studies and before the report;
``python -m eval.readme_results`` calls it too, so a report is always rendered from the claims
of its own folder.
"""

from __future__ import annotations

from pathlib import Path

import pandas as pd

from eval.claims.benchmark import benchmark_claims
from eval.claims.study_lines import study_claims
from eval.core.result_files import write_csv
from eval.protocol.claims import FILE, to_frame


def build_claims(results: str | Path) -> pd.DataFrame:
    """Every claim the report on ``results`` states (:data:`eval.protocol.claims.COLUMNS`)."""
    results = Path(results)
    return to_frame([*benchmark_claims(results), *study_claims(results)])


def write_claims(results: str | Path) -> Path:
    """Write ``<results>/claims.csv`` from the folder's result files; returns its path."""
    results = Path(results)
    return write_csv(build_claims(results), results / FILE, index=False)
