"""Metrics (DESIGN §3) on hand-computed cases, and the threshold sweep against the per-pair form."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from eval.protocol.metrics import (
    RankedAssignments,
    average_precision,
    candidate_thresholds,
    metrics_at_thresholds,
    pair_metrics,
    pooled_pr_curve,
    summarise_runs,
)


def test_empty_prediction_with_covisible_objects():
    m = pair_metrics(np.zeros((0, 2), int), [[0, 1], [2, 3]], n1=3, n2=4)
    assert (m.tp, m.n_pred, m.n_gt) == (0, 0, 2)
    assert m.precision == 0.0 and m.recall == 0.0 and m.f1 == 0.0
    # Right: view-1 object 1 and view-2 objects 0, 2 (non-covisible, unmatched) = 3 of 7.
    assert m.accuracy == pytest.approx(3 / 7)


def test_no_covisible_objects_and_no_prediction_is_perfect():
    m = pair_metrics([], [], n1=2, n2=5)
    assert m.precision == 1.0 and m.recall == 1.0 and m.f1 == 1.0 and m.accuracy == 1.0


def test_no_covisible_objects_but_a_prediction():
    m = pair_metrics([[0, 0]], [], n1=2, n2=3)
    assert m.precision == 0.0 and m.recall == 1.0 and m.f1 == 0.0
    assert m.accuracy == pytest.approx(3 / 5)


def test_empty_views():
    m = pair_metrics([], [], n1=0, n2=0)
    assert m.accuracy == 1.0 and m.precision == 1.0 and m.recall == 1.0


def test_unequal_view_sizes_mixed_errors():
    # n = 4, m = 3. One right, one swapped partner, one non-covisible object matched.
    gt = [[0, 0], [1, 1], [2, 2]]
    pred = [[0, 0], [1, 2], [3, 1]]
    m = pair_metrics(pred, gt, n1=4, n2=3)
    assert m.tp == 1
    assert m.precision == pytest.approx(1 / 3) and m.recall == pytest.approx(1 / 3)
    assert m.f1 == pytest.approx(1 / 3)
    # Only objects 0 (view 1) and 0 (view 2) are decided right.
    assert m.correct == 2 and m.accuracy == pytest.approx(2 / 7)


def test_perfect_partial_matching():
    gt = [[0, 2], [3, 0]]
    m = pair_metrics(gt, gt, n1=5, n2=3)
    assert (m.accuracy, m.precision, m.recall, m.f1) == (1.0, 1.0, 1.0, 1.0)


def test_accuracy_differs_from_recall_when_negatives_are_left_unmatched():
    # Two covisible, one found; three non-covisible objects correctly unmatched.
    m = pair_metrics([[0, 0]], [[0, 0], [1, 1]], n1=3, n2=4)
    assert m.recall == 0.5 and m.precision == 1.0
    assert m.accuracy == pytest.approx((2 + 1 + 2) / 7)


@pytest.mark.parametrize(("n1", "n2", "covisible"), [(3, 4, 2), (17, 17, 5), (30, 4, 1)])
def test_declaring_nothing_scores_half_balanced_accuracy_whatever_the_distractor_share(
    n1, n2, covisible
):
    gt = np.stack([np.arange(covisible), np.arange(covisible)], axis=1)
    m = pair_metrics([], gt, n1=n1, n2=n2)
    assert m.balanced_accuracy == 0.5
    # Plain accuracy instead awards the non-covisible share.
    assert m.accuracy == pytest.approx((n1 + n2 - 2 * covisible) / (n1 + n2))


def test_balanced_accuracy_by_hand():
    # Two covisible, one found (covisible share 2/4 objects); the 3 non-covisible objects unmatched.
    m = pair_metrics([[0, 0]], [[0, 0], [1, 1]], n1=3, n2=4)
    assert m.balanced_accuracy == pytest.approx(0.5 * (2 / 4 + 3 / 3))
    # One right, one swapped partner, non-covisible view-1 object 3 matched (0 of 1 left alone).
    m = pair_metrics([[0, 0], [1, 2], [3, 1]], [[0, 0], [1, 1], [2, 2]], n1=4, n2=3)
    assert m.balanced_accuracy == pytest.approx(0.5 * (2 / 6 + 0 / 1))
    # A perfect partial matching scores 1.
    assert pair_metrics([[0, 2], [3, 0]], [[0, 2], [3, 0]], n1=5, n2=3).balanced_accuracy == 1.0


def test_balanced_accuracy_without_non_covisible_objects_is_the_covisible_share():
    gt = [[0, 1], [1, 0], [2, 2]]
    m = pair_metrics([[0, 1], [1, 2], [2, 0]], gt, n1=3, n2=3)
    assert m.balanced_accuracy == pytest.approx(1 / 3) == pytest.approx(m.recall)
    assert pair_metrics([], gt, n1=3, n2=3).balanced_accuracy == 0.0
    # Without covisible objects it is the non-covisible share; empty views score 1.
    assert pair_metrics([[0, 0]], [], n1=2, n2=3).balanced_accuracy == pytest.approx(3 / 5)
    assert pair_metrics([], [], n1=0, n2=0).balanced_accuracy == 1.0


@pytest.mark.parametrize(
    ("pairs", "message"),
    [
        ([[0, 5]], "out of range"),
        ([[0, 0], [0, 1]], "one-to-one"),
        ([[0, 1, 2]], r"\(k, 2\)"),
        ([[0.5, 1]], "integers"),
    ],
)
def test_bad_pairs_are_rejected_with_the_array_named(pairs, message):
    with pytest.raises(ValueError, match=message) as err:
        pair_metrics(pairs, [], n1=3, n2=3)
    assert "predicted" in str(err.value)


def test_pooled_pr_curve_and_average_precision_by_hand():
    # One frame: scores 0.9 (right), 0.8 (wrong), 0.7 (right); four ground-truth pairs.
    ranked = RankedAssignments.from_frames(
        [([[0, 0], [1, 2], [2, 2 - 1]], [0.9, 0.8, 0.7], [[0, 0], [2, 1], [3, 3], [4, 4]], 5, 5)]
    )
    curve = pooled_pr_curve(ranked)
    np.testing.assert_allclose(curve.thresholds, [0.9, 0.8, 0.7])
    np.testing.assert_allclose(curve.precision, [1.0, 0.5, 2 / 3])
    np.testing.assert_allclose(curve.recall, [0.25, 0.25, 0.5])
    assert average_precision(curve) == pytest.approx(0.25 * 1.0 + 0.25 * 2 / 3)


def test_pr_curve_ties_enter_together():
    ranked = RankedAssignments.from_frames(
        [([[0, 0], [1, 1]], [0.5, 0.5], [[0, 0]], 2, 2), ([[0, 0]], [0.5], [[0, 0]], 1, 1)]
    )
    curve = pooled_pr_curve(ranked)
    np.testing.assert_allclose(curve.precision, [2 / 3])
    np.testing.assert_allclose(curve.recall, [1.0])


@st.composite
def frames(draw):
    out = []
    for _ in range(draw(st.integers(1, 4))):
        n1, n2 = draw(st.integers(0, 6)), draw(st.integers(0, 6))
        k = min(n1, n2)
        rows1 = draw(st.permutations(range(n1)))[:k] if n1 else []
        cols = draw(st.permutations(range(n2)))[:k] if n2 else []
        assigned = np.array(list(zip(rows1, cols, strict=True)), dtype=int).reshape(-1, 2)
        scores = draw(st.lists(st.sampled_from([0.0, 0.2, 0.5, 0.9]), min_size=k, max_size=k))
        g = draw(st.integers(0, k))
        gt_rows = draw(st.permutations(range(n1)))[:g] if n1 else []
        gt_cols = draw(st.permutations(range(n2)))[:g] if n2 else []
        gt = np.array(list(zip(gt_rows, gt_cols, strict=True)), dtype=int).reshape(-1, 2)
        out.append((assigned, np.array(scores, dtype=float), gt, n1, n2))
    return out


@settings(max_examples=60, deadline=None)
@given(frames())
def test_threshold_sweep_equals_per_pair_metrics_of_the_kept_pairs(frame_list):
    ranked = RankedAssignments.from_frames(frame_list)
    thresholds = candidate_thresholds(ranked)
    swept = metrics_at_thresholds(ranked, thresholds)
    for f, (assigned, scores, gt, n1, n2) in enumerate(frame_list):
        for t, tau in enumerate(thresholds):
            m = pair_metrics(assigned[scores >= tau], gt, n1, n2)
            for name in ("accuracy", "balanced_accuracy", "precision", "recall", "f1"):
                assert swept[name][f, t] == pytest.approx(getattr(m, name)), (name, f, tau)
            assert swept["tp"][f, t] == m.tp and swept["n_pred"][f, t] == m.n_pred


def test_candidate_thresholds_start_above_every_score():
    ranked = RankedAssignments.from_frames([([[0, 0]], [0.4], [[0, 0]], 1, 1)])
    t = candidate_thresholds(ranked)
    assert t[0] > 0.4 and t[-1] == 0.4
    swept = metrics_at_thresholds(ranked, t)
    assert swept["n_pred"][0].tolist() == [0, 1]


def test_summarise_runs_is_mean_over_pairs_then_mean_and_std_over_runs():
    rows = [
        # seed 0: pair means 0.5 ; seed 1: pair means 1.0
        {"matcher": "a", "seed": 0, "accuracy": 0.0, "precision": 0.0, "recall": 0.0, "f1": 0.0},
        {"matcher": "a", "seed": 0, "accuracy": 1.0, "precision": 1.0, "recall": 1.0, "f1": 1.0},
        {"matcher": "a", "seed": 1, "accuracy": 1.0, "precision": 1.0, "recall": 1.0, "f1": 1.0},
    ]
    out = summarise_runs(pd.DataFrame(rows), by=["matcher"])
    row = out.iloc[0]
    assert row["accuracy_mean"] == pytest.approx(0.75)
    assert row["accuracy_std"] == pytest.approx(np.std([0.5, 1.0], ddof=1))
    assert row["runs"] == 2
