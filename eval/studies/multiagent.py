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
(:mod:`matchers.fusion`); the result is scored by :mod:`eval.protocol.multiway_metrics`.
``ms_per_snapshot``: the matcher's time on the subset's pairs plus the fusion's, per snapshot.
``f1_gain`` and its interval: the per-snapshot F1 of the fused result minus that of
``independent`` (same matcher, preset, N; runs averaged), mean and episode-level cluster
t-interval (95 %).
"""

from __future__ import annotations

import time
from collections.abc import Mapping, Sequence
from itertools import combinations
from pathlib import Path

import numpy as np
import pandas as pd

from eval.core.result_files import write_csv, write_text
from eval.core.runner import Runner, requests_for
from eval.core.tasks import MatcherSpec, PairOutcome
from eval.protocol.calibration import calibrate, predictions
from eval.protocol.cluster_interval import t_interval
from eval.protocol.multiway_metrics import MultiwayCounts, multiway_counts, summarise_counts
from eval.studies.evaluation import as_named, open_entry
from matchers.fusion import PairwiseEvidence, available_fusions, get_fusion
from matchers.fusion.universe import canonical_labels, components

SCENARIO = "scenarios/cad-multi.toml"
LABEL = "CAD-multi"
TEST_SNAPSHOTS = 20
VAL_SNAPSHOTS = 10
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
    ``multiagent/per_snapshot.csv`` in ``out_dir``; returns the table. ``matchers``: specs, or
    {row label: spec} (e.g. tuned parameters under the matcher's plain name)."""
    out_dir = Path(out_dir)
    named = as_named(matchers)
    label_of = {spec: label for label, spec in named.items()}
    fusions = list(fusions) if fusions is not None else available_fusions()
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
    for n_agents, subset in subsets.items():
        for preset in presets:
            for label in labels:
                for seed in seeds:
                    outcomes = {
                        pair: results[("test", preset, label, seed, pair)].outcomes
                        for pair in combinations(subset, 2)
                    }
                    fused = _fused_rows(outcomes, subset, taus[(preset, label)], fusions)
                    where = {"n_agents": n_agents, "preset": preset, "matcher": label}
                    rows += [r | where | {"seed": seed} for r in fused]
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


def _fused_rows(outcomes, subset, tau: float, fusions: Sequence[str]) -> list[dict]:
    """Per snapshot and fusion: the counts, its episode and time."""
    rows = []
    count = len(next(iter(outcomes.values())))
    for k in range(count):
        evidence = _evidence(outcomes, subset, k, lambda o: predictions(o, tau))
        truth = _truth(outcomes, subset, k)
        matcher_s = sum(per[k].time_s for per in outcomes.values())
        first = next(iter(outcomes.values()))[k]
        for name in fusions:
            started = time.perf_counter()
            universe = get_fusion(name)(evidence)
            fusion_s = time.perf_counter() - started
            counts = multiway_counts(universe, truth)
            rows.append(
                {"fusion": name, "snapshot": k, "episode": first.episode}
                | vars(counts)
                | {"seconds": matcher_s + fusion_s, "fusion_s": fusion_s}
            )
    return rows


def _snapshot_f1(group: pd.DataFrame) -> float:
    return summarise_counts(_counts(group))["f1_pooled"]


def _counts(group: pd.DataFrame) -> list[MultiwayCounts]:
    fields = list(MultiwayCounts.__dataclass_fields__)
    return [MultiwayCounts(*row) for row in group[fields].itertuples(index=False)]


def multiagent_table(per_snapshot: pd.DataFrame) -> pd.DataFrame:
    """One row per (N, matcher, fusion, preset) with :data:`COLUMNS`."""
    by = ["n_agents", "matcher", "fusion", "preset"]
    rows = []
    for key, group in per_snapshot.groupby(by, sort=False):
        metrics = summarise_counts(_counts(group))
        rows.append(
            dict(zip(by, key, strict=True))
            | metrics
            | {"ms_per_snapshot": 1000 * group["seconds"].mean()}
            | {"fusion_ms_per_snapshot": 1000 * group["fusion_s"].mean()}
            | {"snapshots": group["snapshot"].nunique(), "runs": group["seed"].nunique()}
        )
    table = pd.DataFrame(rows)
    gains = _gains(per_snapshot)
    table = table.merge(gains, on=by, how="left")
    return table[list(COLUMNS)].reset_index(drop=True)


def _gains(per_snapshot: pd.DataFrame, level: float = 0.95) -> pd.DataFrame:
    """Per (N, matcher, fusion, preset): the per-snapshot F1 minus ``independent``'s (runs
    averaged), mean and episode-level cluster t-interval."""
    by = ["n_agents", "matcher", "preset"]
    f1 = (
        per_snapshot.groupby([*by, "fusion", "snapshot", "seed"], sort=False)
        .apply(_snapshot_f1, include_groups=False)
        .rename("f1")
        .reset_index()
        .groupby([*by, "fusion", "snapshot"], sort=False)["f1"]
        .mean()
        .reset_index()
    )
    episodes = per_snapshot.groupby("snapshot")["episode"].first()
    rows = []
    for key, group in f1.groupby(by, sort=False):
        base = group[group["fusion"] == "independent"].set_index("snapshot")["f1"]
        for fusion, rows_f in group.groupby("fusion", sort=False):
            mine = rows_f.set_index("snapshot")["f1"]
            common = mine.index.intersection(base.index)
            d = (mine[common] - base[common]).to_numpy()
            gain, low, high = np.nan, np.nan, np.nan  # no independent run to compare with
            if len(d):
                gain, low, high, _ = t_interval(
                    d, episodes[common].to_numpy(), level, bounds=(-1.0, 1.0)
                )
            rows.append(
                dict(zip(by, key, strict=True))
                | {"fusion": fusion, "f1_gain": gain, "gain_ci_low": low, "gain_ci_high": high}
            )
    return pd.DataFrame(rows)


