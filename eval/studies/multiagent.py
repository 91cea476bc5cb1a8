"""The multi-agent table (``results/table_multiagent.{md,csv}``): N agents' pairwise matchings
fused into one assignment, on ``cad-multi`` (4 vehicles + 2 roadside units per snapshot).

Protocol. Every pair of the six views of every snapshot is a two-view problem (view i receives,
view j sends; a roadside unit's pose is exact under every preset); each two-view matcher runs on
all 15 pairs of the test and validation snapshots under each localisation preset
(:data:`PRESETS`), with CAD's tuned parameters (the same junction, camera and detector; Table
I's tuning). τ is calibrated per (matcher, preset) on the validation snapshots, all 15 view
pairs pooled (:mod:`eval.protocol.calibration`). For N agents (:data:`SUBSETS`: views 1-2, then a
roadside unit, a third vehicle, all six) each snapshot's pairwise matchings within the subset —
scores and the pairs kept at τ — go to every fusion method of the registry
(:mod:`matchers.fusion`), on the test *and* the validation snapshots; the result is scored by
:mod:`eval.protocol.multiway_metrics`. The table's figures are the test snapshots'; the
``val_*`` columns are the validation snapshots', on which every "best" of :func:`goals` is chosen
before it is reported on test.
``ms_per_snapshot``: the matcher's time on the subset's pairs plus the fusion's, per snapshot.
``f1_gain``: the pooled F1 of the fused result minus that of ``independent`` (same matcher,
preset, N) — pooled over every view pair of every snapshot and run, the same numbers as the
``f1_pooled`` column — with a 95 % episode-bootstrap percentile interval (episodes and runs
resampled, :mod:`eval.protocol.pooled_bootstrap`), the two-sided bootstrap p (``gain_p``) and
that p Holm-adjusted over every gain of the table (``gain_p_holm``, family size
``gain_family``; :mod:`eval.protocol.holm`). ``count_error_ci_*``: the count error's episode-
bootstrap interval. ``time_ratio``: ms per snapshot over that of the same matcher, fusion and
preset at the smallest N, with its interval. The cycle-violation rate is 0 for every fused
output by construction: :func:`goals` checks it as an invariant, not as a goal.
A two-view matcher that cannot run under a preset (a prior reader under ``denied``,
:mod:`eval.core.abstention`) keeps its rows with no number: it enters no bootstrap, no Holm
family and no "best".
"""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping, Sequence
from itertools import combinations
from pathlib import Path

import numpy as np
import pandas as pd

from eval.core.abstention import NO_NUMBER, cannot_run
from eval.core.result_files import write_csv, write_text
from eval.core.runner import Runner, requests_for
from eval.core.tasks import MatcherSpec, PairOutcome
from eval.protocol.calibration import calibrate, predictions
from eval.protocol.claims import measurement_line
from eval.protocol.goal_verdict import NOT_SHOWN, goal_line
from eval.protocol.holm import holm
from eval.protocol.multiway_metrics import (
    MultiwayCounts,
    count_errors,
    multiway_counts,
    summarise_counts,
)
from eval.protocol.pooled_bootstrap import (
    F1_COUNTS,
    LEVEL,
    RESAMPLES,
    SEED,
    f1_of,
    group_sums,
    interval,
    mean_of,
    resamplable,
    summarise,
    weights_for,
)
from eval.studies.evaluation import as_named, open_entry
from matchers.core.plugin_guard import PluginError
from matchers.fusion import PairwiseEvidence, checked_fusion, usable_fusions
from matchers.fusion.universe import canonical_labels, components

