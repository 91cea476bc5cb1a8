"""Scoring helpers of the validation harness: protocol accuracy and tau calibration."""

from __future__ import annotations

import numpy as np
import pytest

from eval.protocol.metrics import metrics_at_thresholds
from eval.validation.coid_synthetic import FramePair, calibrate_threshold, ranked
from eval.validation.synthetic import accuracy


def _frame(n1: int, n2: int, truth: list[tuple[int, int]]) -> FramePair:
    return FramePair(
        points1=np.zeros((n1, 3)),
        points2=np.zeros((n2, 3)),
        features1=np.ones((n1, 2)),
        features2=np.ones((n2, 2)),
        truth=np.array(truth, dtype=int).reshape(-1, 2),
        ids1=np.arange(n1),
        ids2=np.arange(n2),
    )


def _result(frame: int, pairs: list[tuple[int, int]], scores: list[float], shape) -> dict:
    s = np.zeros(shape)
    p = np.array(pairs, dtype=int).reshape(-1, 2)
    s[p[:, 0], p[:, 1]] = scores
    return {"frame": frame, "pairs": p, "scores": s}


def test_protocol_accuracy_counts_unmatched_as_wrong():
    truth = np.array([2, 0, 1, 3])
    assert accuracy(np.array([[0, 2], [1, 0], [2, 1], [3, 3]]), truth) == 1.0
    assert accuracy(np.array([[0, 2], [1, 1], [2, 0]]), truth) == 0.25


def test_calibration_drops_exactly_the_low_scoring_wrong_pairs():
    frames = {0: _frame(3, 3, [(0, 0), (1, 1)]), 1: _frame(3, 4, [(0, 2)])}
    results = [
        _result(0, [(0, 0), (1, 1), (2, 2)], [0.9, 0.8, 0.1], (3, 3)),  # (2,2) wrong
        _result(1, [(0, 2), (1, 0), (2, 1)], [0.7, 0.3, 0.2], (3, 4)),  # last two wrong
    ]
    rk = ranked(results, frames)
    tau, f1 = calibrate_threshold(rk)
    assert tau == pytest.approx(0.5)  # midpoint of (0.3, 0.7]
    assert f1 == pytest.approx(1.0)
    at = metrics_at_thresholds(rk, [tau])
    np.testing.assert_allclose(at["precision"][:, 0], [1.0, 1.0])
    np.testing.assert_allclose(at["accuracy"][:, 0], [1.0, 1.0])


def test_calibration_keeps_everything_when_all_pairs_are_right():
    frames = {0: _frame(2, 2, [(0, 0), (1, 1)])}
    rk = ranked([_result(0, [(0, 0), (1, 1)], [0.5, 0.1], (2, 2))], frames)
    assert calibrate_threshold(rk) == (pytest.approx(0.05), 1.0)  # below the lowest score


def test_calibration_returns_the_middle_of_the_best_interval():
    # every tau in (0.2, 0.9] keeps the right pair and drops the wrong one
    frames = {0: _frame(2, 2, [(0, 0)])}
    rk = ranked([_result(0, [(0, 0), (1, 1)], [0.9, 0.2], (2, 2))], frames)
    assert calibrate_threshold(rk) == (pytest.approx(0.55), 1.0)
