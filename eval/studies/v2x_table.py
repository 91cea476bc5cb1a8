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

from eval.core.abstention import NO_NUMBER, cannot_run
from eval.core.pose_metrics import COLUMNS as POSE_COLUMNS
from eval.core.pose_metrics import SECONDARY, success_flags, summarise_pose
from eval.core.result_files import write_csv, write_text
from eval.core.runner import Runner
from eval.core.tasks import MatcherSpec
from eval.protocol import tuning
from eval.protocol.claims import difference_verdict
from eval.protocol.cluster_interval import t_interval
from eval.protocol.detectable_difference import minimum_detectable_difference
from eval.protocol.goal_verdict import goal_line
from eval.protocol.metrics import summarise_pooled, summarise_runs
from eval.studies.evaluation import chosen_specs, evaluate, open_entry
from eval.studies.regime_cards import AUC_FILE

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
    "mdd",
    "clusters",
)


def reads_prior(name: str) -> bool:
    """Whether registered matcher ``name`` reads the localisation prior (unknown: False)."""
    from matchers.core.registry import requires

    try:
        return "world1" in requires(name)
    except ValueError:
        return False


def runnable(names: Sequence[str], preset: str) -> list[str]:
    """``names`` less the matchers that cannot run under ``preset`` (a prior reader under
    ``denied``, :func:`eval.core.abstention.cannot_run`), in order."""
    return [m for m in names if not cannot_run(m, preset)]


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
    `out_dir` (``name`` "v2x"; the box-only table :mod:`eval.studies.v2x_boxes` uses its own);
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


def validation_f1(thresholds: Path, label: str) -> dict[str, float]:
    """{matcher: mean per-pair validation F1 at its calibrated τ} from a ``thresholds.csv``."""
    if not Path(thresholds).is_file():
        return {}
    table = pd.read_csv(thresholds, keep_default_na=False, na_values=[""])
    table = table[table["dataset"] == label]
    return {
        str(r.matcher): float(r.val_f1) for r in table.itertuples(index=False) if pd.notna(r.val_f1)
    }


def _per_pair_means(group: pd.DataFrame, columns: Sequence[str]) -> pd.DataFrame:
    """Per frame pair: the mean over runs of ``columns``, with the pair's episode."""
    agg = {c: (c, "mean") for c in columns} | {"episode": ("episode", "first")}
    return group.groupby("pair", sort=True).agg(**agg).reset_index()


def _interval(values: np.ndarray, episodes: np.ndarray) -> tuple[float, float, float]:
    """(mean, low, high) of per-pair values with their episode-level cluster t-interval."""
    if not len(values):
        return (float("nan"),) * 3
    mean, low, high, _ = t_interval(values, episodes, bounds=(0.0, 1.0))
    return mean, low, high


def v2x_table(per_pair: pd.DataFrame) -> pd.DataFrame:
    """One row per (matcher, preset) — and the ``oracle`` and ``prior`` rows per preset — with
    :data:`COLUMNS`."""
    by = ["matcher", "preset"]
    runs = summarise_runs(per_pair, by=by)[[*by, "f1_mean", "f1_std"]]
    pooled = summarise_pooled(per_pair, by=by)[[*by, "f1_pooled_mean"]]
    table = runs.merge(pooled.rename(columns={"f1_pooled_mean": "f1_pooled"}), on=by)
    table = table.merge(summarise_pose(per_pair, by), on=by, how="left")
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
            means = _per_pair_means(group, ["f1"])
            _, row["f1_low"], row["f1_high"] = _interval(
                means["f1"].to_numpy(), means["episode"].to_numpy()
            )
        flag = "prior_scored" if prefix == "prior_" else "pose_scored"
        scored = group[group[flag].astype(bool)] if flag in group.columns else group.iloc[:0]
        if len(scored):
            scored = scored.assign(_success=success_flags(scored, prefix))
            means = _per_pair_means(scored, ["_success"])
            _, row["success_low"], row["success_high"] = _interval(
                means["_success"].to_numpy(), means["episode"].to_numpy()
            )
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