SCENARIO = "scenarios/cad-multi.toml"
LABEL = "CAD-multi"
TEST_SNAPSHOTS = 60
VAL_SNAPSHOTS = 30
SUBSETS: dict[int, tuple[int, ...]] = {
    2: (1, 2),
    3: (1, 2, 5),
    4: (1, 2, 3, 5),
    6: (1, 2, 3, 4, 5, 6),
}
"""Views per agent count (1-4 vehicles, 5-6 roadside units): nested, a roadside unit from N = 3."""
PRESETS = ("denied", "gnss-urban")
MATCHERS = ("sm", "maximin", "freealign", "pose_refine")
"""Two-view matchers: two hypergraph-free and hypergraph baselines, the best pose-free one of the
V2X table, and the best with a prior."""
BASELINE = "independent"
"""The fusion every gain is measured against."""
BY = ["n_agents", "matcher", "fusion", "preset"]
GAIN_BAR = 0.05
COUNT_BAR = 0.10
COLUMNS = (
    "n_agents",
    "matcher",
    "fusion",
    "preset",
    "f1_pooled",
    "cycle_violation_rate",
    "count_error",
    "ms_per_snapshot",
    "fusion_ms_per_snapshot",
    "precision_pooled",
    "recall_pooled",
    "cluster_precision",
    "cluster_recall",
    "f1_gain",
    "gain_ci_low",
    "gain_ci_high",
    "snapshots",
    "runs",
    "gain_p",
    "gain_p_holm",
    "gain_family",
    "count_error_ci_low",
    "count_error_ci_high",
    "time_ratio",
    "time_ratio_ci_low",
    "time_ratio_ci_high",
    "val_f1_pooled",
    "val_count_error",
    "val_f1_gain",
)
SPLITS = ("test", "val")
INTERVAL_COLUMNS = (
    "f1_gain",
    "gain_ci_low",
    "gain_ci_high",
    "gain_p",
    "gain_p_holm",
    "gain_family",
    "count_error_ci_low",
    "count_error_ci_high",
    "time_ratio",
    "time_ratio_ci_low",
    "time_ratio_ci_high",
)


def evaluate_multiagent(
    test_dir: str | Path,
    val_dir: str | Path,
    matchers: Sequence[MatcherSpec] | Mapping[str, MatcherSpec],
    seeds: Sequence[int],
    runner: Runner,
    out_dir: str | Path,
    presets: Sequence[str] = PRESETS,
    subsets: dict[int, tuple[int, ...]] = SUBSETS,
    fusions: Sequence[str] | None = None,
) -> pd.DataFrame:
    """Run, calibrate, fuse and score (module docstring); writes ``table_multiagent.csv/.md`` and
    ``multiagent/per_snapshot.csv`` (test and validation rows, column ``split``) in ``out_dir``;
    returns the table. ``matchers``: specs, or {row label: spec} (e.g. tuned parameters under the
    matcher's plain name)."""
    out_dir = Path(out_dir)
    named = as_named(matchers)
    label_of = {spec: label for label, spec in named.items()}
    fusions = list(fusions) if fusions is not None else usable_fusions()
    limit = getattr(runner, "plugin_time_limit_s", None)  # plug-in fusions: per snapshot
    fusions = {name: checked_fusion(name, time_limit_s=limit) for name in fusions}
    entry = open_entry(test_dir, val_dir, LABEL)
    views = sorted(set().union(*subsets.values()))
    view_pairs = list(combinations(views, 2))
    splits = {
        "test": (entry.test_dir, entry.test_checksum),
        "val": (entry.val_dir, entry.val_checksum),
    }
    keys, requests = [], []
    for preset in presets:
        for split, dataset in splits.items():
            for pair in view_pairs:
                made = requests_for(
                    [dataset], named.values(), seeds, localisation=preset, views=pair
                )
                keys += [(split, preset, label_of[r.matcher], r.seed, pair) for r in made]
                requests += made
    results = dict(zip(keys, runner.run(requests, desc=f"{LABEL} view pairs"), strict=True))
    labels = list(named)
    taus = {
        (preset, label): calibrate(
            [r for k, r in results.items() if k[0] == "val" and k[1] == preset and k[2] == label]
        ).tau
        for preset in presets
        for label in labels
    }
    rows = []
    for split in SPLITS:
        for n_agents, subset in subsets.items():
            for preset in presets:
                for label in labels:
                    for seed in seeds:
                        outcomes = {
                            pair: results[(split, preset, label, seed, pair)].outcomes
                            for pair in combinations(subset, 2)
                        }
                        fused = _fused_rows(outcomes, subset, taus[(preset, label)], fusions)
                        where = {"n_agents": n_agents, "preset": preset, "matcher": label}
                        rows += [r | where | {"seed": seed, "split": split} for r in fused]
    per_snapshot = pd.DataFrame(rows)
    write_csv(per_snapshot.round(6), out_dir / "multiagent" / "per_snapshot.csv")
    table = multiagent_table(per_snapshot)
    write_csv(table.round(6), out_dir / "table_multiagent.csv")
    write_text(out_dir / "table_multiagent.md", to_markdown(table) + "\n")
    return table


