"""``cadsim evaluate DATASET_DIR... --matchers all --runs 4 --out DIR``: calibrate τ on each
dataset's validation dataset, run every matcher on the test dataset with several seeds (cached,
parallel), and write per-pair metrics, AP, PR curves, Table I and the qualitative-figure input.

Each test dataset DIR is paired with a validation dataset from other simulation seeds: ``--val``
(same order), else ``DIR-val`` when it exists. ``--no-calibration`` reports the full Hungarian
assignment (τ = none) instead.
"""

from __future__ import annotations

import argparse
import json
import logging
from collections.abc import Sequence
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from cadsim.cli import int_in
from cadsim.limits import MAX_RUNS, MAX_WORKERS
from eval import calibration, tasks
from eval.cache import ResultCache
from eval.executor import add_scheduler_argument, make_executor
from eval.metrics import RankedAssignments, average_precision, pair_metrics, pooled_pr_curve
from eval.runner import Runner, requests_for
from eval.tables import PAPER_CSV, write_table1
from eval.tasks import MatcherSpec, RunResult

log = logging.getLogger(__name__)

PAPER_ORDER = ("sm", "rrwm", "hgm", "tm", "bcagm", "rrwhm", "mos", "maximin", "appearance")
QUALITATIVE_MATCHERS = ("rrwhm", "mos", "maximin")
DEFAULT_CACHE = "cache/runs"


@dataclass(frozen=True)
class DatasetEntry:
    """A test dataset and its validation dataset. label: the table's dataset name (``CAD``)."""

    label: str
    scenario: str
    test_dir: str
    test_checksum: str
    test_pairs: int
    val_dir: str | None = None
    val_checksum: str | None = None
    val_pairs: int = 0


def dataset_label(scenario_name: str) -> str:
    """Table name of a scenario: the part before the first '-', upper case (cad-x -> CAD)."""
    return scenario_name.split("-", 1)[0].upper()


def open_entry(test_dir: str | Path, val_dir: str | Path | None) -> DatasetEntry:
    """Open the test (and validation) dataset and describe them. Each is verified against its
    manifest's checksums (once per process for unchanged files): the result cache is keyed by
    the manifest's checksum, so a record modified after generation would otherwise go unseen."""
    test = tasks.open_dataset(str(test_dir))
    val = tasks.open_dataset(str(val_dir)) if val_dir is not None else None
    for dataset in (test, val):
        if dataset is not None:
            dataset.verify_once()
    if val is not None and val.scenario_name != test.scenario_name:
        raise ValueError(
            f"{val_dir}: validation scenario {val.scenario_name!r} differs from "
            f"{test_dir}'s {test.scenario_name!r}"
        )
    return DatasetEntry(
        label=dataset_label(test.scenario_name),
        scenario=test.scenario_name,
        test_dir=str(test_dir),
        test_checksum=test.checksum,
        test_pairs=len(test),
        val_dir=None if val is None else str(val_dir),
        val_checksum=None if val is None else val.checksum,
        val_pairs=0 if val is None else len(val),
    )


def parse_matchers(text: str) -> list[MatcherSpec]:
    """``all`` (every registered matcher, paper order first) or a comma-separated list."""
    from matchers.registry import available

    known = list(available())
    if text.strip() == "all":
        names = [n for n in PAPER_ORDER if n in known] + [n for n in known if n not in PAPER_ORDER]
    else:
        names = [n.strip() for n in text.split(",") if n.strip()]
        unknown = [n for n in names if n not in known]
        if unknown or not names:
            raise ValueError(
                f"--matchers: unknown {unknown or text!r}; available: {', '.join(known)}"
            )
    return [MatcherSpec(n) for n in dict.fromkeys(names)]


def score_runs(runs: Sequence[RunResult], taus: dict[str, float | None], **columns) -> pd.DataFrame:
    """One row per (run, frame pair): metrics of the prediction at the matcher's τ, plus the
    given constant `columns`."""
    rows = []
    for run in runs:
        label = run.spec.matcher.label
        tau = taus.get(label)
        for o in run.outcomes:
            m = pair_metrics(calibration.predictions(o, tau), o.gt_pairs, o.n1, o.n2)
            rows.append(
                columns
                | {
                    "matcher": label,
                    "seed": run.spec.seed,
                    "noise_rate": run.spec.noise_rate,
                    "pair": o.index,
                    "episode": o.episode,
                    "sim_seed": o.sim_seed,
                    "tau": np.nan if tau is None else tau,
                    **{k: getattr(m, k) for k in ("n1", "n2", "n_gt", "n_pred", "tp", "correct")},
                    **{k: getattr(m, k) for k in ("accuracy", "precision", "recall", "f1")},
                    "time_s": o.time_s,
                }
            )
    return pd.DataFrame(rows)


