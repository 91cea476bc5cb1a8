"""The V2X association table (``results/table_v2x.{md,csv}``): every matcher under every
localisation preset on ``cad-v2x``, scored on association *and* on the relative pose its
matches recover (:mod:`eval.core.pose_metrics`: the robust planar fit, the 6-DoF fit as a
secondary column).

Protocol. Every matcher is tuned with the equal budget of every table (8 configurations,
:mod:`eval.protocol.tuning`) on the validation split under the scenario's own preset
(:data:`TUNE_PRESET`, ``gnss-urban``). A matcher that reads the prior is tuned again under every
other preset on that preset's validation draw (the same 8-configuration budget; not under
``denied``, where it has no input); the others see only a preset's latency and keep their
``gnss-urban`` choice. τ is calibrated on the validation split at each preset (``DIR/v2x/<preset>/``
holds each preset's evaluation files, ``tuning.csv`` among them). A matcher that does not read
the prior is computed once per latency (``exact+0ms``, ``exact+100ms``). Under ``denied`` the
prior matchers cannot run (:mod:`eval.core.abstention`): their rows are kept with no number
(empty CSV cells, :data:`~eval.core.abstention.NO_NUMBER` in Markdown) and they are left out
of every ranking, "chosen on validation" and comparison.

Reference rows per preset: ``oracle`` — the same robust fit of the *true* association (the ceiling
detection error leaves to every matcher; ``share_of_oracle`` states each matcher's success as a
share of it) — and ``prior`` — the transform the two observers' noisy broadcast poses imply
(poses only). Both have no F1.

Columns (:data:`COLUMNS`): F1 mean and std over runs of the per-pair mean, its episode-level
cluster t-interval (``f1_low``/``f1_high``), pooled F1, success@(1 m, 2°) with its episode-level
interval and its share of the oracle's, success@(2 m, 5°), median RTE/RRE, pose failures, the
6-DoF fit's success@(1 m, 2°), the median time per pair. Beside it, ``table_v2x_intervals.csv``:
per preset, the best matcher *by validation F1* against the runner-up (also by validation F1),
the mean per-pair test F1 difference with its episode-level cluster t-interval (DESIGN §3).
"""

from __future__ import annotations

import logging
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np
import pandas as pd

from eval.core.abstention import cannot_run
from eval.core.pose_metrics import COLUMNS as POSE_COLUMNS
from eval.core.pose_metrics import SECONDARY, success_flags, summarise_pose
from eval.core.registration_metrics import COLUMNS as REG_COLUMNS
from eval.core.registration_metrics import summarise_registration
from eval.core.result_files import write_csv, write_text
from eval.core.runner import Runner
from eval.core.tasks import MatcherSpec
from eval.engine.comparison import INTERVAL_COLUMNS, best_against_runner_up
from eval.engine.difficulty_levels import write_split_levels
from eval.engine.episode_interval import column_interval
from eval.engine.protocol_run import evaluate
from eval.engine.splits import open_entry
from eval.engine.validation_choice import (
    chosen_specs,
    ranked_on_validation,
    runnable,
    validation_f1,
)
from eval.protocol import tuning
from eval.protocol.metrics import summarise_pooled, summarise_runs
from eval.studies.v2x.markdown import to_markdown

log = logging.getLogger(__name__)

SUBDIR = "v2x"
PRESETS = ("exact", "rtk", "gnss-open-sky", "gnss-urban", "denied")
TUNE_PRESET = "gnss-urban"
NO_PRIOR_PRESET = "denied"
PRIOR_ROW = "prior"
ORACLE_ROW = "oracle"
REFERENCE_ROWS = (ORACLE_ROW, PRIOR_ROW)
COLUMNS = (
    "matcher",
    "preset",
    "f1_mean",
    "f1_std",
    "f1_low",
    "f1_high",
    "f1_pooled",
    "success_1m_2deg",
    "success_low",
    "success_high",
    "share_of_oracle",
    "success_2m_5deg",
    *POSE_COLUMNS[:2],
    POSE_COLUMNS[4],
    SECONDARY,
    *REG_COLUMNS[:3],  # V2X-Reg++'s success@1/2/3 m (eval.core.registration_metrics)
    "ms_per_pair",
)


def reads_prior(name: str) -> bool:
    """Whether registered matcher ``name`` reads the localisation prior (unknown: False)."""
    from matchers.core.registry import requires

    try:
        return "world1" in requires(name)
    except ValueError:
        return False