def _truth(outcomes: dict[tuple[int, int], list[PairOutcome]], subset, k: int) -> list[np.ndarray]:
    """Per view of ``subset``, the true object of each detection of snapshot ``k`` (the
    connected components of the ground-truth pairs: one per object)."""
    evidence = _evidence(outcomes, subset, k, lambda o: o.gt_pairs)
    flat = canonical_labels(components(evidence))
    off = evidence.offsets
    return [flat[off[v] : off[v + 1]] for v in range(len(subset))]


def _evidence(outcomes, subset, k: int, chosen) -> PairwiseEvidence:
    """Snapshot ``k``'s pairwise evidence over ``subset`` (views renumbered 0..N-1); ``chosen``
    picks each pair's declared matches from its outcome."""
    local = {view: v for v, view in enumerate(subset)}
    sizes = [0] * len(subset)
    scores, matches = {}, {}
    for (i, j), per_snapshot in outcomes.items():
        o = per_snapshot[k]
        sizes[local[i]], sizes[local[j]] = o.n1, o.n2
        scores[(local[i], local[j])] = o.scores
        matches[(local[i], local[j])] = chosen(o)
    return PairwiseEvidence(tuple(sizes), scores, matches)


def _fused_rows(
    outcomes, subset, tau: float, fusions: Sequence[str] | Mapping[str, Callable]
) -> list[dict]:
    """Per snapshot and fusion: the counts, its episode and time. ``fusions``: names, or {name:
    the callable to run} (:func:`matchers.fusion.checked_fusion`: plug-ins checked)."""
    if not isinstance(fusions, Mapping):
        fusions = {name: checked_fusion(name) for name in fusions}
    rows = []
    count = len(next(iter(outcomes.values())))
    for k in range(count):
        evidence = _evidence(outcomes, subset, k, lambda o: predictions(o, tau))
        truth = _truth(outcomes, subset, k)
        matcher_s = sum(per[k].time_s for per in outcomes.values())
        first = next(iter(outcomes.values()))[k]
        for name, fuse in fusions.items():
            started = time.perf_counter()
            try:
                universe = fuse(evidence)
            except PluginError as exc:  # a plug-in broke its contract: say where
                raise type(exc)(f"{exc} (snapshot {k}, views {tuple(subset)})") from exc
            fusion_s = time.perf_counter() - started
            counts = multiway_counts(universe, truth)
            rows.append(
                {"fusion": name, "snapshot": k, "episode": first.episode}
                | vars(counts)
                | {"seconds": matcher_s + fusion_s, "fusion_s": fusion_s}
            )
    return rows


def _counts(group: pd.DataFrame) -> list[MultiwayCounts]:
    fields = list(MultiwayCounts.__dataclass_fields__)
    return [MultiwayCounts(*row) for row in group[fields].itertuples(index=False)]


def _split(per_snapshot: pd.DataFrame, split: str) -> pd.DataFrame:
    """The rows of one split (a frame without ``split``: every row is a test row)."""
    if "split" not in per_snapshot:
        return per_snapshot if split == "test" else per_snapshot.iloc[:0]
    return per_snapshot[per_snapshot["split"] == split]