def ranked_on_validation(group: pd.DataFrame, validation: Mapping[str, float] | None) -> list[str]:
    """The matchers of one preset's per-pair rows, best first by validation F1 (``validation``:
    {matcher: val F1}; a matcher without one ranks last). Without validation figures (a table
    built in memory) the ranking is by test F1 — callers that state a verdict pass them. A
    matcher that cannot run under the preset is not ranked."""
    presets = set(group["preset"]) if "preset" in group.columns else set()
    names = list(dict.fromkeys(group["matcher"]))
    for preset in presets:
        names = runnable(names, preset)
    group = group[group["matcher"].isin(names)]
    if validation:
        return sorted(names, key=lambda m: -validation.get(m, -np.inf))
    test = group.groupby("matcher", sort=False)["f1"].mean()
    return list(test.sort_values(ascending=False, kind="stable").index)


def best_against_runner_up(
    per_pair: pd.DataFrame,
    validation: Mapping[str, Mapping[str, float]] | None = None,
    level: float = 0.95,
) -> pd.DataFrame:
    """Per preset: the matcher of highest validation F1 (``validation``: {preset: {matcher: val
    F1}}) against the second, the mean per-pair *test* F1 difference (runs averaged first) and
    its cluster t-interval over episodes, with the minimum detectable difference (``mdd``, 95 %
    confidence, 80 % power; :mod:`eval.protocol.detectable_difference`) over its ``clusters``.
    Matchers that cannot run under the preset are in no
    comparison (:func:`ranked_on_validation`)."""
    rows = []
    for preset, group in per_pair.groupby("preset", sort=False):
        ranking = ranked_on_validation(group, (validation or {}).get(preset))
        if len(ranking) < 2:
            continue
        best, second = ranking[:2]
        means = (
            group.groupby(["matcher", "pair"], sort=False)
            .agg(f1=("f1", "mean"), episode=("episode", "first"))
            .reset_index()
        )
        joined = means[means["matcher"] == best].merge(
            means[means["matcher"] == second], on="pair", suffixes=("", "_b")
        )
        d = (joined["f1"] - joined["f1_b"]).to_numpy()
        episodes = joined["episode"].to_numpy()
        diff, low, high, _ = t_interval(d, episodes, level, bounds=(-1.0, 1.0))
        mdd, clusters = minimum_detectable_difference(d, episodes, level)
        rows.append(
            {"preset": preset, "best": best, "runner_up": second, "f1_diff": diff}
            | {"ci_low": low, "ci_high": high, "pairs": len(joined)}
            | {"episodes": joined["episode"].nunique(), "mdd": mdd, "clusters": clusters}
        )
    return pd.DataFrame(rows, columns=list(INTERVAL_COLUMNS))


def _cell(value: float, percent: bool = True, digits: int = 1) -> str:
    if value is None or not np.isfinite(value):
        return "–"
    return f"{100 * value:.{digits}f}" if percent else f"{value:.{digits}f}"


def _ranged(value: float, low: float, high: float) -> str:
    """``v [lo, hi]`` in percent; ``v`` alone without an interval."""
    if not np.isfinite(value):
        return "–"
    if np.isfinite(low) and np.isfinite(high):
        return f"{100 * value:.1f} [{100 * low:.1f}, {100 * high:.1f}]"
    return f"{100 * value:.1f}"


