"""The V2X association table (``results/table_v2x.{md,csv}``): every matcher under every
localisation preset on ``cad-v2x``, scored on association *and* on the relative pose its
matches recover (:mod:`eval.core.pose_metrics`).

Protocol. The matchers are tuned once, with the equal budget of every table (8 configurations,
:mod:`eval.protocol.tuning`), on the validation split under the scenario's own preset
(:data:`TUNE_PRESET`, ``gnss-urban``); under every preset the chosen configurations run on the
test split with τ calibrated on the validation split at that preset (``DIR/v2x/<preset>/``
holds each preset's evaluation files). A matcher that does not read the prior sees only a
preset's latency, so the runner computes it once per latency (``exact+0ms``, ``exact+100ms``).
Under ``denied`` the prior matchers declare nothing (their rows are kept, F1 0). The row
``prior`` is the localisation prior's own relative-pose error — what a vehicle has with no
matching at all (from the ``pose`` runs' outcomes; under ``denied``, all failures).

Columns (:data:`COLUMNS`): F1 mean and std over runs of the per-pair mean, pooled F1, the pose
columns over every (run, pair), and the median time per pair. Beside it,
``table_v2x_intervals.csv``: per preset, the best matcher by F1 against the runner-up, the
mean per-pair difference with its episode-level cluster t-interval (DESIGN §3).
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np
import pandas as pd

from eval.core.pose_metrics import COLUMNS as POSE_COLUMNS
from eval.core.pose_metrics import summarise_pose
from eval.core.result_files import write_csv, write_text
from eval.core.runner import Runner
from eval.core.tasks import MatcherSpec
from eval.protocol.cluster_interval import t_interval
from eval.protocol.metrics import summarise_pooled, summarise_runs
from eval.studies.evaluation import chosen_specs, evaluate, open_entry

SUBDIR = "v2x"
PRESETS = ("exact", "rtk", "gnss-open-sky", "gnss-urban", "denied")
TUNE_PRESET = "gnss-urban"
PRIOR_ROW = "prior"
COLUMNS = (
    "matcher",
    "preset",
    "f1_mean",
    "f1_std",
    "f1_pooled",
    *POSE_COLUMNS[2:4],
    *POSE_COLUMNS[:2],
    POSE_COLUMNS[4],
    "ms_per_pair",
)
INTERVAL_COLUMNS = (
    "preset",
    "best",
    "runner_up",
    "f1_diff",
    "ci_low",
    "ci_high",
    "pairs",
    "episodes",
)


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
) -> pd.DataFrame:
    """Evaluate `matchers` under every preset (module docstring); writes the per-preset files
    under ``out_dir/v2x/``, ``table_v2x.csv/.md`` and ``table_v2x_intervals.csv`` in
    `out_dir`; returns the table."""
    out_dir = Path(out_dir)
    base = out_dir / SUBDIR
    tuned_dir = base / TUNE_PRESET
    tuned = open_entry(test_dir, val_dir, label, localisation=TUNE_PRESET)
    evaluate([tuned], matchers, seeds, runner, tuned_dir, tune=tune, untuned=False)
    named, _ = chosen_specs(tuned_dir, label, matchers)
    frames = []
    for preset in presets:
        folder = base / preset
        if preset != TUNE_PRESET:
            entry = open_entry(test_dir, val_dir, label, localisation=preset)
            evaluate([entry], named, seeds, runner, folder, untuned=False)
        per_pair = pd.read_csv(
            folder / "metrics_per_pair.csv", keep_default_na=False, na_values=[""]
        )
        frames.append(per_pair.assign(preset=preset))
    per_pair = pd.concat(frames, ignore_index=True)
    write_csv(per_pair, base / "metrics_per_pair.csv")
    table = v2x_table(per_pair)
    write_csv(table.round(6), out_dir / "table_v2x.csv")
    intervals = best_against_runner_up(per_pair)
    write_csv(intervals.round(6), out_dir / "table_v2x_intervals.csv")
    write_text(out_dir / "table_v2x.md", to_markdown(table, intervals, label) + "\n")
    return table


def v2x_table(per_pair: pd.DataFrame) -> pd.DataFrame:
    """One row per (matcher, preset) — and a ``prior`` row per preset — with :data:`COLUMNS`."""
    by = ["matcher", "preset"]
    runs = summarise_runs(per_pair, by=by)[[*by, "f1_mean", "f1_std"]]
    pooled = summarise_pooled(per_pair, by=by)[[*by, "f1_pooled_mean"]]
    table = runs.merge(pooled.rename(columns={"f1_pooled_mean": "f1_pooled"}), on=by)
    table = table.merge(summarise_pose(per_pair, by), on=by, how="left")
    times = per_pair.groupby(by, sort=False)["time_s"].median().mul(1000).rename("ms_per_pair")
    table = table.merge(times.reset_index(), on=by)
    prior = _prior_rows(per_pair)
    table = pd.concat([table, prior], ignore_index=True)
    order = {p: k for k, p in enumerate(PRESETS)}
    table["_p"] = table["preset"].map(lambda p: order.get(p, len(order)))
    table = table.sort_values(["_p"], kind="stable").drop(columns="_p")
    return table[list(COLUMNS)].reset_index(drop=True)


def _prior_rows(per_pair: pd.DataFrame) -> pd.DataFrame:
    """The prior's own pose error per preset (from the ``pose`` runs; none given: failures)."""
    rows = []
    pose = per_pair[per_pair["matcher"] == "pose"]
    for preset, group in pose.groupby("preset", sort=False):
        scored = group[group["pose_scored"].astype(bool)]
        given = scored["prior_scored"].astype(bool).to_numpy()
        errors = pd.DataFrame(
            {
                "pose_scored": True,
                "rte_m": np.where(given, scored["prior_rte_m"].to_numpy(), np.nan),
                "rre_deg": np.where(given, scored["prior_rre_deg"].to_numpy(), np.nan),
                "group": 0,
            }
        )
        summary = summarise_pose(errors, ["group"])
        stats = summary.drop(columns="group").iloc[0].to_dict() if len(summary) else {}
        rows.append({"matcher": PRIOR_ROW, "preset": preset, "ms_per_pair": 0.0} | stats)
    return pd.DataFrame(rows)