def _by_matcher(runs: Sequence[RunResult]) -> dict[str, list[RunResult]]:
    out: dict[str, list[RunResult]] = {}
    for run in runs:
        out.setdefault(run.spec.matcher.label, []).append(run)
    return out


def calibrate_entry(
    entry: DatasetEntry, matchers: Sequence[MatcherSpec], seeds: Sequence[int], runner: Runner
) -> tuple[list[RunResult], dict[str, calibration.Calibration]]:
    """Validation runs of `entry` and τ per matcher fitted on them (only on them)."""
    if entry.val_dir is None:
        return [], {}
    val_runs = runner.run(
        requests_for([(entry.val_dir, entry.val_checksum)], matchers, seeds),
        desc=f"{entry.label} validation",
    )
    return val_runs, {
        label: calibration.calibrate(runs) for label, runs in _by_matcher(val_runs).items()
    }


def representative_pair(runs: Sequence[RunResult]) -> int:
    """Index of the frame pair with the median number of covisible objects (lowest index on
    ties): a deterministic, not cherry-picked, pair for the qualitative figure."""
    counts = np.array([len(o.gt_pairs) for o in runs[0].outcomes])
    median = np.sort(counts)[(len(counts) - 1) // 2]
    return int(runs[0].outcomes[int(np.flatnonzero(counts == median)[0])].index)


def qualitative_entry(
    entry: DatasetEntry, test_runs: Sequence[RunResult], taus: dict[str, float | None]
) -> dict:
    """Predictions of the Fig. 3 matchers (first seed) on the representative test pair."""
    first_seed = min(r.spec.seed for r in test_runs)
    runs = [r for r in test_runs if r.spec.seed == first_seed]
    index = representative_pair(runs)
    methods = {}
    for run in runs:
        if run.spec.matcher.name not in QUALITATIVE_MATCHERS:
            continue
        outcome = next(o for o in run.outcomes if o.index == index)
        methods[run.spec.matcher.label] = calibration.predictions(
            outcome, taus.get(run.spec.matcher.label)
        ).tolist()
        gt = outcome.gt_pairs.tolist()
    if not methods:
        return {}
    return {
        "dataset_dir": entry.test_dir,
        "pair": index,
        "seed": first_seed,
        "gt_pairs": gt,
        "methods": methods,
    }


def ranking_quality(label: str, test_runs: Sequence[RunResult]) -> tuple[list[dict], pd.DataFrame]:
    """Threshold-free view of dataset `label`: AP rows per (matcher, run), and the PR curves of
    every matcher with its runs pooled."""
    ap_rows, curves = [], []
    for matcher, runs in _by_matcher(test_runs).items():
        for run in runs:
            curve = pooled_pr_curve(RankedAssignments.from_frames(run.ranking_frames()))
            ap = average_precision(curve)
            ap_rows.append({"dataset": label, "matcher": matcher, "seed": run.spec.seed, "ap": ap})
        pooled = pooled_pr_curve(
            RankedAssignments.from_frames([f for r in runs for f in r.ranking_frames()])
        )
        curves.append(
            pd.DataFrame(
                {"dataset": label, "matcher": matcher, "threshold": pooled.thresholds}
                | {"precision": pooled.precision, "recall": pooled.recall}
            )
        )
    return ap_rows, pd.concat(curves, ignore_index=True)


def evaluate(
    entries: Sequence[DatasetEntry],
    matchers: Sequence[MatcherSpec],
    seeds: Sequence[int],
    runner: Runner,
    out_dir: str | Path,
    calibrate: bool = True,
) -> dict:
    """The whole evaluation; writes thresholds.csv, metrics_per_pair.csv, average_precision.csv,
    pr_curves.csv, qualitative.json and evaluation.json into `out_dir`. Returns the τ table as
    {dataset label: {matcher label: τ or None}}."""
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    labels = [e.label for e in entries]
    if len(set(labels)) != len(labels):
        raise ValueError(f"datasets: two test datasets of the same scenario kind {labels}")
    tau_rows, per_pair, ap_rows, pr_rows, qualitative, taus_all = [], [], [], [], {}, {}
    for entry in entries:
        if calibrate and entry.val_dir is None:
            raise ValueError(
                f"{entry.test_dir}: no validation dataset (give --val DIR or create "
                f"{entry.test_dir}-val), or pass --no-calibration"
            )
        val_runs, fits = calibrate_entry(entry, matchers, seeds, runner) if calibrate else ([], {})
        test_runs = runner.run(
            requests_for([(entry.test_dir, entry.test_checksum)], matchers, seeds),
            desc=f"{entry.label} test",
        )
        if val_runs:
            calibration.check_disjoint(val_runs, test_runs)
        taus = {m.label: (fits[m.label].tau if m.label in fits else None) for m in matchers}
        taus_all[entry.label] = taus
        for label, fit in fits.items():
            tau_rows.append(
                {"dataset": entry.label, "matcher": label, "tau": fit.tau, "val_f1": fit.val_f1}
                | {"val_frames": fit.frames, "val_runs": fit.runs, "val_dir": entry.val_dir}
            )
        per_pair.append(score_runs(test_runs, taus, dataset=entry.label, split="test"))
        ap, pr = ranking_quality(entry.label, test_runs)
        ap_rows += ap
        pr_rows.append(pr)
        q = qualitative_entry(entry, test_runs, taus)
        if q:
            qualitative[entry.label] = q
    pd.DataFrame(
        tau_rows,
        columns=["dataset", "matcher", "tau", "val_f1", "val_frames", "val_runs", "val_dir"],
    ).to_csv(out_dir / "thresholds.csv", index=False)
    pd.concat(per_pair, ignore_index=True).to_csv(out_dir / "metrics_per_pair.csv", index=False)
    pd.DataFrame(ap_rows).to_csv(out_dir / "average_precision.csv", index=False)
    pd.concat(pr_rows, ignore_index=True).round(6).to_csv(out_dir / "pr_curves.csv", index=False)
    (out_dir / "qualitative.json").write_text(json.dumps(qualitative, indent=1), encoding="utf-8")
    record = {
        "datasets": [asdict(e) for e in entries],
        "matchers": [m.label for m in matchers],
        "seeds": list(seeds),
        "calibrated": calibrate,
        "thresholds": taus_all,
        "code_version": runner.version,
        "cache": str(runner.cache.root),
    }
    (out_dir / "evaluation.json").write_text(json.dumps(record, indent=1), encoding="utf-8")
    return taus_all


def add_runner_arguments(parser: argparse.ArgumentParser) -> None:
    """Options every cached, parallel command shares."""
    parser.add_argument("--matchers", default="all", help="'all' or a comma list (default: all)")
    parser.add_argument(
        "--runs",
        type=int_in(1, MAX_RUNS),
        default=4,
        help=f"runs with seeds 0..RUNS-1, RUNS in 1..{MAX_RUNS} (default 4)",
    )
    parser.add_argument("--out", default="results", help="output directory (default: results)")
    parser.add_argument(
        "--cache", default=DEFAULT_CACHE, help=f"result cache (default: {DEFAULT_CACHE})"
    )
    parser.add_argument(
        "--workers",
        type=int_in(1, MAX_WORKERS),
        default=None,
        help=f"processes, 1..{MAX_WORKERS} (default: one per core)",
    )
    add_scheduler_argument(parser)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("datasets", nargs="+", metavar="DATASET_DIR", help="test datasets")
    parser.add_argument("--val", nargs="+", metavar="DIR", help="validation datasets, same order")
    parser.add_argument(
        "--no-calibration", action="store_true", help="report full assignments (no τ)"
    )
    parser.add_argument("--paper", default=str(PAPER_CSV), help="the paper's Table I (CSV)")
    add_runner_arguments(parser)


def val_dirs(datasets: Sequence[str], given: Sequence[str] | None) -> list[str | None]:
    """Validation dataset per test dataset: `given` in order, else ``DIR-val`` if it exists."""
    if given:
        if len(given) != len(datasets):
            raise ValueError(f"--val: {len(given)} directories for {len(datasets)} datasets")
        return list(given)
    candidates = [str(Path(d).with_name(Path(d).name + "-val")) for d in datasets]
    return [c if (Path(c) / "manifest.json").is_file() else None for c in candidates]


def run(args: argparse.Namespace) -> int:
    vals = [None] * len(args.datasets) if args.no_calibration else val_dirs(args.datasets, args.val)
    entries = [open_entry(d, v) for d, v in zip(args.datasets, vals, strict=True)]
    matchers = parse_matchers(args.matchers)
    with make_executor(args.workers, args.scheduler) as executor:
        runner = Runner(ResultCache(args.cache), executor)
        evaluate(entries, matchers, range(args.runs), runner, args.out, not args.no_calibration)
    markdown = write_table1(args.out, args.paper)
    from eval.figures import render_all

    render_all(args.out)
    print(markdown)
    return 0
