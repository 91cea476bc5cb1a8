"""Scores per difficulty level (:mod:`cadsim.dataset.difficulty`): each test pair's level from the
rule fitted on its *validation* split, per-level F1 with episode intervals, and per dataset and
level whether the table can rank — the share of test pairs on which the top method is perfect,
whether the top method is separated from the runner-up, maximin against its best rival with the
minimum detectable difference (MDD) and the clusters an MDD of 5 points would need.

The headline level (:func:`headline_level`) is chosen on the validation split alone: the level on
which the paper's methods differ most there (the largest standard deviation of their mean
validation F1, averaged over the datasets; a tie goes to the harder level). docs/evaluation.md,
"Difficulty levels", states the rule. Imports ``eval/protocol/``, ``eval/engine/`` and the
dataset reader.
"""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np
import pandas as pd

from cadsim.dataset.difficulty import FACTORS, LEVELS, LevelRule
from eval.engine.matcher_list import PAPER_ORDER
from eval.engine.power_analysis import clusters_needed
from eval.protocol.cluster_interval import cluster_standard_error, t_interval
from eval.protocol.detectable_difference import mdd_factor

REFERENCE = "maximin"
TARGET_MDD = 0.05
"""The MDD (F1, fraction) a headline comparison is sized for; the clusters it needs are reported
(:func:`eval.engine.power_analysis.clusters_needed`)."""


def split_levels(
    test_dir: str | Path, val_dir: str | Path
) -> tuple[pd.DataFrame, pd.DataFrame, LevelRule]:
    """(test, validation) tables of ``pair``, ``level`` and the factors, and the rule fitted on
    the validation split (module docstring)."""
    from cadsim.dataset import Dataset

    def factors_of(path) -> list[dict]:
        return [pair.difficulty for pair in Dataset(path)]

    val = factors_of(val_dir)
    rule = LevelRule.fit(val)
    tables = []
    for factors in (factors_of(test_dir), val):
        table = pd.DataFrame(
            [{k: f.get(k) for k in FACTORS} for f in factors], columns=list(FACTORS)
        )
        table.insert(0, "level", rule.levels(factors))
        table.insert(0, "pair", np.arange(len(factors)))
        tables.append(table)
    return tables[0], tables[1], rule


def _pair_f1(per_pair: pd.DataFrame, metric: str) -> pd.DataFrame:
    """(pair × matcher) table of ``metric`` averaged over runs, with each pair's episode."""
    means = per_pair.groupby(["pair", "matcher"], sort=True)[metric].mean().unstack("matcher")
    episodes = per_pair.groupby("pair", sort=True)["episode"].first()
    return means.assign(_episode=episodes)


def level_tables(
    per_pair: pd.DataFrame,
    levels: pd.DataFrame,
    order: Sequence[str],
    by: Sequence[str] = ("dataset",),
    metric: str = "f1",
) -> tuple[pd.DataFrame, pd.DataFrame]:
    """(rows, summary) for the test ``per_pair`` metrics joined with ``levels`` (``pair`` →
    ``level``; a ``dataset`` column when several datasets are joined). Rows: per ``by`` × level
    × matcher (those of ``order`` present) the pairs, clusters, mean and 95 % episode interval.
    Summary: per ``by`` × level the top method, the share of pairs it scores perfectly, the top
    minus the runner-up with its interval and whether it excludes 0, and maximin minus its best
    rival with its interval, MDD and the clusters an MDD of 5 points needs."""
    keys = [k for k in ("dataset", "pair") if k in levels.columns and k in per_pair.columns]
    joined = per_pair.merge(levels[[*keys, "level"]], on=keys, how="left")
    rows, summary = [], []
    for group_key, group in joined.groupby([*by, "level"], sort=False):
        label = dict(
            zip(
                [*by, "level"],
                group_key if isinstance(group_key, tuple) else (group_key,),
                strict=True,
            )
        )
        table = _pair_f1(group, metric)
        present = [m for m in order if m in table.columns and table[m].notna().all()]
        if not present:
            continue
        episodes = table["_episode"].to_numpy()
        means = {}
        for matcher in present:
            mean, low, high, clusters = t_interval(
                table[matcher].to_numpy(), episodes, bounds=(0, 1)
            )
            means[matcher] = mean
            rows.append(
                label
                | {"matcher": matcher, "pairs": len(table), "clusters": clusters}
                | {metric: mean, "low": low, "high": high}
            )
        ranked = sorted(present, key=lambda m: (-means[m], order.index(m)))
        top = ranked[0]
        entry = label | {
            "pairs": len(table),
            "top": top,
            "top_perfect_share": float((table[top] >= 1.0 - 1e-12).mean()),
        }
        if len(ranked) > 1:
            runner_up = ranked[1]
            diff = (table[top] - table[runner_up]).to_numpy()
            mean, low, high, _ = t_interval(diff, episodes, bounds=(-1, 1))
            entry |= {
                "runner_up": runner_up,
                "top_minus_runner_up": mean,
                "top_low": low,
                "top_high": high,
                "separated": bool(low > 0),
            }
        rivals = [m for m in ranked if m != REFERENCE]
        if REFERENCE in present and rivals:
            rival = rivals[0]
            diff = (table[REFERENCE] - table[rival]).to_numpy()
            mean, low, high, clusters = t_interval(diff, episodes, bounds=(-1, 1))
            se, _ = cluster_standard_error(diff, episodes)
            entry |= {
                "rival": rival,
                "maximin_minus_rival": mean,
                "rival_low": low,
                "rival_high": high,
                "clusters": clusters,
                "mdd": mdd_factor(clusters) * se if clusters > 1 else float("nan"),
                "clusters_for_mdd_5": clusters_needed(diff, episodes, TARGET_MDD),
            }
        summary.append(entry)
    return pd.DataFrame(rows), pd.DataFrame(summary)


