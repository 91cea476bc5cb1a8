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
from eval.engine.result_table import bullets
from eval.protocol.claims import Claim, difference_verdict
from eval.studies.temporal.goals import goal_claims, goals, study_of
from eval.studies.temporal.table import (
    GAIN_COLUMNS,
    LIDAR_SCENARIO,
    LIDAR_TABLE,
    LONG,
    ORACLE_ROW,
    SCENARIO,
    TABLE,
    abstains,
)
from matchers.core.search_spaces import TUNING_BUDGET


def readme_part(
    results: Path, rel: str, seconds: float | None = None, name: str = TABLE
) -> list[str]:
    """README lines for the temporal table (none without ``table_temporal.csv``): per preset
    what accumulation buys (one row each) and the issue's goal lines; ``seconds``: the last cold
    run's generation + study time (a "≤ 2 min cold" line), None: not measured cold. ``name``
    :data:`LIDAR_TABLE`: the same for the LiDAR table (:func:`readme_part_lidar`)."""
    results = Path(results)
    lidar = name == LIDAR_TABLE
    written = _tables(results, name)
    if written is None:
        return []
    table, gain = written
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
    findings: list[str] = [c.statement for c in gain_claims(gain, name)]
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


def gain_claims(gain: pd.DataFrame, name: str = TABLE) -> list[Claim]:
    """Per row of the gain table ``<name>_gain.csv``: W = 10 against W = 1 (tuned per W, or at
    W = 10's parameters and τ) for the method chosen on validation, the pooled-F1 difference
    with its episode-bootstrap interval as a claim."""
    out = []
    for g in gain.itertuples(index=False):
        if not (np.isfinite(g.pooled_low) and np.isfinite(g.pooled_high)):
            verdict = "no interval (one episode)"
        elif g.pooled_low > 0:
            verdict = "a gain, interval above 0"
        elif g.pooled_high < 0:
            verdict = "a loss, interval below 0"
        else:
            verdict = "no measurable change, interval across 0"
        statement = (
            f"`{g.preset}`: W = 10 against W = 1 ({g.parameters}) for `{g.method}`: "
            f"{100 * g.pooled_diff:+.1f} pooled F1 points — {verdict}"
        )
        out.append(
            Claim(
                study_of(name),
                f"{g.method} W = 10 ({g.preset}, {g.parameters})",
                "W = 1",
                "pooled F1 points",
                100 * g.pooled_diff,
                100 * g.pooled_low,
                100 * g.pooled_high,
                0.0,
                "diff",
                difference_verdict(g.pooled_low, g.pooled_high),
                "validation",
                f"{int(g.episodes)} simulation episodes (bootstrap)",
                f"{name}_gain.csv",
                statement,
            )  # fmt: skip
        )
    return out


def claims(results: Path, name: str = TABLE) -> list[Claim]:
    """The claims of table ``name``'s part, in the report's order: W = 10 against W = 1, then
    the goals (none without ``<name>.csv``)."""
    written = _tables(Path(results), name)
    if written is None:
        return []
    table, gain = written
    return [*gain_claims(gain, name), *goal_claims(table, Path(results), name)]


def _tables(results: Path, name: str) -> tuple[pd.DataFrame, pd.DataFrame] | None:
    """(``<name>.csv``, ``<name>_gain.csv`` or an empty gain table), or None without the
    first."""
    path = results / f"{name}.csv"
    if not path.is_file():
        return None
    table = pd.read_csv(path, keep_default_na=False, na_values=[""])
    gain_path = results / f"{name}_gain.csv"
    gain = pd.read_csv(gain_path) if gain_path.is_file() else pd.DataFrame(columns=GAIN_COLUMNS)
    return table, gain


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