def multiagent_table(
    per_snapshot: pd.DataFrame,
    resamples: int = RESAMPLES,
    seed: int = SEED,
    level: float = LEVEL,
) -> pd.DataFrame:
    """One row per (N, matcher, fusion, preset) with :data:`COLUMNS`: the test snapshots'
    figures, their episode-bootstrap intervals (``resamples`` resamples of the episodes and runs,
    seeded), and the validation snapshots' ``val_*`` figures (NaN without validation rows). A
    matcher that cannot run under the preset (:func:`eval.core.abstention.cannot_run`) keeps
    its rows, every figure empty, and is in no gain family."""
    keys = _split(per_snapshot, "test")[BY].drop_duplicates()
    ran = [
        not cannot_run(m, p)
        for m, p in zip(per_snapshot["matcher"], per_snapshot["preset"], strict=True)
    ]
    per_snapshot = per_snapshot[ran]
    test, val = _split(per_snapshot, "test"), _split(per_snapshot, "val")
    table = _summary(test).merge(_intervals(test, resamples, seed, level), on=BY, how="left")
    if len(val):
        on_val = _summary(val)[[*BY, "f1_pooled", "count_error"]].merge(
            _point_gains(val), on=BY, how="left"
        )
        on_val = on_val.rename(
            columns={
                "f1_pooled": "val_f1_pooled",
                "count_error": "val_count_error",
                "f1_gain": "val_f1_gain",
            }
        )
        table = table.merge(on_val, on=BY, how="left")
    else:
        table = table.assign(val_f1_pooled=np.nan, val_count_error=np.nan, val_f1_gain=np.nan)
    table = keys.merge(table, on=BY, how="left")  # the rows that could not run: keys only
    table[["snapshots", "runs"]] = table[["snapshots", "runs"]].astype("Int64")
    return table[list(COLUMNS)].reset_index(drop=True)


def _summary(split: pd.DataFrame) -> pd.DataFrame:
    """Per (N, matcher, fusion, preset): the pooled metrics over every snapshot and run, the
    times, snapshots and runs."""
    rows = []
    for key, group in split.groupby(BY, sort=False):
        rows.append(
            dict(zip(BY, key, strict=True))
            | summarise_counts(_counts(group))
            | {"ms_per_snapshot": 1000 * group["seconds"].mean()}
            | {"fusion_ms_per_snapshot": 1000 * group["fusion_s"].mean()}
            | {"snapshots": group["snapshot"].nunique(), "runs": group["seed"].nunique()}
        )
    return pd.DataFrame(rows)


def _with_terms(split: pd.DataFrame) -> pd.DataFrame:
    """``split`` with the per-row terms the bootstrap sums: the count error (0 where no object
    is present) and whether it counts, and a 1 per row (a snapshot of a run)."""
    errors = count_errors(split["objects_estimated"], split["objects_present"])
    return split.assign(
        _error=np.nan_to_num(errors, nan=0.0), _counted=np.isfinite(errors).astype(float), _one=1.0
    )


def _rows_of(groups: pd.DataFrame, **change) -> np.ndarray:
    """For each row of ``groups`` (the key columns :data:`BY`), the row index of the same key
    with ``change`` applied (-1: none)."""
    where = {tuple(key): i for i, key in enumerate(groups[BY].itertuples(index=False))}
    changed = groups[BY].assign(**change)
    return np.array([where.get(tuple(key), -1) for key in changed.itertuples(index=False)])


def _gain_index(groups: pd.DataFrame) -> tuple[np.ndarray, np.ndarray]:
    """(rows with a gain, their baseline's row): every fused row whose ``independent`` ran."""
    base = _rows_of(groups, fusion=BASELINE)
    has = (base >= 0) & (groups["fusion"].to_numpy() != BASELINE)
    return np.flatnonzero(has), base[has]


def _point_gains(split: pd.DataFrame) -> pd.DataFrame:
    """Per (N, matcher, fusion, preset): the pooled F1 minus ``independent``'s (point only)."""
    sums = group_sums(split, BY, F1_COUNTS)
    rows, base = _gain_index(sums.groups)
    f1 = f1_of(sums)
    gain = np.full(len(sums.groups), np.nan)
    gain[rows] = f1[rows] - f1[base]
    return sums.groups.assign(f1_gain=gain)


