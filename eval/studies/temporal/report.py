"""The temporal study's report: its goal lines (each through
:func:`eval.protocol.goal_verdict.goal_line`, chosen on validation), the README part of the camera
and LiDAR tables (what accumulation buys per preset, abstentions, the oracle's ceiling) and the
run record's tuning section. Reads the written files; runs nothing."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd

from eval.core.abstention import NO_NUMBER
from eval.engine.cells import cell, ranged
from eval.engine.goal import Goal
from eval.engine.result_table import bullets
from eval.protocol.goal_verdict import goal_line
from eval.studies.temporal.gain import best_long
from eval.studies.temporal.scores import finite_interval
from eval.studies.temporal.table import (
    FIXED,
    GAIN_COLUMNS,
    LIDAR_SCENARIO,
    LIDAR_TABLE,
    LONG,
    ORACLE_ROW,
    SCENARIO,
    TABLE,
    TUNED,
    abstains,
    folder_of,
)
from matchers.core.search_spaces import TUNING_BUDGET

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


def goals(table: pd.DataFrame, results: Path, name: str = TABLE) -> list[str]:
    """The issue's goal lines (each through :func:`goal_line`) of table ``name``."""
    per_frame = _per_frame(results, name)
    lines = []
    for goal in CHOSEN_GOALS:
        best = best_long(table, goal.condition)
        if best is not None:
            row = _row(table, best, LONG, goal.condition)
            lines.append(goal.line(row, f"`{best}`, chosen on validation"))
    urban = best_long(table, "gnss-urban")
    if urban is not None:
        row = _row(table, urban, LONG, "gnss-urban")
        if per_frame is not None:
            mine = _frames(per_frame, urban, LONG, "gnss-urban")
            oracle = _frames(per_frame, ORACLE_ROW, 0, "gnss-urban")
            if mine is not None and oracle is not None and len(mine) == len(oracle):
                diff = mine["success"].to_numpy(float) - 0.9 * oracle["success"].to_numpy(float)
                mean, low, high, _ = finite_interval(diff, mine["episode"], bounds=(-1.0, 1.0))
                lines.append(
                    goal_line(
                        "`gnss-urban`, W = 10: success − 0.9 × the oracle's ≥ 0",
                        mean,
                        low,
                        high,
                        0.0,
                        detail=f"`{urban}`; share of the oracle {cell(row.share_of_oracle, digits=0)} %",
                    )
                )
        lines.append(
            goal_line(
                "`gnss-urban`, W = 10: partner changes ≤ 1 per 100 object-frames",
                row.partner_changes_per_100,
                row.partner_changes_low,
                row.partner_changes_high,
                1.0,
                at_least=False,
                scale=1.0,
                digits=2,
                detail=f"`{urban}`",
            )
        )
    continuity = Path(results) / folder_of(name) / "continuity.csv"
    if continuity.is_file():
        c = pd.read_csv(continuity)
        c = c[(c["preset"] == "gnss-urban") & (c["band"] == "fast") & (c["links"] > 0)]
        if len(c):
            c = c.iloc[0]
            lines.append(
                goal_line(
                    "own tracker: ≥ 90 % of consecutive detections on one track for objects "
                    "moving ≥ 10 m/s",
                    c.continuity,
                    c.continuity_low,
                    c.continuity_high,
                    0.90,
                    detail=f"{int(c.kept)} of {int(c.links)} links, `gnss-urban` test split",
                )
            )
    gain = Path(results) / f"{name}_gain.csv"
    if gain.is_file():
        every = pd.read_csv(gain)
        fixed = every[(every["preset"] == "gnss-urban") & (every["parameters"] == FIXED)]
        if len(fixed):
            f = fixed.iloc[0]
            lines.append(
                goal_line(
                    "`gnss-urban`: W = 10 ≥ W = 1 at fixed parameters (pooled F1)",
                    f.pooled_diff,
                    f.pooled_low,
                    f.pooled_high,
                    0.0,
                    detail=f"`{f.method}`, W = 10's parameters and τ at both",
                )
            )
        g = every[(every["preset"] == "denied") & (every["parameters"] == TUNED)]
        if len(g):
            g = g.iloc[0]
            low = g.pooled_low
            above = "above 0" if np.isfinite(low) and low > 0 else "not above 0"
            lines.append(
                goal_line(
                    "`denied`: W = 10 beats W = 1 by ≥ +10 pooled F1 points",
                    g.pooled_diff,
                    g.pooled_low,
                    g.pooled_high,
                    0.10,
                    detail=f"`{g.method}`; interval {above}",
                )
            )
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