def evaluate_v2x(
    test_dir: str | Path,
    val_dir: str | Path,
    label: str,
    matchers: Sequence[MatcherSpec],
    seeds: Sequence[int],
    runner: Runner,
    out_dir: str | Path,
    presets: Sequence[str] = PRESETS,
    tune: bool = True,
    name: str = SUBDIR,
    sensor: str | None = None,
) -> pd.DataFrame:
    """Evaluate `matchers` under every preset (module docstring); writes the per-preset files
    under ``out_dir/<name>/``, ``table_<name>.csv/.md`` and ``table_<name>_intervals.csv`` in
    `out_dir` (``name`` "v2x"; the box-only table :mod:`eval.studies.v2x.boxes` uses its own);
    ``sensor``: read a two-sensor dataset as "camera" or "lidar" (None: as stored); returns
    the table."""
    out_dir = Path(out_dir)
    base = out_dir / name
    tuned_dir = base / TUNE_PRESET
    tuned = open_entry(test_dir, val_dir, label, localisation=TUNE_PRESET, sensor=sensor)
    evaluate([tuned], matchers, seeds, runner, tuned_dir, tune=tune, untuned=False)
    named, _ = chosen_specs(tuned_dir, label, matchers)
    frames, validation, recorded = [], {}, {}
    for preset in presets:
        folder = base / preset
        if preset != TUNE_PRESET:
            entry = open_entry(test_dir, val_dir, label, localisation=preset, sensor=sensor)
            here = _retuned(entry, matchers, named, runner, folder) if tune else named
            evaluate([entry], here, seeds, runner, folder, untuned=False)
        per_pair = pd.read_csv(
            folder / "metrics_per_pair.csv", keep_default_na=False, na_values=[""]
        )
        frames.append(per_pair.assign(preset=preset))
        found = validation_f1(folder / "thresholds.csv", label)
        validation[preset] = {m: found[m] for m in runnable(list(found), preset)}
        recorded[preset] = {m: validation[preset].get(m, np.nan) for m in found}
    per_pair = pd.concat(frames, ignore_index=True)
    write_csv(per_pair, base / "metrics_per_pair.csv")
    table = v2x_table(per_pair)
    write_csv(table.round(6), out_dir / f"table_{name}.csv")
    val_table = pd.DataFrame(
        [
            {"preset": p, "matcher": m, "val_f1": f}
            for p, fs in recorded.items()
            for m, f in fs.items()
        ]
    )
    write_csv(val_table.round(6), base / "validation_f1.csv")
    intervals = best_against_runner_up(per_pair, validation)
    write_csv(intervals.round(6), out_dir / f"table_{name}_intervals.csv")
    write_split_levels(out_dir, f"table_{name}", per_pair, test_dir, val_dir, ("preset",))
    write_text(out_dir / f"table_{name}.md", to_markdown(table, intervals, label) + "\n")
    return table


def _retuned(
    entry,
    matchers: Sequence[MatcherSpec],
    named: Mapping[str, MatcherSpec],
    runner: Runner,
    folder: Path,
) -> dict[str, MatcherSpec]:
    """``named`` with every prior-reading matcher re-tuned on ``entry``'s validation split at its
    preset (the same budget); the choices go to ``folder/tuning.csv``."""
    readers = [m for m in matchers if reads_prior(m.name)]
    if not readers or entry.localisation == NO_PRIOR_PRESET:
        return dict(named)
    chosen = tuning.tune_entry(entry, readers, runner, None, entry.localisation)
    folder.mkdir(parents=True, exist_ok=True)
    write_csv(pd.DataFrame(tuning.tuning_rows(chosen.values())), folder / "tuning.csv")
    return dict(named) | {label: choice.spec for label, choice in chosen.items()}


