"""The appearance-realism goals of the V2X study: ``regime.csv``'s CAD-V2X AUCs read against
their bars with their episode-bootstrap intervals (``regime_auc_intervals.csv``). Reads files
only; a point value never meets a goal."""

from __future__ import annotations

from pathlib import Path

import pandas as pd

from eval.engine.goal import Goal
from eval.protocol.claims import Claim
from eval.studies.table1.regime_cards import AUC_FILE

AUC_BAND = (0.60, 0.80)
IMAGE_AUC_MAX = 0.75
REALISM_LABEL = "CAD-V2X"


def realism_check(results: Path) -> list[str]:
    """The statements of :func:`realism_claims`, as the report prints them."""
    return [claim.statement for claim in realism_claims(results)]


def realism_claims(results: Path) -> list[Claim]:
    """The appearance-realism goals on the held-out test split (``regime.csv``'s CAD-V2X row;
    its settings were chosen on validation seeds, docs/scenarios.md), as claims: whole-feature AUC within
    :data:`AUC_BAND`, image-only AUC at most :data:`IMAGE_AUC_MAX`, each read off its
    episode-bootstrap interval (``regime_auc_intervals.csv``); without that file the values are
    points and every goal is *not shown* (a point value never meets a goal)."""
    path = Path(results) / "regime.csv"
    if not path.is_file():
        return []
    table = pd.read_csv(path).set_index("dataset")
    if REALISM_LABEL not in table.index:
        return []
    row = table.loc[REALISM_LABEL].to_dict()
    where = "over every candidate pair of the held-out test split"
    bounds = Path(results) / AUC_FILE
    intervals = pd.read_csv(bounds).set_index("dataset") if bounds.is_file() else None
    if intervals is not None and REALISM_LABEL in intervals.index:
        row |= intervals.loc[REALISM_LABEL].to_dict()
        where += f", 95 % interval over its {int(row['episodes'])} episodes"
    else:
        where = f"a point value {where}, no episode interval"
    nan = float("nan")
    low, high = AUC_BAND
    alike = row.get("same_class_auc")
    within = (
        ""
        if alike is None or pd.isna(alike)
        else (
            f"; against same-class false pairs only {alike:.3f} (appearance tells look-alikes "
            "apart little: the pooled value is high because most false pairs cross classes, a car "
            "against a sign, where DMGM's are mostly one class — docs/scenarios.md)"
        )
    )

    def goal(name: str, key: str, bar: float, at_least: bool, detail: str) -> Claim:
        text = f"appearance realism, {name} {'≥' if at_least else '≤'} {bar:.2f}"
        declared = Goal(
            "", text, (key, f"{key}_low", f"{key}_high"), bar, at_least, "fixed", 1.0, 3
        )
        return declared.claim_of(
            row[key], row.get(f"{key}_low", nan), row.get(f"{key}_high", nan), detail,
            study="v2x", subject=text, source="table_v2x.csv", clusters="simulation episodes",
        )  # fmt: skip

    return [
        goal("whole-feature AUC", "appearance_auc", low, True, where),
        goal(
            "whole-feature AUC", "appearance_auc", high, False, f"{where}; DMGM's is 0.57{within}"
        ),
        goal("image-only AUC", "image_auc", IMAGE_AUC_MAX, False, where),
    ]


__all__ = ["AUC_BAND", "IMAGE_AUC_MAX", "REALISM_LABEL", "realism_check", "realism_claims"]