def _intervals(split: pd.DataFrame, resamples: int, seed: int, level: float) -> pd.DataFrame:
    """Per (N, matcher, fusion, preset) of ``split``: the pooled-F1 gain over ``independent``
    with its interval, two-sided p and Holm-adjusted p over every gain of the table; the count
    error's interval; the time ratio to the smallest N with its interval — every interval from
    the same episode-and-run resamples (:mod:`eval.protocol.pooled_bootstrap`)."""
    values = [*F1_COUNTS, "_error", "_counted", "seconds", "_one"]
    sums = group_sums(_with_terms(split), BY, values)
    groups, k = sums.groups, len(sums.groups)
    weights = weights_for(sums, resamples, seed)
    out = {name: np.full(k, np.nan) for name in INTERVAL_COLUMNS}

    f1, f1_resampled = f1_of(sums), f1_of(sums, weights)
    rows, base = _gain_index(groups)
    if len(rows):
        gain = summarise(
            f1[rows] - f1[base],
            f1_resampled[:, rows] - f1_resampled[:, base],
            level,
            len(sums.episodes),
        )
        out["f1_gain"][rows], out["gain_p"][rows] = gain.point, gain.p
        out["gain_ci_low"][rows], out["gain_ci_high"][rows] = gain.low, gain.high
        out["gain_p_holm"][rows] = holm(gain.p)
        out["gain_family"][rows] = np.count_nonzero(np.isfinite(gain.p))
    low_rows = _smallest_n_rows(groups)
    seconds = mean_of(sums, "seconds", "_one")
    out["time_ratio"] = _divide(seconds, seconds[low_rows])
    if not resamplable(sums):  # one episode: the points, and no interval
        return groups.assign(**out)
    errors = mean_of(sums, "_error", "_counted", weights)
    out["count_error_ci_low"], out["count_error_ci_high"] = interval(errors, level)
    seconds = mean_of(sums, "seconds", "_one", weights)
    ratio = _divide(seconds, seconds[:, low_rows])
    out["time_ratio_ci_low"], out["time_ratio_ci_high"] = interval(ratio, level)
    return groups.assign(**out)


def _smallest_n_rows(groups: pd.DataFrame) -> np.ndarray:
    """For each row of ``groups``, the row of the same matcher, fusion and preset at its
    smallest N."""
    smallest = groups.groupby(["matcher", "fusion", "preset"], sort=False)["n_agents"]
    return _rows_of(groups, n_agents=smallest.transform("min").to_numpy())


def _divide(num: np.ndarray, den: np.ndarray) -> np.ndarray:
    with np.errstate(invalid="ignore", divide="ignore"):
        return num / den


def best_on_validation(rows: pd.DataFrame, column: str, lowest: bool) -> pd.Series | None:
    """The row of ``rows`` best on the validation figure ``column`` (its lowest or highest
    value; ties: the first row), or None when no row has one (a table without validation
    figures). Every "best" of :func:`goals` is chosen here, then reported on test."""
    known = rows[np.isfinite(_column(rows, column))]
    if known.empty:
        return None
    return known.loc[known[column].idxmin() if lowest else known[column].idxmax()]


def _pct(value: float) -> str:
    return "–" if value is None or not np.isfinite(value) else f"{100 * value:.1f}"


def _column(table: pd.DataFrame, name: str) -> pd.Series:
    """Column ``name`` as floats, NaN where missing (a table written before the column)."""
    if name not in table:
        return pd.Series(np.nan, index=table.index)
    return pd.to_numeric(table[name], errors="coerce").astype(float)


def _family(table: pd.DataFrame) -> int:
    family = _column(table, "gain_family")
    return int(family.max()) if family.notna().any() else 0