def headline_level(
    val_per_pair: pd.DataFrame, val_levels: pd.DataFrame, methods: Sequence[str], metric: str = "f1"
) -> dict:
    """The level the headline leads with, from validation data only (module docstring):
    {"level", "criterion", "spread": {level: mean over datasets of the std of the methods'
    mean validation F1}}."""
    keys = [k for k in ("dataset", "pair") if k in val_levels.columns and k in val_per_pair.columns]
    joined = val_per_pair[val_per_pair["matcher"].isin(methods)].merge(
        val_levels[[*keys, "level"]], on=keys, how="left"
    )
    spread: dict[str, list[float]] = {level: [] for level in LEVELS}
    for (_, level), group in joined.groupby(["dataset", "level"], sort=False):
        if level not in spread:
            continue
        means = group.groupby("matcher")[metric].mean()
        if len(means) > 1:
            spread[level].append(float(means.std(ddof=0)))
    averaged = {level: (float(np.mean(v)) if v else float("nan")) for level, v in spread.items()}
    known = [level for level in LEVELS if np.isfinite(averaged[level])]
    if not known:
        raise ValueError("headline level: no validation pairs with a level")
    best = max(known, key=lambda level: (round(averaged[level], 12), LEVELS.index(level)))
    return {
        "level": best,
        "chosen_on": "validation",
        "criterion": "largest std of the paper methods' mean validation F1 (mean over datasets)",
        "spread": averaged,
    }


def write_levels(
    out_dir: str | Path,
    stem: str,
    per_pair: pd.DataFrame,
    levels: pd.DataFrame,
    order: Sequence[str],
    by: Sequence[str] = ("dataset",),
    extra: Mapping | None = None,
) -> tuple[pd.DataFrame, pd.DataFrame]:
    """``<stem>_levels.csv`` (rows) and ``<stem>_levels_summary.csv`` in ``out_dir``; ``extra``
    (e.g. the headline choice) into ``<stem>_levels.json``. Returns (rows, summary)."""
    from eval.core.result_files import write_csv, write_text

    out_dir = Path(out_dir)
    rows, summary = level_tables(per_pair, levels, order, by)
    write_csv(rows.round(6), out_dir / f"{stem}_levels.csv")
    write_csv(summary.round(6), out_dir / f"{stem}_levels_summary.csv")
    if extra is not None:
        write_text(
            out_dir / f"{stem}_levels.json", json.dumps(extra, indent=1, default=float) + "\n"
        )
    return rows, summary


BASELINES = ("appearance", "none")
PAPER_METHODS = tuple(m for m in PAPER_ORDER if m not in BASELINES)
"""The paper's eight methods (:data:`~eval.engine.matcher_list.PAPER_ORDER` without the two
baselines): the ones whose spread on validation picks the headline level."""


def write_table1_levels(
    out_dir: str | Path, entries: Sequence, variant: str = "equal_cues"
) -> dict:
    """Table I by difficulty level (``table1_levels.csv``, ``table1_levels_summary.csv``, and the
    headline choice ``table1_levels.json``) from the ``variant``'s per-pair test and validation
    metrics; each entry's levels from the rule fitted on its validation split. Returns the
    headline choice."""
    from eval.protocol.variants import variant_path

    out_dir = Path(out_dir)
    read = {"keep_default_na": False, "na_values": [""]}
    test = pd.read_csv(variant_path(out_dir, "metrics_per_pair", variant, ".csv"), **read)
    val = pd.read_csv(variant_path(out_dir, "metrics_per_pair_validation", variant, ".csv"), **read)
    test_levels, val_levels, rules = [], [], {}
    for entry in entries:
        t, v, rule = split_levels(entry.test_dir, entry.val_dir)
        test_levels.append(t.assign(dataset=entry.label))
        val_levels.append(v.assign(dataset=entry.label))
        rules[entry.label] = rule.as_record()
    test_levels = pd.concat(test_levels, ignore_index=True)
    val_levels = pd.concat(val_levels, ignore_index=True)
    from eval.core.result_files import write_csv

    columns = ["dataset", "pair", "level", *FACTORS]
    write_csv(test_levels[columns].round(6), out_dir / "difficulty_levels.csv")
    headline = headline_level(val, val_levels, PAPER_METHODS)
    order = [m for m in PAPER_ORDER if m in set(test["matcher"])]
    order += [m for m in dict.fromkeys(test["matcher"]) if m not in order]
    extra = headline | {
        "variant": variant,
        "rules": rules,
        "level_counts": {
            label: {lv: int((g["level"] == lv).sum()) for lv in LEVELS}
            for label, g in test_levels.groupby("dataset", sort=False)
        },
    }
    write_levels(out_dir, "table1", test, test_levels, order, ("dataset",), extra)
    return extra


def write_split_levels(
    out_dir: str | Path, stem: str, per_pair: pd.DataFrame, test_dir, val_dir, by: Sequence[str]
) -> None:
    """A V2X table's per-level breakdown (``<stem>_levels.csv`` and its summary) of ``per_pair``
    (one dataset; ``by`` e.g. ("preset",)), the levels from the rule fitted on ``val_dir``."""
    levels, _, _ = split_levels(test_dir, val_dir)
    order = list(dict.fromkeys(per_pair["matcher"]))
    write_levels(out_dir, stem, per_pair, levels, order, by)