def to_markdown(table: pd.DataFrame, intervals: pd.DataFrame, label: str) -> str:
    """The table as Markdown (percent for rates), one block per preset, then the intervals."""
    lines = [
        f"**{label}** — matchers × localisation presets; F1 and success rates in percent with "
        "95 % episode-level intervals, RTE in metres, RRE in degrees, time in ms per pair; pose "
        "from the robust planar fit (6-DoF fit's success beside it); `oracle`: the same fit of "
        'all true matches; `prior`: the broadcast poses alone; "of oracle": success as a share '
        "of the oracle's",
        "",
        "| Preset | Matcher | F1 [95 % CI] | F1 pooled | success@(1 m, 2°) [95 % CI] | of oracle "
        "| success@(2 m, 5°) | RTE median | RRE median | pose failures | 6-DoF success@(1 m, 2°) "
        "| ms / pair |",
        "|:---|:---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for row in table.itertuples(index=False):
        if cannot_run(row.matcher, row.preset):
            lines.append(f"| {row.preset} | {row.matcher} | {NO_NUMBER} |" + " n/a |" * 9)
            continue
        f1 = _ranged(row.f1_mean, row.f1_low, row.f1_high)
        lines.append(
            f"| {row.preset} | {row.matcher} | {f1} | {_cell(row.f1_pooled)} "
            f"| {_ranged(row.success_1m_2deg, row.success_low, row.success_high)} "
            f"| {_cell(row.share_of_oracle, digits=0)} | {_cell(row.success_2m_5deg)} "
            f"| {_cell(row.rte_m_median, False, 2)} | {_cell(row.rre_deg_median, False, 2)} "
            f"| {_cell(row.pose_failure_rate)} | {_cell(getattr(row, SECONDARY))} "
            f"| {_cell(row.ms_per_pair, False)} |"
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
            f"[{100 * row.ci_low:+.1f}, {100 * row.ci_high:+.1f}]"
            if np.isfinite(row.ci_low) and np.isfinite(row.ci_high)
            else "– (one episode)"
        )
        mdd = getattr(row, "mdd", float("nan"))  # absent from files written before it
        lines.append(
            f"| {row.preset} | {row.best} | {row.runner_up} | {100 * row.f1_diff:+.1f} "
            f"| {interval} | {_cell(mdd)} | {row.episodes} |"
        )
    return "\n".join(lines)


TOP = 4


def _validation(results: Path, name: str = SUBDIR) -> dict[str, dict[str, float]]:
    """{preset: {matcher: validation F1}} as ``<name>/validation_f1.csv`` records it."""
    path = Path(results) / name / "validation_f1.csv"
    if not path.is_file():
        return {}
    table = pd.read_csv(path)
    return {
        p: {m: f for m, f in zip(g["matcher"], g["val_f1"], strict=True) if not cannot_run(m, p)}
        for p, g in table.groupby("preset", sort=False)
    }


def compact(
    table: pd.DataFrame,
    validation: Mapping[str, Mapping[str, float]] | None = None,
    top: int = TOP,
) -> pd.DataFrame:
    """Per preset: the `top` matchers by validation F1 (test F1 without validation figures)
    among those that can run there, the best one that reads no prior (if not among them) and
    the reference rows, in table order."""
    keep = []
    for preset, group in table.groupby("preset", sort=False):
        rows = group[~group["matcher"].isin(REFERENCE_ROWS)]
        rows = rows[rows["matcher"].isin(runnable(list(rows["matcher"]), preset))]
        val = (validation or {}).get(preset)
        if val:
            ranked = sorted(rows.index, key=lambda i: -val.get(rows.at[i, "matcher"], -np.inf))
        else:
            ranked = list(rows.sort_values("f1_mean", ascending=False, kind="stable").index)
        chosen = ranked[:top]
        free = [i for i in ranked if not reads_prior(rows.at[i, "matcher"])]
        if free and free[0] not in chosen:
            chosen.append(free[0])
        chosen += list(group.index[group["matcher"].isin(REFERENCE_ROWS)])
        keep += chosen
    return table.loc[keep].reset_index(drop=True)


def compact_markdown(results: Path, name: str, label: str) -> str | None:
    """The compact Markdown of the V2X-protocol table ``table_<name>.csv`` under ``results``
    (validation-ranked rows, intervals from ``table_<name>_intervals.csv`` when present), or
    None without ``table_<name>.md``."""
    results = Path(results)
    if not (results / f"table_{name}.md").is_file():
        return None
    table = pd.read_csv(results / f"table_{name}.csv", keep_default_na=False, na_values=[""])
    intervals_path = results / f"table_{name}_intervals.csv"
    intervals = (
        pd.read_csv(intervals_path)
        if intervals_path.is_file()
        else pd.DataFrame(columns=list(INTERVAL_COLUMNS))
    )
    return to_markdown(compact(table, _validation(results, name)), intervals, label)


def _family(name: str) -> str:
    if name in REFERENCE_ROWS:
        return "a reference row"
    return "with the prior" if reads_prior(name) else "without a prior"


def chosen_row(
    table: pd.DataFrame, preset: str, validation: Mapping[str, Mapping[str, float]] | None
) -> tuple[str, pd.Series] | None:
    """(name, row) of the matcher of ``preset`` with the highest validation F1 (test F1 without
    validation figures: a table built in memory); None when the preset has no matcher row that
    can run there."""
    rows = table[(table["preset"] == preset) & ~table["matcher"].isin(REFERENCE_ROWS)]
    rows = rows[rows["matcher"].isin(runnable(list(rows["matcher"]), preset))]
    if rows.empty:
        return None
    rows = rows.set_index("matcher")
    val = (validation or {}).get(preset) or {}
    best = max(rows.index, key=lambda m: val.get(m, -np.inf)) if val else rows["f1_mean"].idxmax()
    return best, rows.loc[best]


def findings(
    table: pd.DataFrame, validation: Mapping[str, Mapping[str, float]] | None = None
) -> list[str]:
    """Plain statements read off the table: per preset the matcher chosen by validation F1, its
    test F1 and success@(1 m, 2°) with their intervals, and the oracle's success."""
    out = []
    for preset in [p for p in PRESETS if p in set(table["preset"])]:
        here = table[table["preset"] == preset].set_index("matcher")
        found = chosen_row(table, preset, validation)
        if found is None:
            continue
        best, b = found
        oracle = here.loc[ORACLE_ROW] if ORACLE_ROW in here.index else None
        ceiling = (
            f"; the oracle's {_ranged(oracle.success_1m_2deg, oracle.success_low, oracle.success_high)}"
            if oracle is not None
            else ""
        )
        out.append(
            f"`{preset}`: chosen on validation `{best}` ({_family(best)}): test F1 "
            f"{_ranged(b.f1_mean, b.f1_low, b.f1_high)}, success@(1 m, 2°) "
            f"{_ranged(b.success_1m_2deg, b.success_low, b.success_high)} "
            f"({_cell(b.share_of_oracle, digits=0)} % of the oracle's){ceiling}"
        )
    return out


def goals(
    table: pd.DataFrame, validation: Mapping[str, Mapping[str, float]] | None = None
) -> list[str]:
    """The V2X goal lines, each with its interval and a verdict that reads it
    (:mod:`eval.protocol.goal_verdict`); the method is the one chosen on validation."""
    out = []

    urban = chosen_row(table, "gnss-urban", validation)
    if urban is not None:
        name, row = urban
        out.append(
            goal_line(
                "`gnss-urban` F1 ≥ 90",
                row.f1_mean,
                row.f1_low,
                row.f1_high,
                0.9,
                detail=f"`{name}`, chosen on validation",
            )
        )
        out.append(
            goal_line(
                "`gnss-urban` success@(1 m, 2°) ≥ 90",
                row.success_1m_2deg,
                row.success_low,
                row.success_high,
                0.9,
                detail=f"`{name}`; {_cell(row.share_of_oracle, digits=0)} % of the oracle's",
            )
        )
    denied = chosen_row(table, "denied", validation)
    if denied is not None:
        name, row = denied
        out.append(
            goal_line(
                "`denied` F1 ≥ 80",
                row.f1_mean,
                row.f1_low,
                row.f1_high,
                0.8,
                detail=f"`{name}`, chosen on validation",
            )
        )
    return out


AUC_BAND = (0.60, 0.80)
IMAGE_AUC_MAX = 0.75
REALISM_LABEL = "CAD-V2X"


def runner_up_lines(intervals: pd.DataFrame) -> list[str]:
    """Per preset of ``table_v2x_intervals.csv``: the matcher chosen on validation against the
    runner-up, test F1 difference with its episode interval — ahead / behind only where the
    interval excludes 0 (:func:`eval.protocol.claims.difference_verdict`)."""
    out = []
    for row in intervals.itertuples(index=False):
        interval = (
            f"{100 * row.f1_diff:+.1f} [{100 * row.ci_low:+.1f}, {100 * row.ci_high:+.1f}]"
            if np.isfinite(row.ci_low) and np.isfinite(row.ci_high)
            else f"{100 * row.f1_diff:+.1f} (no interval)"
        )
        out.append(
            f"`{row.preset}`: `{row.best}` (chosen on validation) − the runner-up `{row.runner_up}`,"
            f" test F1 {interval} points over {int(row.episodes)} episodes — "
            f"{difference_verdict(row.ci_low, row.ci_high)}"
        )
    return out


def realism_check(results: Path) -> list[str]:
    """The appearance-realism goals on the held-out test split (``regime.csv``'s CAD-V2X row;
    its settings were chosen on validation seeds, docs/scenarios.md): whole-feature AUC within
    :data:`AUC_BAND`, image-only AUC at most :data:`IMAGE_AUC_MAX`, each read off its
    episode-bootstrap interval (``regime_auc_intervals.csv``); without that file the values are
    points and every goal is *not shown* (a point value never meets a goal)."""
    path = Path(results) / "regime.csv"
    if not path.is_file():
        return []
    table = pd.read_csv(path).set_index("dataset")
    if REALISM_LABEL not in table.index:
        return []
    row = table.loc[REALISM_LABEL].to_dict()
    where = "over every candidate pair of the held-out test split"
    bounds = Path(results) / AUC_FILE
    intervals = pd.read_csv(bounds).set_index("dataset") if bounds.is_file() else None
    if intervals is not None and REALISM_LABEL in intervals.index:
        row |= intervals.loc[REALISM_LABEL].to_dict()
        where += f", 95 % interval over its {int(row['episodes'])} episodes"
    else:
        where = f"a point value {where}, no episode interval"
    nan = float("nan")
    low, high = AUC_BAND
    alike = row.get("same_class_auc")
    within = (
        ""
        if alike is None or pd.isna(alike)
        else (
            f"; against same-class false pairs only {alike:.3f} (appearance tells look-alikes "
            "apart little: the pooled value is high because most false pairs cross classes, a car "
            "against a sign, where DMGM's are mostly one class — docs/scenarios.md)"
        )
    )

    def goal(name: str, key: str, bar: float, at_least: bool, detail: str) -> str:
        return goal_line(
            f"appearance realism, {name} {'≥' if at_least else '≤'} {bar:.2f}", row[key],
            row.get(f"{key}_low", nan), row.get(f"{key}_high", nan), bar, at_least,
            scale=1.0, digits=3, detail=detail,
        )  # fmt: skip

    return [
        goal("whole-feature AUC", "appearance_auc", low, True, where),
        goal(
            "whole-feature AUC", "appearance_auc", high, False, f"{where}; DMGM's is 0.57{within}"
        ),
        goal("image-only AUC", "image_auc", IMAGE_AUC_MAX, False, where),
    ]


def readme_part(results: Path, rel: str) -> list[str]:
    """README lines for the V2X task (none without ``table_v2x.md``)."""
    results = Path(results)
    path = results / "table_v2x.md"
    if not path.is_file():
        return []
    table = pd.read_csv(results / "table_v2x.csv", keep_default_na=False, na_values=[""])
    validation = _validation(results)
    intervals_path = results / "table_v2x_intervals.csv"
    intervals = (
        pd.read_csv(intervals_path)
        if intervals_path.is_file()
        else pd.DataFrame(columns=list(INTERVAL_COLUMNS))
    )
    lines = goals(table, validation) + runner_up_lines(intervals)
    lines += realism_check(results)
    episodes = int(intervals["episodes"].max()) if len(intervals) else 0
    return [
        "### The V2X task",
        "",
        "`scenarios/cad-v2x.toml`: CAD with GNSS-like localisation error and 100 ms message "
        "latency, detector misses, clutter and jitter, and varied light and exposure "
        "(docs/localisation.md, docs/detection.md). Every matcher under every localisation "
        "preset, tuned (equal budget) under `gnss-urban` and, if it reads the prior, again under "
        "each preset on that preset's validation draw; τ per preset; pose metrics from the "
        "robust planar fit of the declared matches against the true relative pose "
        "(latency included); `oracle` is the same fit of the true matches (the ceiling), "
        f"`prior` the vehicles' broadcast poses alone; {episodes} test episodes. Per preset "
        f"the {TOP} best by validation F1, the best without a prior and the reference rows; "
        f"every matcher: [{rel}/table_v2x.md]({rel}/table_v2x.md).",
        "",
        to_markdown(compact(table, validation), intervals, "CAD-V2X"),
        "",
        *[f"- {line}." for line in findings(table, validation) + lines],
        "",
        f"(`{rel}/table_v2x.csv`, `{rel}/table_v2x_intervals.csv`, `{rel}/v2x/`: per-preset "
        "evaluation files.)",
        "",
    ]
