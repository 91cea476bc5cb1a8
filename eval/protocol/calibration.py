"""Acceptance thresholds τ: calibrated per matcher on validation runs, applied to cached scores.

A matcher's prediction at τ is its Hungarian assignment with the pairs scoring below τ dropped
(``matchers.core.discretise``; :func:`predictions` applies it to the cached assignment). :func:`calibrate` picks the τ that maximises the mean per-pair F1 over
the validation frame pairs of all given runs (every seed pooled). F1 is piecewise constant in τ,
changing only at assigned scores; τ is put in the middle of the best interval (between the best
candidate score and the next lower one), so it does not sit on a validation score; ties go to the
highest τ. :func:`check_disjoint` refuses validation runs that share a frame pair (record
checksum) or a simulation seed with the test runs.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass

import numpy as np

from eval.core.tasks import PairOutcome, RunResult
from eval.protocol.metrics import RankedAssignments, candidate_thresholds, metrics_at_thresholds


@dataclass(frozen=True)
class Calibration:
    """τ for one matcher: tau, the mean validation F1 it gives, the frame pairs (over all runs)
    and runs it was fitted on; thresholds (descending) and f1 trace the sweep."""

    tau: float
    val_f1: float
    frames: int
    runs: int
    thresholds: np.ndarray
    f1: np.ndarray


def calibrate(val_runs: Sequence[RunResult]) -> Calibration:
    """τ maximising the mean per-pair F1 over the frame pairs of `val_runs` (one matcher)."""
    if not val_runs:
        raise ValueError("val_runs: no validation runs to calibrate on")
    names = {r.spec.matcher for r in val_runs}
    if len(names) != 1:
        raise ValueError(
            f"val_runs: expected runs of one matcher, got {sorted(m.label for m in names)}"
        )
    frames = [f for run in val_runs for f in run.ranking_frames()]
    if not frames:
        raise ValueError("val_runs: the validation runs hold no frame pairs")
    ranked = RankedAssignments.from_frames(frames)
    tau, best_f1, thresholds, f1 = calibrate_ranked(ranked)
    return Calibration(tau, best_f1, len(frames), len(val_runs), thresholds, f1)


def calibrate_ranked(ranked: RankedAssignments) -> tuple[float, float, np.ndarray, np.ndarray]:
    """The τ rule on ranked validation assignments: (τ, its mean per-pair F1, candidate
    thresholds (descending), mean F1 at each). F1 changes only at assigned scores, so τ is the
    middle of the best interval (between the best candidate and the next lower one, or 0); ties go
    to the highest τ; when keeping nothing is best, τ is the top candidate."""
    thresholds = candidate_thresholds(ranked)
    f1 = metrics_at_thresholds(ranked, thresholds)["f1"].mean(axis=0)
    best = int(np.argmax(f1))  # thresholds descend: the first maximum is the highest τ
    if best == 0:
        tau = float(thresholds[0])  # keep nothing
    else:
        lower = thresholds[best + 1] if best + 1 < len(thresholds) else 0.0
        tau = float((thresholds[best] + lower) / 2)
    return tau, float(f1[best]), thresholds, f1


def frame_identities(runs: Iterable[RunResult]) -> tuple[set[str], set[int]]:
    """(record checksums, simulation seeds) of every frame pair in `runs`."""
    outcomes = [o for r in runs for o in r.outcomes]
    return {o.checksum for o in outcomes}, {o.sim_seed for o in outcomes}


def check_disjoint(val_runs: Iterable[RunResult], test_runs: Iterable[RunResult]) -> None:
    """``ValueError`` if a validation frame pair, or its simulation seed, is also in the test runs."""
    val_sums, val_seeds = frame_identities(val_runs)
    test_sums, test_seeds = frame_identities(test_runs)
    if val_sums & test_sums:
        raise ValueError(f"validation and test share {len(val_sums & test_sums)} frame pair(s)")
    if val_seeds & test_seeds:
        raise ValueError(
            f"validation and test share simulation seeds {sorted(val_seeds & test_seeds)[:5]}: "
            "generate the validation dataset with another --seed"
        )


def predictions(outcome: PairOutcome, tau: float | None) -> np.ndarray:
    """(k, 2) predicted pairs of `outcome` at acceptance threshold `tau` (None: all assigned):
    the matcher's own assignment with the pairs scoring below τ dropped. For every matcher that
    discretises with ``matchers.core.discretise`` this is ``discretise(scores, tau)``; a matcher whose
    assignment is smaller (``none`` declares nothing) keeps its own."""
    assigned = np.asarray(outcome.assigned, dtype=np.int64).reshape(-1, 2)
    if tau is None:
        return assigned
    return assigned[outcome.assigned_scores >= tau]
