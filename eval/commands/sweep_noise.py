"""``cadsim sweep-noise DATASET_DIR --rates 0,0.001,... --out DIR``: Fig. 4 — every matcher's
accuracy, precision and recall against the depth-noise rate.

Each (rate, seed) re-applies noise to the stored clean depth and re-detects
(``FramePair.redetect``; nothing is re-rendered); all matchers of that run see the same detections.
Predictions use the matchers' parameters and calibrated τ from ``DIR/thresholds.csv`` (written by
``cadsim evaluate``, tuned when it tuned; noise-free calibration, as deployed) or, for a matcher it
lacks, the defaults and τ fitted here on the validation dataset's stored detections.
"""

from __future__ import annotations

import argparse
from collections.abc import Sequence
from pathlib import Path

import pandas as pd

from cadsim.cli import int_in
from cadsim.limits import MAX_NOISE_RATE, MAX_PAIRS
from eval.commands.evaluate import add_localisation_argument, add_runner_arguments
from eval.core.cache import ResultCache
from eval.core.executor import make_executor
from eval.core.keyed_csv import upsert_csv
from eval.core.runner import Runner
from eval.core.tasks import MatcherSpec
from eval.engine.matcher_list import parse_matchers
from eval.engine.named_runs import calibrate_entry, run_named, score_runs
from eval.engine.splits import DatasetEntry, Named, open_entry, val_dirs
from eval.engine.validation_choice import chosen_specs
from eval.protocol.metrics import METRICS

# Fig. 4's default x axis: σ = rate · d² (metres) — at 20 m depth, 0.12 m … 40 m. On CAD, 3e-4 has
# no visible effect and ≥ 0.03 is severe (docs/evaluation.md).
DEFAULT_RATES = (0.0, 0.0003, 0.001, 0.003, 0.01, 0.03, 0.1)


def parse_rates(text: str) -> list[float]:
    """Comma-separated noise rates, each finite and in [0, MAX_NOISE_RATE]; sorted, distinct."""
    try:
        rates = [float(r) for r in text.split(",") if r.strip()]
    except ValueError as exc:
        raise ValueError(f"--rates: expected comma-separated numbers, got {text!r}") from exc
    if not rates or not all(0 <= r <= MAX_NOISE_RATE for r in rates):  # NaN fails too
        raise ValueError(
            f"--rates: expected one or more rates in [0, {MAX_NOISE_RATE:g}], got {text!r}"
        )
    return sorted(set(rates))


def thresholds_for(
    out_dir: Path, entry: DatasetEntry, matchers: Sequence[MatcherSpec], seeds, runner: Runner
) -> tuple[Named, dict[str, float | None]]:
    """Spec and τ per matcher: from out_dir/thresholds.csv for this dataset, else the requested
    spec calibrated here."""
    named, taus = chosen_specs(out_dir, entry.label, matchers)
    missing = {label: spec for label, spec in named.items() if taus[label] is None}
    if missing and entry.val_dir is not None:
        _, fits = calibrate_entry(entry, missing, seeds, runner)
        taus |= {label: fit.tau for label, fit in fits.items()}
    return named, taus


def sweep(
    entry: DatasetEntry,
    matchers: Sequence[MatcherSpec],
    seeds: Sequence[int],
    rates: Sequence[float],
    runner: Runner,
    out_dir: str | Path,
    limit: int | None = None,
) -> pd.DataFrame:
    """Run the sweep on the first `limit` frame pairs (None: all); write this dataset's rows of
    ``noise_runs.csv`` (per-run means over the frame pairs; other datasets' rows are kept) and
    return them."""
    if limit is not None and limit < 1:
        raise ValueError(f"--pairs: expected >= 1 frame pairs, got {limit}")
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    named, taus = thresholds_for(out_dir, entry, matchers, seeds, runner)
    runs = run_named(
        runner,
        (entry.test_dir, entry.test_checksum),
        named,
        seeds,
        f"{entry.label} noise sweep",
        noise_rates=rates,
        limit=limit,
        localisation=entry.localisation,
    )
    per_pair = score_runs(runs, taus, dataset=entry.label)
    per_run = (
        per_pair.groupby(["dataset", "matcher", "noise_rate", "seed"], sort=False)
        .agg(
            **{m: (m, "mean") for m in METRICS},
            frames=("pair", "size"),
            tau=("tau", "first"),
            params=("params", "first"),
        )
        .reset_index()
    )
    upsert_csv(out_dir / "noise_runs.csv", per_run)
    return per_run


def f1_summary(per_run: pd.DataFrame) -> str:
    """The sweep's numbers as a markdown table: per matcher (rows) and noise rate (columns),
    F1 in percent, mean ± standard deviation over runs (as fig4's lines and bands)."""
    from eval.report.tables import matcher_order, method_name

    stats = per_run.groupby(["matcher", "noise_rate"], sort=False)["f1"]
    mean, std = stats.mean() * 100, stats.std(ddof=1).fillna(0.0) * 100
    rates = sorted(per_run["noise_rate"].unique())
    matchers = sorted(per_run["matcher"].unique(), key=matcher_order)
    lines = [
        f"F1 (%) by noise rate (σ = rate · d²), mean ± std over {per_run['seed'].nunique()} runs",
        "| Method | " + " | ".join(f"{r:g}" for r in rates) + " |",
        "|:---|" + "---:|" * len(rates),
    ]
    for m in matchers:
        cells = [
            f"{mean[(m, r)]:.1f} ± {std[(m, r)]:.1f}" if (m, r) in mean.index else "–"
            for r in rates
        ]
        lines.append(f"| {method_name(m)} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("dataset", metavar="DATASET_DIR", help="test dataset (CAD in the paper)")
    parser.add_argument(
        "--rates",
        default=",".join(str(r) for r in DEFAULT_RATES),
        help="comma-separated noise rates (σ = rate·d², d in metres)",
    )
    parser.add_argument(
        "--val", default=None, metavar="DIR", help="validation dataset (default: DATASET_DIR-val)"
    )
    parser.add_argument(
        "--pairs",
        type=int_in(1, MAX_PAIRS),
        default=None,
        help="only the first N frame pairs (N >= 1)",
    )
    add_localisation_argument(parser)
    add_runner_arguments(parser)


def run(args: argparse.Namespace) -> int:
    from eval.core.result_files import check_outputs

    check_outputs(args.out, args.cache)
    rates = parse_rates(args.rates)
    (val,) = val_dirs([args.dataset], [args.val] if args.val else None)
    entry = open_entry(args.dataset, val, localisation=args.localisation)
    matchers = parse_matchers(args.matchers)
    with make_executor(args.workers, args.scheduler) as executor:
        runner = Runner(
            ResultCache(args.cache),
            executor,
            progress=not args.no_progress,
            plugin_time_limit_s=args.plugin_time_limit,
        )
        per_run = sweep(entry, matchers, range(args.runs), rates, runner, args.out, args.pairs)
    print(f1_summary(per_run))
    from eval.report.figures import write_fig4

    for path in write_fig4(args.out):
        print(path)
    return 0
