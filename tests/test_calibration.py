"""Threshold calibration: maximises validation F1, never sees test frames, applies τ like the
matchers' shared discretisation."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest
from test_runner import fake_matcher, make_datasets

from eval.core import tasks
from eval.core.cache import ResultCache
from eval.core.executor import SerialExecutor
from eval.core.runner import Runner
from eval.core.tasks import MatcherSpec, PairOutcome, RunResult, RunSpec
from eval.engine.protocol_run import evaluate
from eval.engine.splits import open_entry
from eval.protocol import calibration
from matchers.core.discretise import discretise


def _outcome(index, sim_seed, scores, gt, assigned=None):
    scores = np.asarray(scores, float)
    assigned = discretise(scores) if assigned is None else np.asarray(assigned)
    return PairOutcome(
        index=index, name=f"p{index}", episode=index, sim_seed=sim_seed, checksum=f"{sim_seed:064x}",
        n1=scores.shape[0], n2=scores.shape[1], gt_pairs=np.asarray(gt, np.int64).reshape(-1, 2),
        assigned=assigned, scores=scores, time_s=0.0, iterations=0,
    )  # fmt: skip


def _run(outcomes, matcher="m", seed=0):
    return RunResult(RunSpec("x", MatcherSpec(matcher), seed, None, "v"), "val", outcomes)


def test_tau_separates_right_from_wrong_pairs_and_sits_between_them():
    # Right pairs score 0.9 and 1.0, the wrong (non-covisible) pair 0.3.
    scores = np.array([[1.0, 0.0, 0.0], [0.0, 0.9, 0.0], [0.0, 0.0, 0.3]])
    fit = calibration.calibrate([_run([_outcome(0, 1, scores, [[0, 0], [1, 1]])])])
    assert fit.tau == pytest.approx((0.9 + 0.3) / 2)
    assert fit.val_f1 == pytest.approx(1.0)
    assert (fit.frames, fit.runs) == (1, 1)


def test_tau_keeps_everything_when_every_assigned_pair_is_right():
    scores = np.array([[1.0, 0.1], [0.2, 0.4]])
    fit = calibration.calibrate([_run([_outcome(0, 1, scores, [[0, 0], [1, 1]])])])
    assert fit.tau <= 0.4
    np.testing.assert_array_equal(
        calibration.predictions(_outcome(0, 1, scores, []), fit.tau), [[0, 0], [1, 1]]
    )


def test_calibration_pools_seeds_and_maximises_mean_f1():
    good = _outcome(0, 1, [[1.0, 0.0], [0.0, 0.5]], [[0, 0], [1, 1]])
    bad = _outcome(1, 2, [[1.0, 0.0], [0.0, 0.6]], [[0, 0]])
    fit = calibration.calibrate([_run([good], seed=0), _run([bad], seed=1)])
    # τ ≤ 0.5: F1 = (1 + 2/3) / 2; 0.5 < τ ≤ 0.6: (2/3 + 2/3) / 2; τ > 0.6: (2/3 + 1) / 2.
    assert fit.val_f1 == pytest.approx((1 + 2 / 3) / 2)
    assert fit.tau <= 0.5 or fit.tau > 0.6
    assert fit.runs == 2 and fit.frames == 2


def test_calibrate_rejects_empty_and_mixed_input():
    with pytest.raises(ValueError, match="no validation runs"):
        calibration.calibrate([])
    o = _outcome(0, 1, [[1.0]], [[0, 0]])
    with pytest.raises(ValueError, match="one matcher"):
        calibration.calibrate([_run([o], "a"), _run([o], "b")])


def test_predictions_match_the_shared_discretisation_and_the_sweep():
    rng = np.random.default_rng(3)
    for _ in range(20):
        scores = rng.uniform(size=(rng.integers(1, 7), rng.integers(1, 7)))
        o = _outcome(0, 1, scores, [])
        for tau in (0.0, 0.3, 0.7, 1.0):
            expected = o.assigned[o.assigned_scores >= tau]
            np.testing.assert_array_equal(calibration.predictions(o, tau), expected)
            np.testing.assert_array_equal(calibration.predictions(o, tau), discretise(scores, tau))
        np.testing.assert_array_equal(calibration.predictions(o, None), discretise(scores))


def test_a_matcher_that_assigns_nothing_predicts_nothing_even_without_tau():
    o = _outcome(0, 1, np.zeros((3, 4)), [[0, 0]], assigned=np.zeros((0, 2), np.int64))
    assert calibration.predictions(o, None).shape == (0, 2)
    assert calibration.predictions(o, 0.0).shape == (0, 2)


def test_check_disjoint_refuses_shared_frames_or_simulation_seeds():
    a = _run([_outcome(0, 11, [[1.0]], [[0, 0]])])
    b = _run([_outcome(0, 12, [[1.0]], [[0, 0]])])
    calibration.check_disjoint([a], [b])
    with pytest.raises(ValueError, match="share"):
        calibration.check_disjoint([a], [a])


def test_evaluation_calibrates_on_validation_frames_only(tmp_path, monkeypatch):
    datasets = make_datasets({"data/cad": (100, 4), "data/cad-val": (900, 3)})
    monkeypatch.setattr(tasks, "open_dataset", lambda path: datasets[path])
    monkeypatch.setattr(tasks, "matcher_function", lambda name: fake_matcher)
    seen: list[RunResult] = []
    real = calibration.calibrate

    def spy(runs):
        seen.extend(runs)
        return real(runs)

    monkeypatch.setattr(calibration, "calibrate", spy)
    runner = Runner(ResultCache(tmp_path / "cache"), SerialExecutor(), version="v", progress=False)
    entry = open_entry("data/cad", "data/cad-val")
    assert entry.label == "CAD"
    matchers = [MatcherSpec("a"), MatcherSpec("b")]
    taus = evaluate([entry], matchers, [0, 1], runner, tmp_path / "out")

    val_seeds = {p.sim_seed for p in datasets["data/cad-val"]}
    test_seeds = {p.sim_seed for p in datasets["data/cad"]}
    received = {o.sim_seed for run in seen for o in run.outcomes}
    assert received == val_seeds and not received & test_seeds
    assert {r.dataset_dir for r in seen} == {"data/cad-val"}
    assert len(seen) == 4  # 2 matchers × 2 seeds

    thresholds = pd.read_csv(tmp_path / "out" / "thresholds.csv")
    assert set(thresholds["matcher"]) == {"a", "b"}
    assert dict(zip(thresholds["matcher"], thresholds["tau"], strict=True)) == pytest.approx(
        taus["CAD"]
    )
    per_pair = pd.read_csv(tmp_path / "out" / "metrics_per_pair.csv")
    assert set(per_pair["sim_seed"]) == test_seeds
    assert len(per_pair) == 4 * 2 * 2
    record = json.loads((tmp_path / "out" / "evaluation.json").read_text())
    assert record["thresholds"]["CAD"] == pytest.approx(taus["CAD"])


def test_evaluation_refuses_a_validation_set_from_the_test_seeds(tmp_path, monkeypatch):
    datasets = make_datasets({"data/cad": (100, 3), "data/cad-val": (101, 2)})  # overlapping seeds
    monkeypatch.setattr(tasks, "open_dataset", lambda path: datasets[path])
    monkeypatch.setattr(tasks, "matcher_function", lambda name: fake_matcher)
    runner = Runner(ResultCache(tmp_path / "cache"), SerialExecutor(), version="v", progress=False)
    with pytest.raises(ValueError, match="share"):
        evaluate(
            [open_entry("data/cad", "data/cad-val")], [MatcherSpec("a")], [0], runner, tmp_path
        )
