"""``cadsim sweep-regime DATASET --val VAL --keep 1,0.75,0.5,0.25,0 --out DIR``: every matcher
against the share of non-covisible objects, from the dataset's natural share down to 0.

At each keep level every non-covisible detection of every frame pair (validation and test alike)
stays with that probability (:mod:`eval.core.thinning`: seeded per frame pair, nested levels), τ is
recalibrated on the thinned validation set, and the matchers run on the thinned test set. The
matchers run with the parameters ``DIR/thresholds.csv`` records for this dataset (tuned when the
evaluation was; else their defaults). Level 1 is the untouched dataset and shares its cached runs.

Each run is its own thinning draw (the run's seed is the draw index, :mod:`eval.core.thinning`), so
``--runs`` sets how many independent draws each level averages; ``f1_ci_low``/``f1_ci_high`` is the
95 % cluster-robust t-interval of the level's mean F1 over simulation episodes, each frame pair
averaged over its draws first (:mod:`eval.protocol.cluster_interval`). Every crossover carries a
bootstrap interval that resamples episodes and draws together
(:mod:`eval.protocol.episode_draw_bootstrap`: a crossing share is not a mean, so it has no
t-interval).

Writes (rows of other datasets already there are kept, this dataset's replaced):
``regime_sweep.csv`` (:data:`SWEEP_COLUMNS`), ``crossovers.csv`` (:mod:`eval.protocol.crossovers`) and
``fig_regime.png/.pdf``.
"""

from __future__ import annotations

import argparse
from collections.abc import Sequence
from pathlib import Path
from typing import NamedTuple

import pandas as pd

from eval.commands.evaluate import add_localisation_argument, add_runner_arguments
from eval.core.cache import ResultCache
from eval.core.executor import make_executor
from eval.core.keyed_csv import upsert_csv
from eval.core.runner import Runner
from eval.core.thinning import check_keep, noncovisible_share
from eval.engine.matcher_list import parse_matchers
from eval.engine.named_runs import calibrate_entry, run_named, score_runs
from eval.engine.splits import DatasetEntry, Named, open_entry, val_dirs
from eval.engine.validation_choice import chosen_specs
from eval.protocol.cluster_interval import t_interval
from eval.protocol.crossovers import find_crossovers
from eval.report.threshold_format import rounded

DEFAULT_KEEP = (1.0, 0.75, 0.5, 0.25, 0.0)
SWEEP_COLUMNS = (
    "dataset",
    "keep",
    "share",
    "matcher",
    "f1_mean",
    "f1_std",
    "f1_ci_low",
    "f1_ci_high",
    "balanced_accuracy_mean",
    "recall_mean",
    "tau",
    "pairs",
    "runs",
)


def parse_keep(text: str) -> list[float]:
    """Comma-separated keep levels in [0, 1], returned descending without repeats."""
    try:
        levels = [check_keep(float(k)) for k in text.split(",") if k.strip()]
    except ValueError as exc:
        raise ValueError(
            f"--keep: expected comma-separated numbers in [0, 1], got {text!r}"
        ) from exc
    if not levels:
        raise ValueError(f"--keep: expected at least one level, got {text!r}")
    return sorted(set(levels), reverse=True)


def summarise_level(per_pair: pd.DataFrame, dataset: str, keep: float) -> pd.DataFrame:
    """Rows of ``regime_sweep.csv`` for one level: per matcher, per-run means over the frame
    pairs, then mean (and std of F1) over runs; ``share`` is the achieved non-covisible share of
    the thinned test pairs (objects pooled over pairs and draws)."""
    pairs = per_pair.drop_duplicates(["pair", "seed"])
    share = noncovisible_share(pairs["n1"], pairs["n2"], pairs["n_gt"])
    per_run = per_pair.groupby(["matcher", "seed"], sort=False)[
        ["f1", "balanced_accuracy", "recall"]
    ].mean()
    grouped = per_run.groupby(level=0, sort=False)
    out = pd.DataFrame(
        {
            "f1_mean": grouped["f1"].mean(),
            "f1_std": grouped["f1"].std(ddof=1).fillna(0.0),
            "balanced_accuracy_mean": grouped["balanced_accuracy"].mean(),
            "recall_mean": grouped["recall"].mean(),
            "tau": per_pair.groupby("matcher", sort=False)["tau"].first(),
            "pairs": per_pair.groupby("matcher", sort=False)["pair"].nunique(),
            "runs": grouped.size(),
        }
    ).reset_index(names="matcher")
    out.insert(0, "share", share)
    out.insert(0, "keep", keep)
    out.insert(0, "dataset", dataset)
    return out