def best_against_runner_up(per_pair: pd.DataFrame, level: float = 0.95) -> pd.DataFrame:
    """Per preset: the matcher of highest mean F1 against the second, the mean per-pair F1
    difference (runs averaged first) and its cluster t-interval over episodes."""
    rows = []
    for preset, group in per_pair.groupby("preset", sort=False):
        means = (
            group.groupby(["matcher", "pair"], sort=False)
            .agg(f1=("f1", "mean"), episode=("episode", "first"))
            .reset_index()
        )
        ranking = (
            means.groupby("matcher", sort=False)["f1"]
            .mean()
            .sort_values(ascending=False, kind="stable")
        )
        if len(ranking) < 2:
            continue
        best, second = ranking.index[:2]
        joined = means[means["matcher"] == best].merge(
            means[means["matcher"] == second], on="pair", suffixes=("", "_b")
        )
        d = (joined["f1"] - joined["f1_b"]).to_numpy()
        diff, low, high, _ = t_interval(d, joined["episode"].to_numpy(), level, bounds=(-1.0, 1.0))
        rows.append(
            {"preset": preset, "best": best, "runner_up": second, "f1_diff": diff}
            | {"ci_low": low, "ci_high": high, "pairs": len(joined)}
            | {"episodes": joined["episode"].nunique()}
        )
    return pd.DataFrame(rows, columns=list(INTERVAL_COLUMNS))


def _cell(value: float, percent: bool = True, digits: int = 1) -> str:
    if value is None or not np.isfinite(value):
        return "–"
    return f"{100 * value:.{digits}f}" if percent else f"{value:.{digits}f}"