def readme_part(
    results: Path, rel: str, seconds: float | None = None, name: str = TABLE
) -> list[str]:
    """README lines for the temporal table (none without ``table_temporal.csv``): per preset
    what accumulation buys (one row each) and the issue's goal lines; ``seconds``: the last cold
    run's generation + study time (a "≤ 2 min cold" line), None: not measured cold. ``name``
    :data:`LIDAR_TABLE`: the same for the LiDAR table (:func:`readme_part_lidar`)."""
    results = Path(results)
    lidar = name == LIDAR_TABLE
    path = results / f"{name}.csv"
    if not path.is_file():
        return []
    table = pd.read_csv(path, keep_default_na=False, na_values=[""])
    gain_path = results / f"{name}_gain.csv"
    gain = pd.read_csv(gain_path) if gain_path.is_file() else pd.DataFrame(columns=GAIN_COLUMNS)
    lines = [
        "### The temporal table on LiDAR boxes" if lidar else "### The temporal table",
        "",
        f"`{LIDAR_SCENARIO if lidar else SCENARIO}`: sequences of 10 frames 0.2 s apart of the same two vehicles; each "
        "agent's own tracks from its detections and odometry (never a true id); "
        "`windowed:<m>` (a two-view matcher's scores averaged along the own tracks over W "
        "frames), `temporal_pose` (one planar motion per window from the GNSS prior and the "
        "tracks) and `trajectory_pose` (the same motion from the tracks alone), parameters "
        f"({TUNING_BUDGET} configurations each) and τ per (method, W, preset) on validation. Per preset the method with the best validation F1 "
        "at W = 10 (among those that can run there: a prior reader has no number under `denied`): "
        "test pooled F1 at W = 10 and W = 1 and their difference (episode-level bootstrap 95 % "
        "interval) with W = 1 tuned on its own or at W = 10's parameters and τ (the window "
        "alone), the per-frame mean's difference, success@(1 m, 2°) at W = 10 and the "
        f"oracle's. Every row: [{rel}/{name}.md]({rel}/{name}.md).",
        "",
        "| Preset | Method | parameters | F1 pooled W = 10 | F1 pooled W = 1 "
        "| W = 10 − W = 1 [95 % CI] "
        "| per-frame F1 W = 10 − W = 1 | success W = 10 | oracle success |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for g in gain.itertuples(index=False):
        mine = table[
            (table["method"] == g.method)
            & (table["window"] == LONG)
            & (table["preset"] == g.preset)
        ]
        oracle = table[(table["method"] == ORACLE_ROW) & (table["preset"] == g.preset)]
        success = float(mine["success_1m_2deg"].iloc[0]) if len(mine) else float("nan")
        ceiling = float(oracle["success_1m_2deg"].iloc[0]) if len(oracle) else float("nan")
        lines.append(
            f"| `{g.preset}` | `{g.method}` | {g.parameters} | {cell(g.f1_pooled_w10)} "
            f"| {cell(g.f1_pooled_w1)} "
            f"| {ranged(g.pooled_diff, g.pooled_low, g.pooled_high)} "
            f"| {ranged(g.diff, g.ci_low, g.ci_high)} | {cell(success)} | {cell(ceiling)} |"
        )
    findings = []
    for g in gain.itertuples(index=False):
        if not (np.isfinite(g.pooled_low) and np.isfinite(g.pooled_high)):
            verdict = "no interval (one episode)"
        elif g.pooled_low > 0:
            verdict = "a gain, interval above 0"
        elif g.pooled_high < 0:
            verdict = "a loss, interval below 0"
        else:
            verdict = "no measurable change, interval across 0"
        findings.append(
            f"`{g.preset}`: W = 10 against W = 1 ({g.parameters}) for `{g.method}`: "
            f"{100 * g.pooled_diff:+.1f} pooled F1 points — {verdict}"
        )
    abstained = table[
        [
            m != ORACLE_ROW and abstains(m, p)
            for m, p in zip(table["method"], table["preset"], strict=True)
        ]
    ]
    for preset, rows in abstained.groupby("preset", sort=False):
        names = ", ".join(f"`{m}`" for m in dict.fromkeys(rows["method"]))
        findings.append(f"`{preset}`: {names} — {NO_NUMBER}; in no comparison")
    oracle = table[(table["method"] == ORACLE_ROW) & (table["preset"] == "gnss-urban")]
    if len(oracle) and float(oracle["success_high"].iloc[0]) < 0.60:
        o = oracle.iloc[0]
        findings.append(
            "the oracle's own `gnss-urban` success@(1 m, 2°) is "
            f"{ranged(o.success_1m_2deg, o.success_low, o.success_high)}: below the 60 bar, "
            "which no matcher can then clear (the detections' position error caps the planar fit)"
        )
    timing = (
        [f"stage time (generation + study, last cold run): {seconds:.0f} s (goal ≤ 120 s)"]
        if seconds is not None
        else []
    )
    lines += ["", *bullets(findings + goals(table, results, name) + timing), ""]
    return lines


def temporal_tuning_record(table: pd.DataFrame) -> dict:
    """The run record's ``temporal.tuning``: {preset: {method: {W: {"params": chosen options,
    "tau": τ, "val_f1": validation F1}}}} of every row but the oracle; all three None for a
    method that cannot run under the preset (:func:`abstains`)."""
    record: dict = {}
    for row in table[table["method"] != ORACLE_ROW].itertuples(index=False):
        ran = not abstains(row.method, row.preset)
        record.setdefault(row.preset, {}).setdefault(row.method, {})[str(row.window)] = {
            "params": json.loads(row.params) if ran else None,
            "tau": None if not np.isfinite(row.tau) else round(float(row.tau), 6),
            "val_f1": round(float(row.val_f1), 6) if ran else None,
        }
    return record


def readme_part_lidar(results: Path, rel: str, seconds: float | None = None) -> list[str]:
    """README lines for ``table_temporal_lidar`` (none without it): :func:`readme_part`'s."""
    return readme_part(results, rel, seconds, LIDAR_TABLE)
