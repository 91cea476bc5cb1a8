"""Test (and validation) runs through the executor: every spec of a study on a split × seeds ×
noise rates from the cached runner, scored at each row's τ, and τ fitted on validation runs
only (:mod:`eval.protocol.calibration`). Imports ``eval/core/``, ``eval/protocol/``, this
folder."""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np
import pandas as pd

from eval.core.pose_metrics import outcome_pose
from eval.core.runner import Runner, requests_for
from eval.core.tasks import MatcherSpec, RunResult
from eval.engine.splits import DatasetEntry, Named
from eval.protocol import calibration, tuning
from eval.protocol.metrics import pair_metrics


def as_named(matchers: Sequence[MatcherSpec] | Mapping[str, MatcherSpec]) -> Named:
    """{row label: spec}: a mapping as given, a list of specs under their own labels."""
    if isinstance(matchers, Mapping):
        return dict(matchers)
    return {m.label: m for m in matchers}


def run_named(
    runner: Runner,
    dataset: tuple[str, str],
    named: Named,
    seeds: Sequence[int],
    desc: str,
    *,
    noise_rates: Sequence[float | None] = (None,),
    limit: int | None = None,
    keep: float | None = None,
    localisation: str | None = None,
    sensor: str | None = None,
) -> dict[str, list[RunResult]]:
    """Runs of every spec of `named` on `dataset` (dir, checksum) × seeds × noise rates, grouped
    by row label (seed order, then rate order); `localisation`: a preset re-drawing the prior;
    `sensor`: the sensor a two-sensor dataset is read as (None: as stored)."""
    specs = list(dict.fromkeys(named.values()))
    requests = requests_for(
        [dataset], specs, seeds, noise_rates, limit, keep, localisation, sensor=sensor
    )
    runs = runner.run(requests, desc=desc)
    by_spec: dict[MatcherSpec, list[RunResult]] = {}
    for run in runs:
        by_spec.setdefault(run.spec.matcher, []).append(run)
    return {label: by_spec[spec] for label, spec in named.items()}


def score_runs(
    runs: Mapping[str, Sequence[RunResult]], taus: Mapping[str, float | None], **columns
) -> pd.DataFrame:
    """One row per (row label, run, frame pair): metrics of the prediction at the label's τ, the
    run's matcher options (``params``, JSON), plus the given constant `columns`."""
    rows = []
    scored: dict[tuple[int, float | None], tuple] = {}  # (id(outcome), τ) -> its scores
    for label, label_runs in runs.items():
        tau = taus.get(label)
        for run in label_runs:
            params = tuning.params_json(dict(run.spec.matcher.options))
            for o in run.outcomes:
                # a seed-free matcher's runs for other seeds hold the very same outcomes
                # (eval.core.runner): scored once
                key = (id(o), tau)
                if key not in scored:
                    predicted = calibration.predictions(o, tau)
                    m = pair_metrics(predicted, o.gt_pairs, o.n1, o.n2)
                    scored[key] = (m, outcome_pose(o, predicted))
                m, pose = scored[key]
                rows.append(
                    columns
                    | {
                        "matcher": label,
                        "params": params,
                        "seed": run.spec.seed,
                        "noise_rate": run.spec.noise_rate,
                        "keep": run.spec.keep,
                        "pair": o.index,
                        "episode": o.episode,
                        "sim_seed": o.sim_seed,
                        "tau": np.nan if tau is None else tau,
                        **{
                            k: getattr(m, k)
                            for k in ("n1", "n2", "n_gt", "n_pred", "tp", "correct")
                        },
                        **{
                            k: getattr(m, k)
                            for k in ("accuracy", "balanced_accuracy", "precision", "recall")
                        },
                        "f1": m.f1,
                        "time_s": o.time_s,
                    }
                    | pose
                )
    return pd.DataFrame(rows)


def calibrate_named(
    runs: Mapping[str, Sequence[RunResult]],
) -> dict[str, calibration.Calibration]:
    """τ per row label, fitted on its (validation) runs only."""
    return {label: calibration.calibrate(label_runs) for label, label_runs in runs.items()}


def calibrate_entry(
    entry: DatasetEntry,
    matchers: Sequence[MatcherSpec] | Mapping[str, MatcherSpec],
    seeds: Sequence[int],
    runner: Runner,
    keep: float | None = None,
) -> tuple[dict[str, list[RunResult]], dict[str, calibration.Calibration]]:
    """Validation runs of `entry` (non-covisible detections thinned to `keep`) and τ per row
    label fitted on them (only on them)."""
    if entry.val_dir is None:
        return {}, {}
    val_runs = run_named(
        runner,
        (entry.val_dir, entry.val_checksum),
        as_named(matchers),
        seeds,
        f"{entry.label} validation",
        keep=keep,
        localisation=entry.localisation,
        sensor=entry.sensor,
    )
    return val_runs, calibrate_named(val_runs)