def to_markdown(table: pd.DataFrame, intervals: pd.DataFrame, label: str) -> str:
    """The table as Markdown (percent for rates), one block per preset, then the intervals."""
    lines = [
        f"**{label}** — matchers × localisation presets; F1 and success rates in percent, "
        "RTE in metres, RRE in degrees, time in ms per pair",
        "",
        "| Preset | Matcher | F1 | F1 pooled | success@(1 m, 2°) | success@(2 m, 5°) | RTE median "
        "| RRE median | pose failures | ms / pair |",
        "|:---|:---|---:|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for row in table.itertuples(index=False):
        f1 = (
            "–"
            if not np.isfinite(row.f1_mean)
            else f"{100 * row.f1_mean:.1f} ± {100 * row.f1_std:.1f}"
        )
        lines.append(
            f"| {row.preset} | {row.matcher} | {f1} | {_cell(row.f1_pooled)} "
            f"| {_cell(row.success_1m_2deg)} | {_cell(row.success_2m_5deg)} "
            f"| {_cell(row.rte_m_median, False, 2)} | {_cell(row.rre_deg_median, False, 2)} "
            f"| {_cell(row.pose_failure_rate)} | {_cell(row.ms_per_pair, False)} |"
        )
    lines += [
        "",
        "Best against runner-up (F1, percentage points; 95 % cluster t-interval over episodes):",
        "",
        "| Preset | Best | Runner-up | Difference | Interval | Episodes |",
        "|:---|:---|:---|---:|---:|---:|",
    ]
    for row in intervals.itertuples(index=False):
        interval = (
            f"[{100 * row.ci_low:+.1f}, {100 * row.ci_high:+.1f}]"
            if np.isfinite(row.ci_low) and np.isfinite(row.ci_high)
            else "– (one episode)"
        )
        lines.append(
            f"| {row.preset} | {row.best} | {row.runner_up} | {100 * row.f1_diff:+.1f} "
            f"| {interval} | {row.episodes} |"
        )
    return "\n".join(lines)


TOP = 4


def compact(table: pd.DataFrame, top: int = TOP) -> pd.DataFrame:
    """Per preset: the `top` matchers by F1, the best one that reads no prior (if not among
    them) and the ``prior`` row, in table order."""
    from matchers.core.registry import requires

    def no_prior(name: str) -> bool:
        try:
            return name != PRIOR_ROW and "world1" not in requires(name)
        except ValueError:
            return False

    keep = []
    for _, group in table.groupby("preset", sort=False):
        ranked = group[group["matcher"] != PRIOR_ROW].sort_values(
            "f1_mean", ascending=False, kind="stable"
        )
        chosen = list(ranked.index[:top])
        free = ranked[ranked["matcher"].map(no_prior)]
        if len(free) and free.index[0] not in chosen:
            chosen.append(free.index[0])
        chosen += list(group.index[group["matcher"] == PRIOR_ROW])
        keep += chosen
    return table.loc[keep].reset_index(drop=True)


def findings(table: pd.DataFrame) -> list[str]:
    """Plain statements read off the table: per preset the best matcher by F1 and by
    success@(1 m, 2°), and which family (with a prior or without) wins."""
    from matchers.core.registry import requires

    def family(name: str) -> str:
        if name == PRIOR_ROW:
            return "the prior alone"
        try:
            return "with the prior" if "world1" in requires(name) else "without a prior"
        except ValueError:
            return "unknown"

    out = []
    rows = table[table["matcher"] != PRIOR_ROW]
    for preset in [p for p in PRESETS if p in set(table["preset"])]:
        here = rows[rows["preset"] == preset]
        if here.empty:
            continue
        best = here.loc[here["f1_mean"].idxmax()]
        pose_best = (
            table[table["preset"] == preset]
            .sort_values("success_1m_2deg", ascending=False, kind="stable")
            .iloc[0]
        )
        out.append(
            f"`{preset}`: best F1 {100 * best.f1_mean:.1f} by `{best.matcher}` "
            f"({family(best.matcher)}); best success@(1 m, 2°) "
            f"{100 * pose_best.success_1m_2deg:.1f} by `{pose_best.matcher}`"
        )
    return out


def readme_part(results: Path, rel: str) -> list[str]:
    """README lines for the V2X task (none without ``table_v2x.md``)."""
    results = Path(results)
    path = results / "table_v2x.md"
    if not path.is_file():
        return []
    table = pd.read_csv(results / "table_v2x.csv", keep_default_na=False, na_values=[""])
    urban = table[(table["preset"] == "gnss-urban") & (table["matcher"] != PRIOR_ROW)]
    denied = table[(table["preset"] == "denied") & (table["matcher"] != PRIOR_ROW)]
    goals = []
    if not urban.empty:
        best = urban.loc[urban["f1_mean"].idxmax()]
        met = best.f1_mean >= 0.9 and urban["success_1m_2deg"].max() >= 0.9
        goals.append(
            f"`gnss-urban` goal (F1 ≥ 90 and success@(1 m, 2°) ≥ 90): "
            f"{'met' if met else 'not met'} — best F1 {100 * best.f1_mean:.1f}, best "
            f"success {100 * urban['success_1m_2deg'].max():.1f}"
        )
    if not denied.empty:
        top = denied["f1_mean"].max()
        goals.append(
            f"`denied` goal (F1 ≥ 80): {'met' if top >= 0.8 else 'not met'} — best {100 * top:.1f}"
        )
    intervals_path = results / "table_v2x_intervals.csv"
    intervals = (
        pd.read_csv(intervals_path)
        if intervals_path.is_file()
        else pd.DataFrame(columns=list(INTERVAL_COLUMNS))
    )
    separated = [
        row.preset
        for row in intervals.itertuples(index=False)
        if np.isfinite(row.ci_low) and (row.ci_low > 0 or row.ci_high < 0)
    ]
    goals.append(
        "the best matcher is ahead of the runner-up beyond the episode-level interval in "
        + (", ".join(f"`{p}`" for p in separated) if separated else "no preset")
    )
    return [
        "### The V2X task",
        "",
        "`scenarios/cad-v2x.toml`: CAD with GNSS-like localisation error and 100 ms message "
        "latency, detector misses, clutter and jitter, and varied light and exposure "
        "(docs/localisation.md, docs/detection.md). Every matcher under every localisation "
        "preset, tuned once (equal budget) under `gnss-urban`, τ per preset; pose metrics from "
        "the least-squares rigid fit of the declared matches against the true relative pose "
        "(latency included); the `prior` row is the error of the vehicles' own poses. Per preset "
        f"the {TOP} best by F1, the best without a prior and the prior itself; every matcher: "
        f"[{rel}/table_v2x.md]({rel}/table_v2x.md).",
        "",
        to_markdown(compact(table), intervals, "CAD-V2X"),
        "",
        *[f"- {line}." for line in findings(table) + goals],
        "",
        f"(`{rel}/table_v2x.csv`, `{rel}/table_v2x_intervals.csv`, `{rel}/v2x/`: per-preset "
        "evaluation files.)",
        "",
    ]