def _pct(value: float) -> str:
    return "–" if value is None or not np.isfinite(value) else f"{100 * value:.1f}"


def to_markdown(table: pd.DataFrame) -> str:
    """The table as Markdown, percent for fractions, one block per preset."""
    lines = [
        f"**{LABEL}** — two-view matcher × fusion × number of agents; pooled pairwise F1, cycle "
        "violations, object-count error and clustering in percent; F1 gain over `independent` "
        "in points with its 95 % episode-level interval; time in ms per snapshot",
        "",
        "| Preset | N | Matcher | Fusion | F1 pooled | F1 gain [95 % CI] | cycle violations "
        "| count error | cluster P / R | ms / snapshot |",
        "|:---|---:|:---|:---|---:|---:|---:|---:|---:|---:|",
    ]
    ordered = table.sort_values(["preset", "n_agents", "matcher"], kind="stable")
    for row in ordered.itertuples(index=False):
        gain = (
            "–"
            if row.fusion == "independent"
            else f"{100 * row.f1_gain:+.1f} [{100 * row.gain_ci_low:+.1f}, "
            f"{100 * row.gain_ci_high:+.1f}]"
        )
        lines.append(
            f"| {row.preset} | {row.n_agents} | {row.matcher} | {row.fusion} "
            f"| {_pct(row.f1_pooled)} | {gain} | {_pct(row.cycle_violation_rate)} "
            f"| {_pct(row.count_error)} | {_pct(row.cluster_precision)} / "
            f"{_pct(row.cluster_recall)} | {row.ms_per_snapshot:.1f} |"
        )
    return "\n".join(lines)


def goals(table: pd.DataFrame, stage_s: float | None = None) -> list[str]:
    """Plain statements of the table's goals, each met or not, with the figures."""
    fused = table[table["fusion"] != "independent"]
    lines = []
    worst = fused["cycle_violation_rate"].max() if len(fused) else 0.0
    lines.append(
        f"fused outputs have no cycle violation: {'met' if worst == 0 else 'not met'} "
        f"(largest rate {100 * worst:.1f} %; `independent` up to "
        f"{100 * table.loc[table['fusion'] == 'independent', 'cycle_violation_rate'].max():.1f} %)"
    )
    wide = fused[fused["n_agents"] >= 4]
    if len(wide):
        best = wide.loc[wide["f1_gain"].idxmax()]
        met = best.f1_gain >= 0.05
        lines.append(
            "fusion raises pooled F1 over `independent` by ≥ 5 points at N ≥ 4 for some "
            f"matcher: {'met' if met else 'not met'} — the largest gain is "
            f"{100 * best.f1_gain:+.1f} points [{100 * best.gain_ci_low:+.1f}, "
            f"{100 * best.gain_ci_high:+.1f}] ({best.matcher} + {best.fusion}, N = "
            f"{best.n_agents}, {best.preset})"
        )
    six = table[(table["n_agents"] == table["n_agents"].max()) & (table["f1_pooled"] > 0)]
    if len(six):
        best = six.loc[six["count_error"].idxmin()]
        lines.append(
            f"object-count error ≤ 10 % at N = {best.n_agents} with the best method: "
            f"{'met' if best.count_error <= 0.10 else 'not met'} — {100 * best.count_error:.1f} % "
            f"({best.matcher} + {best.fusion}, {best.preset})"
        )
    pairs = len(SUBSETS[max(SUBSETS)]) * (len(SUBSETS[max(SUBSETS)]) - 1) // 2
    by = ["matcher", "fusion", "preset"]
    low, high = table["n_agents"].min(), table["n_agents"].max()
    ratio = (
        table[table["n_agents"] == high].set_index(by)["ms_per_snapshot"]
        / table[table["n_agents"] == low].set_index(by)["ms_per_snapshot"]
    ).replace([np.inf, -np.inf], np.nan)
    ratio = ratio[table[table["n_agents"] == high].set_index(by)["f1_pooled"] > 0].dropna()
    if len(ratio):
        fusion_ms = table.loc[table["n_agents"] == high, "fusion_ms_per_snapshot"].max()
        lines.append(
            f"time per snapshot at N = {high} ≤ {pairs} × the two-view time (N = {low}): "
            f"{'met' if ratio.max() <= pairs else 'not met'} — {ratio.min():.1f}× to "
            f"{ratio.max():.1f}× over the matchers and fusions; the fusions themselves take at "
            f"most {fusion_ms:.1f} ms per snapshot, the rest is the {pairs} pairs' matching, "
            "whose views beyond the first two hold more detections (a roadside unit sees more)"
        )
    if stage_s is not None:
        lines.append(
            f"this table's stages ≤ 2 min cold: {'met' if stage_s <= 120 else 'not met'} — "
            f"{stage_s:.0f} s in this run (generation and runs; a cached run re-fuses only)"
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
