"""Threshold-free views of a study's test runs: average precision per (matcher, run), pooled PR
curves, and the qualitative figure's representative pair (the median covisible count, not
cherry-picked). Imports ``eval/core/``, ``eval/protocol/``, this folder."""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np
import pandas as pd

from eval.core.result_files import recorded_path
from eval.core.tasks import RunResult
from eval.engine.splits import DatasetEntry
from eval.protocol import calibration
from eval.protocol.metrics import RankedAssignments, average_precision, pooled_pr_curve

QUALITATIVE_MATCHERS = ("rrwhm", "mos", "maximin")


def representative_pair(runs: Sequence[RunResult]) -> int:
    """Index of the frame pair with the median number of covisible objects (lowest index on
    ties): a deterministic, not cherry-picked, pair for the qualitative figure."""
    counts = np.array([len(o.gt_pairs) for o in runs[0].outcomes])
    median = np.sort(counts)[(len(counts) - 1) // 2]
    return int(runs[0].outcomes[int(np.flatnonzero(counts == median)[0])].index)


def qualitative_entry(
    entry: DatasetEntry,
    test_runs: Mapping[str, Sequence[RunResult]],
    taus: Mapping[str, float | None],
) -> dict:
    """Predictions of the Fig. 3 matchers (first seed) on the representative test pair."""
    all_runs = [r for runs in test_runs.values() for r in runs]
    first_seed = min(r.spec.seed for r in all_runs)
    index = representative_pair([r for r in all_runs if r.spec.seed == first_seed])
    methods, gt = {}, []
    for label, runs in test_runs.items():
        run = next(r for r in runs if r.spec.seed == first_seed)
        if run.spec.matcher.name not in QUALITATIVE_MATCHERS:
            continue
        outcome = next(o for o in run.outcomes if o.index == index)
        methods[label] = calibration.predictions(outcome, taus.get(label)).tolist()
        gt = outcome.gt_pairs.tolist()
    if not methods:
        return {}
    return {
        "dataset_dir": recorded_path(entry.test_dir),
        "pair": index,
        "seed": first_seed,
        "gt_pairs": gt,
        "methods": methods,
    }


def ranking_quality(
    label: str, test_runs: Mapping[str, Sequence[RunResult]]
) -> tuple[list[dict], pd.DataFrame]:
    """Threshold-free view of dataset `label`: AP rows per (matcher, run), and the PR curves of
    every matcher with its runs pooled."""
    ap_rows, curves = [], []
    for matcher, runs in test_runs.items():
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
