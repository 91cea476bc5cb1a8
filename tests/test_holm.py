"""Holm's step-down adjustment (eval.protocol.holm) against hand-computed adjusted p-values."""

from __future__ import annotations

import numpy as np
import pytest

from eval.protocol.holm import holm


@pytest.mark.parametrize(
    "p,adjusted",
    [
        # sorted 0.005, 0.01, 0.03, 0.04 times 4, 3, 2, 1: 0.02, 0.03, 0.06, 0.04 -> max so far
        ([0.01, 0.04, 0.03, 0.005], [0.03, 0.06, 0.06, 0.02]),
        # 0.01 x 3 = 0.03, 0.2 x 2 = 0.4, 0.5 x 1 = 0.5
        ([0.5, 0.2, 0.01], [0.5, 0.4, 0.03]),
        # the step-down maximum: 0.04, then 0.033 and 0.024 are lifted to 0.04
        ([0.01, 0.011, 0.012, 0.5], [0.04, 0.04, 0.04, 0.5]),
        # capped at 1
        ([0.3, 0.6], [0.6, 0.6]),
        ([0.4, 0.9, 0.45], [1.0, 1.0, 1.0]),
        # ties: 0.02 x 3 = 0.06, 0.02 x 2 = 0.04 -> 0.06, 0.02 x 1 -> 0.06
        ([0.02, 0.02, 0.02], [0.06, 0.06, 0.06]),
        ([0.7], [0.7]),
        ([], []),
    ],
)
def test_holm_matches_hand_computed_values(p, adjusted):
    np.testing.assert_allclose(holm(p), adjusted, rtol=0, atol=1e-12)


def test_missing_comparisons_stay_out_of_the_family():
    # a family of two: 0.01 x 2 = 0.02, then 0.02 x 1 -> max 0.02
    np.testing.assert_allclose(holm([np.nan, 0.02, 0.01]), [np.nan, 0.02, 0.02])


def test_holm_is_never_below_the_raw_p_nor_above_bonferroni():
    p = np.random.default_rng(0).uniform(0, 0.2, 40)
    adjusted = holm(p)
    assert (adjusted >= p).all() and (adjusted <= np.minimum(1, 40 * p) + 1e-15).all()
    np.testing.assert_array_equal(holm(p.reshape(5, 8)), adjusted.reshape(5, 8))


def test_p_values_outside_the_unit_interval_are_refused():
    with pytest.raises(ValueError, match=r"\[0, 1\]"):
        holm([0.2, 1.5])


def test_repeated_comparisons_count_once_in_the_family():
    from eval.protocol.holm import holm_distinct

    p = [0.01, 0.02, 0.01, 0.04]  # the first comparison repeated (e.g. a no-prior matcher)
    keys = ["a", "b", "a", "c"]
    adjusted = holm_distinct(p, keys)
    assert adjusted == pytest.approx([0.03, 0.04, 0.03, 0.04])  # m = 3, not 4
    assert list(holm_distinct(p, range(4))) == pytest.approx(list(holm(p)))
    with pytest.raises(ValueError, match="keys"):
        holm_distinct(p, ["a"])
