"""Claims as data: every comparative statement of the report is a record each study emits from
its numbers and its declared goals (``Study.claims``; :mod:`eval.protocol.claims`: the record
and its columns), collected from a results folder into ``claims.csv``. The report prints the
records' statements; nothing reads a rendered line back (:mod:`eval.claims.coverage` only scans
the report for a comparative phrase that no record states).

:func:`write_claims` is what ``make reproduce`` calls after the studies and before the report;
``python -m eval.readme_results`` calls it too, so a report is always rendered from the claims
of its own folder.
"""

from __future__ import annotations

import logging
from pathlib import Path

import pandas as pd

from eval.claims.budget import budget_claims
from eval.core.result_files import write_csv
from eval.protocol.claims import FILE, Claim, to_frame
from eval.studies import studies

log = logging.getLogger(__name__)


def study_claims(results: str | Path) -> list[Claim]:
    """Every study's claims on ``results``, in the studies' order; a study whose files this code
    cannot read states none (its report part says so)."""
    out: list[Claim] = []
    for study in studies():
        try:
            out += study.emitted(Path(results))
        except Exception as error:  # any file format this code does not read
            log.warning("%s: claims left out: %s: %s", study.name, type(error).__name__, error)
    return out + budget_claims(results)


def build_claims(results: str | Path) -> pd.DataFrame:
    """Every claim the report on ``results`` states (:data:`eval.protocol.claims.COLUMNS`)."""
    return to_frame(study_claims(results))


def write_claims(results: str | Path) -> Path:
    """Write ``<results>/claims.csv`` from the folder's result files; returns its path."""
    results = Path(results)
    return write_csv(build_claims(results), results / FILE, index=False)
