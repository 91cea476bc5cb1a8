"""The temporal table as Markdown (``table_temporal.md``, ``table_temporal_lidar.md``): every
(preset, method, W) row with the oracle's, and what accumulation buys. Rendering only: the
numbers come from the written table and gain rows."""

from __future__ import annotations

import json

import pandas as pd

from eval.core.abstention import NO_NUMBER
from eval.engine.cells import cell, ranged
from eval.studies.temporal.table import FIXED, LABEL, ORACLE_ROW, TUNED, abstains
from matchers.core.search_spaces import TUNING_BUDGET


def params_cell(params: object) -> str:
    """A ``params`` cell (canonical JSON) as ``key=value, …``; ``defaults`` for ``{}``."""
    options = json.loads(params) if isinstance(params, str) and params else {}
    if not options:
        return "defaults"
    return ", ".join(f"{k}={v}" for k, v in options.items())


def _num(value: float, digits: int = 2) -> str:
    return cell(value, percent=False, digits=digits)


def to_markdown(table: pd.DataFrame, gain: pd.DataFrame | None = None, label: str = LABEL) -> str:
    """The table as markdown: per preset every (method, W) and the oracle row."""
    lines = [
        f"**{label}** — temporal matchers × window W × localisation preset; pooled F1 (the "
        "headline: frames without a true pair are common in a sequence), mean per-frame F1 and "
        "success in percent with episode-level 95 % intervals; parameters "
        f"({TUNING_BUDGET} configurations each) and τ per "
        "(method, W, preset) from validation; "
        "partner changes and CLEAR-MOT IDSW of the cross-agent links per 100 covisible "
        "object-frames; frames to the first correct association "
        "(mean over objects matched at all; never: objects never matched correctly); HOTA/AssA "
        "of the declared pairs over the own tracks, combined over sequences as TrackEval does, "
        f"AssA also as a share of the oracle's; {NO_NUMBER}: the method reads the "
        "localisation prior, which the preset does not give (no number, in no comparison).",
        "",
        "| Preset | Method | W | τ | parameters | F1 pooled [95 % CI] | F1 per frame [95 % CI] "
        "| success@(1 m, 2°) [95 % CI] | of oracle | partner changes/100 | IDSW/100 "
        "| frames to first | never | HOTA | AssA | AssA of oracle |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for row in table.itertuples(index=False):
        oracle = row.method == ORACLE_ROW
        if not oracle and abstains(row.method, row.preset):
            lines.append(
                f"| `{row.preset}` | `{row.method}` | {row.window} | n/a | n/a | {NO_NUMBER} |"
                + " n/a |" * 10
            )
            continue
        lines.append(
            f"| `{row.preset}` | `{row.method}` | {'' if oracle else row.window} "
            f"| {'' if oracle else _num(row.tau, 3)} | {'' if oracle else params_cell(row.params)} "
            f"| {ranged(row.f1_pooled, row.f1_pooled_low, row.f1_pooled_high)} "
            f"| {ranged(row.f1_mean, row.f1_low, row.f1_high)} "
            f"| {ranged(row.success_1m_2deg, row.success_low, row.success_high)} "
            f"| {cell(row.share_of_oracle, digits=0)} | {_num(row.partner_changes_per_100)} "
            f"| {_num(row.idsw_per_100)} "
            f"| {_num(row.frames_to_first)} | {row.never_matched} | {cell(row.hota)} "
            f"| {cell(row.assa)} | {cell(row.assa_share_of_oracle, digits=0)} |"
        )
    if gain is not None and len(gain):
        lines += [
            "",
            "What accumulation buys (best method at W = 10 by validation F1 among those that can "
            "run; test F1 at W = 10 minus W = 1: pooled, episode-level bootstrap 95 % interval; "
            "per frame, paired per frame, episode-level t-interval; parameters: each W with its "
            f"own tuned parameters and τ ({TUNED}), or W = 1 run with W = 10's ({FIXED}: the "
            "window's effect alone); MDD: the smallest difference these episodes detect at 95 % "
            "confidence and 80 % power):",
            "",
            "| Preset | Method | parameters | F1 pooled W = 10 | F1 pooled W = 1 "
            "| pooled difference [95 % CI] | its MDD "
            "| F1 per frame W = 10 | F1 per frame W = 1 | per-frame difference [95 % CI] | its MDD |",
            "|---|---|---|---|---|---|---|---|---|---|---|",
        ]
        for g in gain.itertuples(index=False):
            lines.append(
                f"| `{g.preset}` | `{g.method}` | {g.parameters} | {cell(g.f1_pooled_w10)} "
                f"| {cell(g.f1_pooled_w1)} "
                f"| {ranged(g.pooled_diff, g.pooled_low, g.pooled_high)} | {cell(g.pooled_mdd)} "
                f"| {cell(g.f1_w10)} | {cell(g.f1_w1)} | {ranged(g.diff, g.ci_low, g.ci_high)} "
                f"| {cell(g.mdd)} |"
            )
    return "\n".join(lines)
