"""The temporal study's goals as declared (:data:`GOALS`: bar, direction, how the method is
chosen) and read as claims off the written tables (:func:`goal_claims`): the best method at
W = 10 chosen on validation, its success against the oracle's, partner changes, the own
tracker's continuity and what the window buys. Reads the written files; runs nothing."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from eval.engine.cells import cell
from eval.engine.goal import Goal
from eval.protocol.claims import Claim
from eval.studies.temporal.gain import best_long
from eval.studies.temporal.scores import finite_interval
from eval.studies.temporal.table import (
    FIXED,
    LIDAR_TABLE,
    LONG,
    ORACLE_ROW,
    TABLE,
    TUNED,
    folder_of,
)

CHOSEN_GOALS = (
    Goal(
        "denied",
        "`denied`, W = 10: best pooled F1 ≥ 80",
        ("f1_pooled", "f1_pooled_low", "f1_pooled_high"),
        0.80,
    ),
    Goal(
        "gnss-urban",
        "`gnss-urban`, W = 10: success@(1 m, 2°) ≥ 60",
        ("success_1m_2deg", "success_low", "success_high"),
        0.60,
    ),
)  # at W = 10, of the method with the best validation F1 there (:func:`best_long`)


def _per_frame(results: Path, name: str = TABLE) -> pd.DataFrame | None:
    path = Path(results) / folder_of(name) / "per_frame.csv"
    return pd.read_csv(path) if path.is_file() else None


ORACLE_SHARE = Goal(
    "gnss-urban",
    "`gnss-urban`, W = 10: success − 0.9 × the oracle's ≥ 0",
    ("", "", ""),  # per-frame differences, not a table row
    0.0,
)
PARTNER_CHANGES = Goal(
    "gnss-urban",
    "`gnss-urban`, W = 10: partner changes ≤ 1 per 100 object-frames",
    ("partner_changes_per_100", "partner_changes_low", "partner_changes_high"),
    1.0,
    at_least=False,
    scale=1.0,
    digits=2,
)
OWN_TRACKER = Goal(
    "gnss-urban",
    "own tracker: ≥ 90 % of consecutive detections on one track for objects moving ≥ 10 m/s",
    ("continuity", "continuity_low", "continuity_high"),
    0.90,
    chosen_on="fixed",  # the own tracker is not chosen: every method shares it
)
FIXED_WINDOW = Goal(
    "gnss-urban",
    "`gnss-urban`: W = 10 ≥ W = 1 at fixed parameters (pooled F1)",
    ("pooled_diff", "pooled_low", "pooled_high"),
    0.0,
)
DENIED_GAIN = Goal(
    "denied",
    "`denied`: W = 10 beats W = 1 by ≥ +10 pooled F1 points",
    ("pooled_diff", "pooled_low", "pooled_high"),
    0.10,
)
GOALS = (*CHOSEN_GOALS, ORACLE_SHARE, PARTNER_CHANGES, OWN_TRACKER, FIXED_WINDOW, DENIED_GAIN)
"""Every goal of the temporal study, as declared (bar, direction, how the method is chosen)."""


def study_of(name: str) -> str:
    """The ``study`` column of table ``name``'s claims."""
    return "temporal_lidar" if name == LIDAR_TABLE else "temporal"


def goals(table: pd.DataFrame, results: Path, name: str = TABLE) -> list[str]:
    """The statements of :func:`goal_claims`, as the report prints them."""
    return [claim.statement for claim in goal_claims(table, results, name)]


def goal_claims(table: pd.DataFrame, results: Path, name: str = TABLE) -> list[Claim]:
    """The study's goals (:data:`GOALS`) of table ``name`` as claims, each read off its
    interval, the method chosen on validation where the goal says so."""
    per_frame = _per_frame(results, name)
    lines = []
    where = {"study": study_of(name), "source": f"{name}_gain.csv"}
    for goal in CHOSEN_GOALS:
        best = best_long(table, goal.condition)
        if best is not None:
            row = _row(table, best, LONG, goal.condition)
            lines.append(goal.claim(row, f"`{best}`, chosen on validation", subject=best, **where))
    urban = best_long(table, "gnss-urban")
    if urban is not None:
        row = _row(table, urban, LONG, "gnss-urban")
        if per_frame is not None:
            mine = _frames(per_frame, urban, LONG, "gnss-urban")
            oracle = _frames(per_frame, ORACLE_ROW, 0, "gnss-urban")
            if mine is not None and oracle is not None and len(mine) == len(oracle):
                diff = mine["success"].to_numpy(float) - 0.9 * oracle["success"].to_numpy(float)
                mean, low, high, _ = finite_interval(diff, mine["episode"], bounds=(-1.0, 1.0))
                share = cell(row.share_of_oracle, digits=0)
                lines.append(
                    ORACLE_SHARE.claim_of(
                        mean,
                        low,
                        high,
                        f"`{urban}`; share of the oracle {share} %",
                        subject=urban,
                        **where,
                    )  # fmt: skip
                )
        lines.append(PARTNER_CHANGES.claim(row, f"`{urban}`", subject=urban, **where))
    continuity = Path(results) / folder_of(name) / "continuity.csv"
    if continuity.is_file():
        c = pd.read_csv(continuity)
        c = c[(c["preset"] == "gnss-urban") & (c["band"] == "fast") & (c["links"] > 0)]
        if len(c):
            c = c.iloc[0]
            detail = f"{int(c.kept)} of {int(c.links)} links, `gnss-urban` test split"
            lines.append(OWN_TRACKER.claim(c, detail, subject="gnss-urban", **where))
    gain = Path(results) / f"{name}_gain.csv"
    if gain.is_file():
        every = pd.read_csv(gain)
        fixed = every[(every["preset"] == "gnss-urban") & (every["parameters"] == FIXED)]
        if len(fixed):
            f = fixed.iloc[0]
            detail = f"`{f.method}`, W = 10's parameters and τ at both"
            lines.append(FIXED_WINDOW.claim(f, detail, subject=f.method, **where))
        g = every[(every["preset"] == "denied") & (every["parameters"] == TUNED)]
        if len(g):
            g = g.iloc[0]
            low = g.pooled_low
            above = "above 0" if np.isfinite(low) and low > 0 else "not above 0"
            detail = f"`{g.method}`; interval {above}"
            lines.append(DENIED_GAIN.claim(g, detail, subject=g.method, **where))
    return lines


def _row(table: pd.DataFrame, method: str, window: int, preset: str):
    rows = table[
        (table["method"] == method) & (table["window"] == window) & (table["preset"] == preset)
    ]
    return next(rows.itertuples(index=False))


def _frames(per_frame: pd.DataFrame, method: str, window: int, preset: str) -> pd.DataFrame | None:
    rows = per_frame[
        (per_frame["method"] == method)
        & (per_frame["window"] == window)
        & (per_frame["preset"] == preset)
    ]
    if not len(rows):
        return None
    return rows.sort_values(["seed", "sequence", "frame"]).reset_index(drop=True)
