"""The temporal study's power analysis (:mod:`eval.engine.power_analysis`): the MDD of its two
window goals — W = 10 against W = 1 in pooled F1 at `gnss-urban` (fixed parameters) and at
`denied` (tuned per W) — on the camera and the LiDAR tables, from ``<table>_gain.csv``'s episode
bootstrap intervals; the ICC of the paired per-frame difference (linearised pooled F1, frames of
one episode a cluster) from ``per_frame.csv`` where both windows' frames are written."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from eval.engine.power_analysis import PowerCheck, interval_row, pooled_f1_terms, read_csv
from eval.protocol.cluster_correlation import intra_cluster_correlation
from eval.studies.temporal.goals import DENIED_GAIN, FIXED_WINDOW, _frames
from eval.studies.temporal.table import FIXED, LIDAR_TABLE, LONG, SHORT, TABLE, TUNED, folder_of

GOAL_ROWS = ((FIXED_WINDOW, FIXED), (DENIED_GAIN, TUNED))
"""(goal, the gain table's ``parameters``) of every comparison covered."""


def window_icc(
    per_frame: pd.DataFrame | None, method: str, preset: str
) -> tuple[float, int | None]:
    """(ICC, frames) of the per-frame linearised pooled-F1 difference W = 10 − W = 1 (tuned per
    W), an episode a cluster; (NaN, None) without both windows' frames."""
    if per_frame is None:
        return float("nan"), None
    long, short = (_frames(per_frame, method, w, preset) for w in (LONG, SHORT))
    if long is None or short is None or len(long) != len(short):
        return float("nan"), None
    diff = pooled_f1_terms(long) - pooled_f1_terms(short)
    return intra_cluster_correlation(diff, long["episode"].to_numpy()), len(diff)


def goal_rows(results: Path, name: str = TABLE) -> list[dict]:
    """The rows of table ``name``'s window goals (none without its gain file)."""
    gain = read_csv(Path(results) / f"{name}_gain.csv")
    if gain is None:
        return []
    per_frame = read_csv(Path(results) / folder_of(name) / "per_frame.csv")
    study = "temporal_lidar" if name == LIDAR_TABLE else "temporal"
    out = []
    for goal, parameters in GOAL_ROWS:
        rows = gain[(gain["preset"] == goal.condition) & (gain["parameters"] == parameters)]
        for row in rows.itertuples(index=False):
            icc, frames = (
                window_icc(per_frame, row.method, row.preset)
                if parameters == TUNED
                else (np.nan, None)
            )
            comparison = f"W = {LONG} − W = {SHORT} pooled F1: {row.method} ({parameters})"
            out.append(
                interval_row(
                    study,
                    comparison,
                    row.preset,
                    row.pooled_low,
                    row.pooled_high,
                    int(row.clusters),
                    "mdd",
                    icc,
                    frames,
                )  # fmt: skip
            )
    return out


CHECKS = (
    PowerCheck("window gain (camera): MDD", lambda results: goal_rows(results, TABLE)),
    PowerCheck("window gain (LiDAR): MDD", lambda results: goal_rows(results, LIDAR_TABLE)),
)
