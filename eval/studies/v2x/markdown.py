"""The V2X table's Markdown (``table_<name>.md`` of :mod:`eval.studies.v2x.table` and its box
and LiDAR siblings): one block per preset, rates in percent with episode-level intervals, then
the best-against-runner-up intervals. Rendering only; imports no study module."""

from __future__ import annotations

import pandas as pd

from eval.core.abstention import NO_NUMBER, cannot_run
from eval.core.pose_metrics import SECONDARY
from eval.engine.cells import cell, has_interval, ranged, signed_interval


def to_markdown(table: pd.DataFrame, intervals: pd.DataFrame, label: str) -> str:
    """The table as Markdown (percent for rates), one block per preset, then the intervals."""
    lines = [
        f"**{label}** — matchers × localisation presets; F1 and success rates in percent with "
        "95 % episode-level intervals, RTE in metres, RRE in degrees, time in ms per pair; pose "
        "from the robust planar fit (6-DoF fit's success beside it); `oracle`: the same fit of "
        'all true matches; `prior`: the broadcast poses alone; "of oracle": success as a share '
        "of the oracle's; V2X-Reg++ success@λ: RTE < λ m and RRE < λ° over every frame (no pose: "
        "a failure)",
        "",
        "| Preset | Matcher | F1 [95 % CI] | F1 pooled | success@(1 m, 2°) [95 % CI] | of oracle "
        "| success@(2 m, 5°) | RTE median | RRE median | pose failures | 6-DoF success@(1 m, 2°) "
        "| V2X-Reg++ success@1 / 2 / 3 m | ms / pair |",
        "|:---|:---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for row in table.itertuples(index=False):
        if cannot_run(row.matcher, row.preset):
            lines.append(f"| {row.preset} | {row.matcher} | {NO_NUMBER} |" + " n/a |" * 10)
            continue
        f1 = ranged(row.f1_mean, row.f1_low, row.f1_high)
        lines.append(
            f"| {row.preset} | {row.matcher} | {f1} | {cell(row.f1_pooled)} "
            f"| {ranged(row.success_1m_2deg, row.success_low, row.success_high)} "
            f"| {cell(row.share_of_oracle, digits=0)} | {cell(row.success_2m_5deg)} "
            f"| {cell(row.rte_m_median, False, 2)} | {cell(row.rre_deg_median, False, 2)} "
            f"| {cell(row.pose_failure_rate)} | {cell(getattr(row, SECONDARY))} "
            f"| {_registration(row)} | {cell(row.ms_per_pair, False)} |"
        )
    abstained = sorted(
        {str(r.preset) for r in table.itertuples(index=False) if cannot_run(r.matcher, r.preset)}
    )
    if abstained:
        lines += [
            "",
            f"{NO_NUMBER}: the matcher reads the localisation prior, which "
            + ", ".join(f"`{p}`" for p in abstained)
            + " does not give; it has no number there and is in no ranking or comparison.",
        ]
    lines += [
        "",
        "Best against runner-up, both chosen by validation F1 (test F1, percentage points; 95 % "
        "cluster t-interval over episodes; MDD: the smallest difference these clusters detect at "
        "95 % confidence and 80 % power):",
        "",
        "| Preset | Best | Runner-up | Difference | Interval | MDD | Episodes |",
        "|:---|:---|:---|---:|---:|---:|---:|",
    ]
    for row in intervals.itertuples(index=False):
        interval = (
            signed_interval(row.ci_low, row.ci_high)
            if has_interval(row.ci_low, row.ci_high)
            else "– (one episode)"
        )
        mdd = getattr(row, "mdd", float("nan"))  # absent from files written before it
        lines.append(
            f"| {row.preset} | {row.best} | {row.runner_up} | {100 * row.f1_diff:+.1f} "
            f"| {interval} | {cell(mdd)} | {row.episodes} |"
        )
    return "\n".join(lines)


def _registration(row) -> str:
    """V2X-Reg++'s success@1 / 2 / 3 m of a row (RTE < λ m and RRE < λ°, every frame counted),
    percent; "–" where the table has none (the reference rows)."""
    values = [getattr(row, f"reg_success_{t}m", None) for t in (1, 2, 3)]
    if any(v is None or pd.isna(v) for v in values):
        return "–"
    return " / ".join(cell(v) for v in values)


__all__ = ["to_markdown"]