def v2x_table(per_pair: pd.DataFrame) -> pd.DataFrame:
    """One row per (matcher, preset) — and the ``oracle`` and ``prior`` rows per preset — with
    :data:`COLUMNS`."""
    by = ["matcher", "preset"]
    runs = summarise_runs(per_pair, by=by)[[*by, "f1_mean", "f1_std"]]
    pooled = summarise_pooled(per_pair, by=by)[[*by, "f1_pooled_mean"]]
    table = runs.merge(pooled.rename(columns={"f1_pooled_mean": "f1_pooled"}), on=by)
    table = table.merge(summarise_pose(per_pair, by), on=by, how="left")
    registration = summarise_registration(per_pair, by)[[*by, *REG_COLUMNS[:3]]]
    table = table.merge(registration, on=by, how="left")
    times = per_pair.groupby(by, sort=False)["time_s"].median().mul(1000).rename("ms_per_pair")
    table = table.merge(times.reset_index(), on=by)
    table = table.merge(_intervals(per_pair, ""), on=by, how="left")
    reference = pd.concat(
        [_reference_rows(per_pair, ORACLE_ROW), _reference_rows(per_pair, PRIOR_ROW)],
        ignore_index=True,
    )
    table = pd.concat([table, reference], ignore_index=True)
    oracle = table[table["matcher"] == ORACLE_ROW].set_index("preset")["success_1m_2deg"]
    ceiling = table["preset"].map(oracle)
    with np.errstate(divide="ignore", invalid="ignore"):
        table["share_of_oracle"] = np.where(ceiling > 0, table["success_1m_2deg"] / ceiling, np.nan)
    order = {p: k for k, p in enumerate(PRESETS)}
    table["_p"] = table["preset"].map(lambda p: order.get(p, len(order)))
    table = table.sort_values(["_p"], kind="stable").drop(columns="_p")
    table = table.reindex(columns=list(COLUMNS)).reset_index(drop=True)
    abstains = [cannot_run(m, p) for m, p in zip(table["matcher"], table["preset"], strict=True)]
    table.loc[abstains, list(COLUMNS[2:])] = np.nan  # no number, never the empty-frame value
    return table


def _intervals(per_pair: pd.DataFrame, prefix: str) -> pd.DataFrame:
    """Per (matcher, preset): the episode-level intervals of the per-pair F1 (matchers only)
    and of success@(1 m, 2°) of the ``prefix`` fit over the scored pairs."""
    rows = []
    for (matcher, preset), group in per_pair.groupby(["matcher", "preset"], sort=False):
        row = {"matcher": matcher, "preset": preset}
        if not prefix:
            _, row["f1_low"], row["f1_high"] = column_interval(group, "f1")
        flag = "prior_scored" if prefix == "prior_" else "pose_scored"
        scored = group[group[flag].astype(bool)] if flag in group.columns else group.iloc[:0]
        if len(scored):
            scored = scored.assign(_success=success_flags(scored, prefix))
            _, row["success_low"], row["success_high"] = column_interval(scored, "_success")
        rows.append(row)
    return pd.DataFrame(rows)


def _reference_rows(per_pair: pd.DataFrame, row: str) -> pd.DataFrame:
    """Per preset, the ``oracle`` row (the planar fit of the true matches) or the ``prior`` row
    (the broadcast poses' own error; under ``denied``: every pair a failure). Both come from one
    matcher's outcomes: the detections, hence the truth's fit, are the same for every matcher of
    a run; the poses only for the matchers that read the prior — one that does not is run under
    ``exact`` with the preset's latency (the runner shares its runs across presets), so the prior
    row is read off the first prior-reading matcher of the preset (none: off the first one)."""
    prefix = f"{row}_"
    rows = []
    for preset, group in per_pair.groupby("preset", sort=False):
        names = list(dict.fromkeys(group["matcher"]))
        readers = [m for m in names if reads_prior(m)] if row == PRIOR_ROW else []
        first = group[group["matcher"] == (readers or names)[0]]
        scored = first[first["pose_scored"].astype(bool)]
        if scored.empty:
            continue
        errors = scored.assign(matcher=row)
        if row == PRIOR_ROW:  # no prior given (denied): a failure, not a missing row
            given = scored["prior_scored"].astype(bool).to_numpy()
            errors = errors.assign(
                prior_scored=True,
                prior_rte_m=np.where(given, scored["prior_rte_m"], np.nan),
                prior_rre_deg=np.where(given, scored["prior_rre_deg"], np.nan),
            )
        summary = summarise_pose(errors, ["matcher", "preset"], prefix=prefix)
        if summary.empty:
            continue
        stats = summary.iloc[0].to_dict()
        stats |= _intervals(errors, prefix).iloc[0].to_dict()
        rows.append(stats | {"matcher": row, "preset": preset, "ms_per_pair": 0.0})
    return pd.DataFrame(rows)


__all__ = [
    "COLUMNS",
    "INTERVAL_COLUMNS",
    "PRESETS",
    "best_against_runner_up",
    "evaluate_v2x",
    "ranked_on_validation",
    "reads_prior",
    "runnable",
    "v2x_table",
    "validation_f1",
]
