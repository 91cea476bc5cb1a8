"""The transfer study's report: its goals, each with its figure, 95 % interval and verdict
(:mod:`eval.protocol.goal_verdict`), and the README part. Reads ``table_transfer.csv``; runs
nothing."""

from __future__ import annotations

import math
from pathlib import Path

import pandas as pd

from eval.engine.goal import Goal
from eval.engine.result_table import read_result
from eval.protocol.claims import Claim, claims_in, lines_of, measurement_claim
from eval.studies.transfer.evaluation import GOAL_BEATS, GOAL_GAP, GOAL_PRIOR_F1, GOAL_SECONDS
from eval.studies.transfer.matrix import COLUMNS, clusters_text, pct, points, to_markdown, value_of
from eval.studies.transfer.sets import EXTERNAL_TEST, EXTERNAL_TRAIN, SIM_ONLY


def _row(table: pd.DataFrame, train: str, matcher: str) -> pd.Series | None:
    rows = table[
        (table["train"] == train) & (table["test"] == EXTERNAL_TEST) & (table["matcher"] == matcher)
    ]
    return rows.iloc[0] if len(rows) else None


def _chosen(row: pd.Series | None, method: str) -> str:
    """How the reference was chosen: ``X chosen on the validation split (its pooled F1 there
    70.2)``; a table without validation figures (an older file) says so."""
    val = value_of(row, "handcrafted_val_f1_pooled")
    if math.isfinite(val):
        return f"{method} chosen on the validation split (its pooled F1 there {pct(val)})"
    return f"{method} not chosen on validation (a table without validation figures)"


BEATS = Goal(
    "DMGM 069 + 071",
    "trained on cadsim only, no prior, beats the best hand-crafted matcher on DMGM 069 + 071 "
    "(learned − hand-crafted pooled F1 ≥ 0)",
    ("diff_handcrafted", "diff_handcrafted_low", "diff_handcrafted_high"),
    GOAL_BEATS,
    unit=" points",
)  # the hand-crafted reference is chosen on validation
PRIOR_F1 = Goal(
    "DMGM 069 + 071",
    "trained on cadsim only, with the prior: pooled F1 on DMGM 069 + 071 ≥ 97.0",
    ("f1_pooled", "f1_pooled_low", "f1_pooled_high"),
    GOAL_PRIOR_F1,
)  # its reference chosen on validation, as above


def gap_goal(matcher: str) -> Goal:
    """The transfer-gap goal of ``matcher`` (a learned matcher, named: chosen on nothing)."""
    return Goal(
        "DMGM 069 + 071",
        f"transfer gap of {matcher} (DMGM-070-trained minus cadsim-trained pooled F1, on DMGM "
        "069 + 071, ≤ 5.0 points)",
        ("diff_sim_only", "diff_sim_only_low", "diff_sim_only_high"),
        GOAL_GAP,
        at_least=False,
        chosen_on="fixed",
        unit=" points",
    )


def _clusters(row: pd.Series | None) -> str:
    """What ``row``'s interval resamples: DMGM's blocks of consecutive pairs (two sequences:
    not independent clusters) or simulation episodes."""
    count = value_of(row, "clusters")
    unit = row.get("cluster_unit") if row is not None else None
    if not isinstance(unit, str) or not math.isfinite(count) or not unit.startswith("block"):
        return "simulation episodes"
    pairs = unit.removeprefix("block of ").removesuffix(" pairs")
    return (
        f"{int(count)} blocks of {pairs} consecutive DMGM pairs from 2 sequences "
        "(not independent clusters)"
    )


def goals(
    table: pd.DataFrame, stage_s: float | None = None, computed: int | None = None
) -> list[str]:
    """The lines of :func:`goal_items`, as the report prints them."""
    return lines_of(goal_items(table, stage_s, computed))


def claims(results: Path, stage_s: float | None = None, computed: int | None = None) -> list[Claim]:
    """The claims of the transfer part (none without ``table_transfer.csv``)."""
    table = read_result(results, SOURCE)
    if table is None:
        return []
    table = table.reindex(columns=list(dict.fromkeys([*COLUMNS, *table.columns])))
    return claims_in(goal_items(table, stage_s, computed))