def to_markdown(table: pd.DataFrame) -> str:
    """The table as Markdown, percent for fractions, one block per preset."""
    m = _family(table)
    lines = [
        f"**{LABEL}** — two-view matcher × fusion × number of agents, test snapshots; pooled "
        "pairwise F1, object-count error (with its 95 % episode-bootstrap interval) and "
        "clustering in percent; F1 gain: pooled F1 minus `independent`'s (same matcher, preset "
        "and N), in points, with its two-sided episode-bootstrap p Holm-adjusted over the "
        f"table's {m} gains (family-wise: a gain is shown at the 5 % level when its adjusted p "
        "≤ 0.05); cycle violations: an invariant, 0 for every fused output by construction — "
        "only `independent`'s raw pairs have any; time in ms per snapshot",
        "",
        f"| Preset | N | Matcher | Fusion | F1 pooled | F1 gain (Holm-adjusted p, m = {m}) "
        "| cycle violations | count error [95 % CI] | cluster P / R | ms / snapshot |",
        "|:---|---:|:---|:---|---:|---:|---:|---:|---:|---:|",
    ]
    ordered = table.sort_values(["preset", "n_agents", "matcher"], kind="stable")
    for row in ordered.itertuples(index=False):
        if cannot_run(row.matcher, row.preset):
            lines.append(
                f"| {row.preset} | {row.n_agents} | {row.matcher} | {row.fusion} | {NO_NUMBER} "
                "| n/a | n/a | n/a | n/a | n/a |"
            )
            continue
        p_holm = getattr(row, "gain_p_holm", np.nan)
        gain = (
            "–"
            if row.fusion == BASELINE or not np.isfinite(row.f1_gain)
            else f"{100 * row.f1_gain:+.1f}" + (f" (p {p_holm:.3f})" if np.isfinite(p_holm) else "")
        )
        low = getattr(row, "count_error_ci_low", np.nan)
        high = getattr(row, "count_error_ci_high", np.nan)
        count = _pct(row.count_error) + (
            f" [{_pct(low)}, {_pct(high)}]" if np.isfinite(low) and np.isfinite(high) else ""
        )
        lines.append(
            f"| {row.preset} | {row.n_agents} | {row.matcher} | {row.fusion} "
            f"| {_pct(row.f1_pooled)} | {gain} | {_pct(row.cycle_violation_rate)} "
            f"| {count} | {_pct(row.cluster_precision)} / "
            f"{_pct(row.cluster_recall)} | {row.ms_per_snapshot:.1f} |"
        )
    return "\n".join(lines)


def _not_shown(goal: str, why: str) -> str:
    return f"{goal}: {NOT_SHOWN} — {why}"


def invariant_line(table: pd.DataFrame) -> str:
    """The cycle-consistency invariant of every fused output (not a goal: it holds by
    construction, so a violation is a bug), with ``independent``'s rate for contrast."""
    fused = table[table["fusion"] != BASELINE]
    rates = fused["cycle_violation_rate"]
    worst = rates.max() if len(fused) else 0.0
    line = "invariant: fused outputs have no cycle violation — " + (
        "holds" if worst == 0 else "violated"
    )
    if worst != 0:
        row = fused.loc[rates.idxmax()]
        line += (
            f" (rate {100 * worst:.1f} % for {row.matcher} + {row.fusion}, N = {row.n_agents}, "
            f"{row.preset}: a fusion bug)"
        )
    alone = table.loc[table["fusion"] == BASELINE, "cycle_violation_rate"]
    if len(alone):
        line += f"; `independent`'s raw pairs break up to {100 * alone.max():.1f} % of the chains"
    return line


def goals(table: pd.DataFrame, stage_s: float | None = None) -> list[str]:
    """Plain statements of the table's goals, each met, not met or not shown by its interval
    (:mod:`eval.protocol.goal_verdict`), every "best" chosen on the validation snapshots and
    reported on test; first the cycle-consistency invariant."""
    fused = table[table["fusion"] != BASELINE]
    lines = [invariant_line(table)]
    goal = (
        f"fusion raises pooled F1 over `independent` by ≥ {100 * GAIN_BAR:.0f} points at N ≥ 4 "
        "for some matcher"
    )
    wide = fused[fused["n_agents"] >= 4]
    if len(wide):
        best = best_on_validation(wide, "val_f1_gain", lowest=False)
        if best is None:
            lines.append(_not_shown(goal, "no validation figures to choose the method on"))
        else:
            p_holm = best.get("gain_p_holm", np.nan)
            lines.append(
                goal_line(
                    goal,
                    best.f1_gain,
                    best.gain_ci_low,
                    best.gain_ci_high,
                    GAIN_BAR,
                    unit=" points",
                    detail=f"{best.matcher} + {best.fusion}, N = {best.n_agents}, {best.preset}: "
                    f"the largest gain on the validation snapshots ({100 * best.val_f1_gain:+.1f} "
                    "points), scored on test with its 95 % episode-bootstrap interval; Holm-"
                    f"adjusted p over the table's {_family(table)} gains {p_holm:.3f}",
                )
            )
    high = table["n_agents"].max()
    goal = f"object-count error ≤ {100 * COUNT_BAR:.0f} % at N = {high} with the best method"
    top = table[table["n_agents"] == high]
    if len(top):
        known = top[_column(top, "val_f1_pooled") > 0]
        best = best_on_validation(known, "val_count_error", lowest=True)
        if best is None:
            lines.append(_not_shown(goal, "no validation figures to choose the method on"))
        else:
            lines.append(
                goal_line(
                    goal,
                    best.count_error,
                    best.get("count_error_ci_low", np.nan),
                    best.get("count_error_ci_high", np.nan),
                    COUNT_BAR,
                    at_least=False,
                    unit=" %",
                    detail=f"{best.matcher} + {best.fusion}, {best.preset}: the lowest on the "
                    f"validation snapshots ({100 * best.val_count_error:.1f} %; methods that "
                    "match something there), scored on test with its 95 % episode-bootstrap "
                    "interval",
                )
            )
    lines += _time_lines(table, stage_s)
    return lines


