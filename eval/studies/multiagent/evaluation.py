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
``val_*`` columns are the validation snapshots', on which every "best" of the goals
(:func:`eval.studies.multiagent.report.goals`) is chosen before it is reported on test.
``ms_per_snapshot``: the matcher's time on the subset's pairs plus the fusion's, per snapshot.
``f1_gain``: the pooled F1 of the fused result minus that of ``independent`` (same matcher,
preset, N) — pooled over every view pair of every snapshot and run, the same numbers as the
``f1_pooled`` column — with a 95 % episode-bootstrap percentile interval (episodes and runs
resampled, :mod:`eval.protocol.pooled_bootstrap`), the two-sided bootstrap p (``gain_p``) and
that p Holm-adjusted over every gain of the table (``gain_p_holm``, family size
``gain_family``; :mod:`eval.protocol.holm`); ``gain_mdd``: its minimum detectable difference
(95 %, 80 % power) from its cluster-robust standard error over episodes
(:func:`eval.studies.multiagent.gains.gain_mdds`). ``count_error_ci_*``: the count error's episode-
bootstrap interval. ``time_ratio``: ms per snapshot over that of the same matcher, fusion and
preset at the smallest N, with its interval. The cycle-violation rate is 0 for every fused
output by construction: the report checks it as an invariant, not as a goal.
A two-view matcher that cannot run under a preset (a prior reader under ``denied``,
:mod:`eval.core.abstention`) keeps its rows with no number: it enters no bootstrap, no Holm
family and no "best".
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable, Mapping, Sequence
from itertools import combinations
from pathlib import Path

import numpy as np
import pandas as pd

from eval.core.abstention import cannot_run
from eval.core.result_files import write_csv, write_text
from eval.core.runner import Runner, requests_for
from eval.core.tasks import MatcherSpec, PairOutcome
from eval.engine.named_runs import as_named
from eval.engine.splits import open_entry
from eval.protocol.calibration import calibrate, predictions
from eval.protocol.multiway_metrics import (
    MultiwayCounts,
    multiway_counts,
    summarise_counts,
)
from eval.protocol.pooled_bootstrap import (
    LEVEL,
    RESAMPLES,
    SEED,
)
from eval.studies.multiagent.fused_cache import FusedCache, cacheable, fused_key
from eval.studies.multiagent.gains import (
    BY,
    INTERVAL_COLUMNS,
    gain_intervals,
    point_gains,
)
from eval.studies.multiagent.markdown import to_markdown
from matchers.core.plugin_guard import PluginError
from matchers.fusion import PairwiseEvidence, checked_fusion, usable_fusions
from matchers.fusion.universe import canonical_labels, components

log = logging.getLogger("eval.reproduce")

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
    *INTERVAL_COLUMNS[:4],
    "snapshots",
    "runs",
    *INTERVAL_COLUMNS[4:],
    "val_f1_pooled",
    "val_count_error",
    "val_f1_gain",
)
SPLITS = ("test", "val")


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
    cache: str | Path | None = None,
) -> pd.DataFrame:
    """Run, calibrate, fuse and score (module docstring); writes ``table_multiagent.csv/.md`` and
    ``multiagent/per_snapshot.csv`` (test and validation rows, column ``split``) in ``out_dir``;
    returns the table. ``matchers``: specs, or {row label: spec} (e.g. tuned parameters under the
    matcher's plain name). ``cache``: a folder of
    :class:`~eval.studies.multiagent.fused_cache.FusedCache` entries; fused rows found there are
    read (no run is loaded, no fusion run), else computed and stored there (None: always
    computed); the files are the same either way."""
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
    labels = list(named)
    groups = {
        (split, n, preset, label, seed, name)
        for split in SPLITS
        for n in subsets
        for preset in presets
        for label in labels
        for seed in seeds
        for name in fusions
    }
    store = FusedCache(cache) if cache is not None and cacheable(fusions) else None
    if store is not None:
        key = fused_key(runner.spec_keys(requests), labels, subsets, presets, seeds, list(fusions))
        per_snapshot = store.load(key, groups)
        if per_snapshot is not None:
            log.info("%s: fused rows read from the result cache %s", LABEL, store.root)
    if store is None or per_snapshot is None:
        results = dict(zip(keys, runner.run(requests, desc=f"{LABEL} view pairs"), strict=True))
        per_snapshot = _fused_table(results, labels, seeds, presets, subsets, fusions)
        if store is not None:
            store.store(key, per_snapshot)
    write_csv(per_snapshot.round(6), out_dir / "multiagent" / "per_snapshot.csv")
    table = multiagent_table(per_snapshot)
    write_csv(table.round(6), out_dir / "table_multiagent.csv")
    write_text(out_dir / "table_multiagent.md", to_markdown(table, LABEL) + "\n")
    return table


def _fused_table(results: dict, labels, seeds, presets, subsets, fusions) -> pd.DataFrame:
    """The fused rows of every split, N, preset, matcher and seed: τ calibrated per (preset,
    matcher) on the validation view pairs, then every fusion per snapshot."""
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
    return pd.DataFrame(rows)


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
    table = _summary(test).merge(gain_intervals(test, resamples, seed, level), on=BY, how="left")
    if len(val):
        on_val = _summary(val)[[*BY, "f1_pooled", "count_error"]].merge(
            point_gains(val), on=BY, how="left"
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