def goal_items(
    table: pd.DataFrame, stage_s: float | None = None, computed: int | None = None
) -> list[Claim | str]:
    """The study's goals as claims, each with its figure, its 95 % interval and its verdict
    (:func:`eval.protocol.goal_verdict.goal_line`: met only when the whole interval clears the
    bar); ``stage_s`` the transfer stage's seconds in the last cold run, ``computed`` how many
    of its runs it computed (0: all cached: a plain line, no claim)."""
    out: list[Claim | str] = []
    free = _row(table, SIM_ONLY, "learned")
    method = free.get("handcrafted") if free is not None else None
    method = method if isinstance(method, str) and method else "the best hand-crafted matcher"
    out.append(
        BEATS.claim_of(
            value_of(free, "diff_handcrafted"),
            value_of(free, "diff_handcrafted_low"),
            value_of(free, "diff_handcrafted_high"),
            f"pooled F1 {pct(value_of(free, 'f1_pooled'))} against {method}'s "
            f"{pct(value_of(free, 'handcrafted_f1_pooled'))}, {_chosen(free, method)}; "
            f"{clusters_text(free)}",
            study="transfer",
            subject=BEATS.text.split(" (")[0],
            source=SOURCE,
            clusters=_clusters(free),
        )  # fmt: skip
    )
    pose = _row(table, SIM_ONLY, "learned_pose")
    pose_method = pose.get("handcrafted") if pose is not None else None
    pose_method = pose_method if isinstance(pose_method, str) and pose_method else "–"
    out.append(
        PRIOR_F1.claim_of(
            value_of(pose, "f1_pooled"),
            value_of(pose, "f1_pooled_low"),
            value_of(pose, "f1_pooled_high"),
            f"learned − {pose_method} ({_chosen(pose, pose_method)}): "
            + points(
                value_of(pose, "diff_handcrafted"),
                value_of(pose, "diff_handcrafted_low"),
                value_of(pose, "diff_handcrafted_high"),
            )
            + f" points; {clusters_text(pose)}",
            study="transfer",
            subject=PRIOR_F1.text,
            source=SOURCE,
            clusters=_clusters(pose),
        )  # fmt: skip
    )
    for matcher in ("learned", "learned_pose"):
        external = _row(table, EXTERNAL_TRAIN, matcher)
        base = _row(table, SIM_ONLY, matcher)
        goal = gap_goal(matcher)
        out.append(
            goal.claim_of(
                value_of(external, "diff_sim_only"),
                value_of(external, "diff_sim_only_low"),
                value_of(external, "diff_sim_only_high"),
                "against the hand-crafted reference: DMGM-trained "
                + points(
                    value_of(external, "diff_handcrafted"),
                    value_of(external, "diff_handcrafted_low"),
                    value_of(external, "diff_handcrafted_high"),
                )
                + ", cadsim-trained "
                + points(
                    value_of(base, "diff_handcrafted"),
                    value_of(base, "diff_handcrafted_low"),
                    value_of(base, "diff_handcrafted_high"),
                )
                + f"; {clusters_text(external)}",
                study="transfer",
                subject=f"transfer gap of {matcher}",
                source=SOURCE,
                clusters=_clusters(external),
            )  # fmt: skip
        )
    if stage_s is not None and computed:
        out.append(
            measurement_claim(
                "transfer",
                "training and evaluation of the learned rows",
                stage_s,
                GOAL_SECONDS,
                f"last cold run, results/cold_run.json; {computed} runs computed",
            )
        )
    elif stage_s is not None:
        out.append(
            f"training and evaluation of the learned rows: {stage_s:.0f} s in this run, every "
            f"run cached and the models reused (the goal, ≤ {GOAL_SECONDS} s cold, is read from a "
            "cold run: the README's timing paragraph)"
        )
    return out


def readme_part(
    results: Path, rel: str, stage_s: float | None = None, computed: int | None = None
) -> list[str]:
    """README lines "Does simulation transfer?" (none without ``table_transfer.csv``)."""
    table = read_result(results, SOURCE)
    if table is None:
        return []
    table = table.reindex(columns=list(dict.fromkeys([*COLUMNS, *table.columns])))  # older files
    external = table[table["test"] == EXTERNAL_TEST]
    return [
        "### Does simulation transfer?",
        "",
        "Learned matchers (gradient-boosted trees on motion-invariant candidate-pair features, "
        "docs/learned.md) trained on cadsim's training splits or on the first 100 pairs of "
        "DMGM's calibration sequence 070, τ from pairs 111–201 of 070, tested on DMGM's 069 + "
        f"071 (every test set: [{rel}/table_transfer.md]({rel}/table_transfer.md)):",
        "",
        to_markdown(external).split("\n", 2)[2].strip(),
        "",
        *[f"- {line}." for line in goals(table, stage_s, computed)],
        "",
    ]


SOURCE = "table_transfer.csv"  # the file the transfer claims read

__all__ = ["claims", "gap_goal", "goal_items", "goals", "readme_part"]