def _time_lines(table: pd.DataFrame, stage_s: float | None) -> list[str]:
    """The time goals: N = max against N = min per snapshot, and the stage's wall time."""
    lines = []
    pairs = len(SUBSETS[max(SUBSETS)]) * (len(SUBSETS[max(SUBSETS)]) - 1) // 2
    low, high = table["n_agents"].min(), table["n_agents"].max()
    rows = table[table["n_agents"] == high]
    if _column(rows, "val_f1_pooled").notna().any():
        rows = rows[_column(rows, "val_f1_pooled") > 0]  # methods matching something on val
    rows = rows[np.isfinite(_column(rows, "time_ratio"))]
    if len(rows) and low != high:
        fusion_ms = table.loc[table["n_agents"] == high, "fusion_ms_per_snapshot"].max()
        lines.append(
            goal_line(
                f"time per snapshot at N = {high} ≤ {pairs} × the two-view time (N = {low}) for "
                "every matcher and fusion",
                rows["time_ratio"].max(),
                rows["time_ratio_ci_low"].max(),
                rows["time_ratio_ci_high"].max(),
                pairs,
                at_least=False,
                scale=1.0,
                unit="×",
                detail=f"the largest ratio over the matchers and fusions, its interval the "
                "largest ends of their 95 % episode-bootstrap intervals; the smallest ratio "
                f"{rows['time_ratio'].min():.1f}×; the fusions themselves take at most "
                f"{fusion_ms:.1f} ms per snapshot, the rest is the {pairs} pairs' matching, "
                "whose views beyond the first two hold more detections (a roadside unit sees "
                "more)",
            )
        )
    if stage_s is not None:  # given only from a cold run (eval.readme_results)
        lines.append(
            measurement_line(
                "this table's stages (generation and runs)",
                stage_s,
                120.0,
                "last cold run, results/cold_run.json",
            )
        )
    return lines


def readme_part(results: Path, rel: str, stage_s: float | None = None) -> list[str]:
    """README lines for the multi-agent table (none without ``table_multiagent.csv``)."""
    path = Path(results) / "table_multiagent.csv"
    if not path.is_file():
        return []
    table = pd.read_csv(path)
    if table.empty:
        return []
    high = table["n_agents"].max()
    shown = table[(table["n_agents"] == high) & (table["preset"] == "gnss-urban")]
    if shown.empty:
        shown = table[table["n_agents"] == high]
    return [
        "### Multi-agent matching",
        "",
        f"![Pooled pairwise F1 and cycle violations against the number of agents]({rel}/fig_multiagent.png)",
        "",
        "`scenarios/cad-multi.toml`: the CAD junction seen per snapshot by 4 vehicles and 2 "
        "roadside units. Every two-view matcher (CAD's tuned parameters, τ per preset on the "
        "validation snapshots) on every pair of views; for N agents the pairwise matchings are "
        "fused into one assignment of every detection to an object (docs/multi-agent.md). "
        f"N = {high} under `gnss-urban` below; every N and preset: "
        f"[{rel}/table_multiagent.md]({rel}/table_multiagent.md).",
        "",
        to_markdown(shown),
        "",
        *[f"- {line}." for line in goals(table, stage_s)],
        "",
    ]
