"""The episode-bootstrap interval of a pooled ROC AUC (eval/protocol/auc_interval.py)."""

import math

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from cadsim.dataset.regime import roc_auc
from eval.protocol.auc_interval import episode_auc_interval

scores = st.lists(st.sampled_from([0.0, 0.25, 0.5, 0.75, 1.0]), min_size=1, max_size=6)


@settings(max_examples=50, deadline=None)
@given(st.lists(st.tuples(scores, scores), min_size=2, max_size=5))
def test_the_point_is_the_pooled_auc_and_lies_in_its_interval(episodes):
    positives = [np.array(p) for p, _ in episodes]
    negatives = [np.array(n) for _, n in episodes]
    auc, low, high = episode_auc_interval(positives, negatives, resamples=200)
    pooled = roc_auc(np.concatenate(positives), np.concatenate(negatives))  # ties count one half
    assert math.isclose(auc, pooled, abs_tol=1e-12)
    assert low - 1e-12 <= auc <= high + 1e-12


def test_episodes_that_disagree_widen_the_interval():
    rng = np.random.default_rng(3)
    alike = [rng.normal(1, 1, 30) for _ in range(12)], [rng.normal(0, 1, 60) for _ in range(12)]
    # half the episodes separate well, half not at all: the pooled AUC is uncertain
    mixed = (
        [rng.normal(3 if k % 2 else 0, 1, 30) for k in range(12)],
        [rng.normal(0, 1, 60) for _ in range(12)],
    )
    _, low_a, high_a = episode_auc_interval(*alike)
    _, low_m, high_m = episode_auc_interval(*mixed)
    assert high_m - low_m > 2 * (high_a - low_a)


def test_one_episode_has_no_interval_and_an_empty_class_no_auc():
    auc, low, high = episode_auc_interval([np.array([0.9])], [np.array([0.1])])
    assert auc == 1.0 and math.isnan(low) and math.isnan(high)
    assert all(math.isnan(x) for x in episode_auc_interval([np.zeros(0)], [np.array([0.1])]))