def level_intervals(per_pair: pd.DataFrame, metric: str = "f1") -> pd.DataFrame:
    """Per (matcher, keep): the 95 % interval of the mean `metric` over frame pairs (each pair
    averaged over its runs first), a cluster-robust t-interval over simulation episodes
    (:mod:`eval.protocol.cluster_interval`); columns ``matcher``, ``keep``,
    ``{metric}_ci_low``, ``{metric}_ci_high``."""
    rows = []
    means = per_pair.groupby(["matcher", "keep", "pair"], sort=False).agg(
        value=(metric, "mean"), episode=("episode", "first")
    )
    for (matcher, keep), group in means.groupby(level=[0, 1], sort=False):
        values, episodes = group["value"].to_numpy(), group["episode"].to_numpy()
        _, low, high, _ = t_interval(values, episodes, bounds=(0.0, 1.0))  # a rate
        rows.append({"matcher": matcher, "keep": keep, f"{metric}_ci_low": low,
                     f"{metric}_ci_high": high})  # fmt: skip
    return pd.DataFrame(rows)


class SweepResult(NamedTuple):
    """The sweep of one dataset: ``rows`` of ``regime_sweep.csv`` and of ``crossovers.csv``."""

    rows: pd.DataFrame
    crossovers: pd.DataFrame


def sweep_regime(
    entry: DatasetEntry,
    named: Named,
    seeds: Sequence[int],
    keeps: Sequence[float],
    runner: Runner,
    limit: int | None = None,
    val_seeds: Sequence[int] | None = None,
) -> SweepResult:
    """The sweep of `entry`: for each keep level, τ recalibrated on the thinned validation
    dataset (runs `val_seeds`, default `seeds`: their thinning draws), then the thinned test
    dataset's first `limit` frame pairs (None: all) with `seeds` (one thinning draw each)."""
    if entry.val_dir is None:
        raise ValueError(f"{entry.test_dir}: the regime sweep needs a validation dataset (--val)")
    rows, scored = [], []
    for keep in keeps:
        keep_or_none = None if keep == 1.0 else keep
        _, fits = calibrate_entry(entry, named, list(val_seeds or seeds), runner, keep=keep_or_none)
        taus = {label: fits[label].tau for label in named}
        test_runs = run_named(
            runner,
            (entry.test_dir, entry.test_checksum),
            named,
            seeds,
            f"{entry.label} keep {keep:g}",
            limit=limit,
            keep=keep_or_none,
            localisation=entry.localisation,
        )
        per_pair = score_runs(test_runs, taus, dataset=entry.label)
        rows.append(summarise_level(per_pair, entry.label, keep))
        scored.append(per_pair.assign(keep=keep))
    per_pair = pd.concat(scored, ignore_index=True)
    summary = pd.concat(rows, ignore_index=True).merge(
        level_intervals(per_pair), on=["matcher", "keep"], how="left"
    )
    return SweepResult(summary[list(SWEEP_COLUMNS)], find_crossovers(per_pair))


def write_sweep(out_dir: str | Path, result: SweepResult, draw: bool = True) -> list[Path]:
    """Merge the sweep's rows into ``regime_sweep.csv`` and ``crossovers.csv`` (its datasets'
    rows replaced, the others kept), then redraw the figure from the whole table (``draw=False``:
    not yet — a caller sweeping several datasets draws once after the last); returns the
    written paths."""
    from eval.report.figures import write_fig_regime

    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    upsert_csv(out_dir / "regime_sweep.csv", rounded(result.rows))
    upsert_csv(out_dir / "crossovers.csv", result.crossovers.round(4))
    written = [out_dir / "regime_sweep.csv", out_dir / "crossovers.csv"]
    return written + (write_fig_regime(out_dir) if draw else [])


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("dataset", metavar="DATASET_DIR", help="test dataset")
    parser.add_argument(
        "--val", default=None, metavar="DIR", help="validation dataset (default: DATASET_DIR-val)"
    )
    parser.add_argument(
        "--keep",
        default=",".join(f"{k:g}" for k in DEFAULT_KEEP),
        help="keep levels of non-covisible detections (default 1,0.75,0.5,0.25,0)",
    )
    parser.add_argument("--pairs", type=int, default=None, help="only the first N test pairs")
    parser.add_argument(
        "--val-runs", type=int, default=None, help="validation runs for τ (default: --runs)"
    )
    add_localisation_argument(parser)
    add_runner_arguments(parser)


def run(args: argparse.Namespace) -> int:
    from eval.core.result_files import check_outputs

    check_outputs(args.out, args.cache)
    (val,) = val_dirs([args.dataset], [args.val] if args.val else None)
    entry = open_entry(args.dataset, val, localisation=args.localisation)
    named, _ = chosen_specs(args.out, entry.label, parse_matchers(args.matchers))
    keeps = parse_keep(args.keep)
    val_seeds = range(args.val_runs) if args.val_runs else None
    with make_executor(args.workers, args.scheduler) as executor:
        runner = Runner(
            ResultCache(args.cache),
            executor,
            progress=not args.no_progress,
            plugin_time_limit_s=args.plugin_time_limit,
        )
        result = sweep_regime(entry, named, range(args.runs), keeps, runner, args.pairs, val_seeds)
    for path in write_sweep(args.out, result):
        print(path)
    return 0
