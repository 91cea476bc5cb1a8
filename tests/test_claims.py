"""The claim record (eval/protocol/claims.py): verdicts, a choice on test only as a labelled
point value, and goals emitted as claims from their declaration (eval/engine/goal.py): bar,
direction and chosen-on from the Goal, never from its text."""

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from eval.engine.goal import Goal
from eval.protocol.claims import (
    AHEAD,
    BEHIND,
    NOT_SHOWN,
    Claim,
    difference_claim,
    difference_verdict,
    point_claim,
)
from eval.protocol.goal_verdict import verdict


def test_a_difference_is_ahead_or_behind_only_when_its_interval_excludes_zero():
    assert difference_verdict(0.01, 0.05) == AHEAD
    assert difference_verdict(-0.05, -0.01) == BEHIND
    assert difference_verdict(-0.01, 0.05) == NOT_SHOWN
    assert difference_verdict(float("nan"), 0.05) == NOT_SHOWN


def test_a_claim_chosen_on_test_is_a_point_value_never_a_verdict():
    with pytest.raises(ValueError, match="chosen on test, so a point value"):
        difference_claim("s", "a", "b", "f1", 0.1, 0.0, 0.2, statement="x", chosen_on="test",
                         clusters="", source="t.csv")  # fmt: skip
    claim = point_claim("s", "a", "b", "f1", 0.5, statement="x", chosen_on="test", source="t")
    assert claim.verdict == "point value" and math.isnan(claim.ci_low)
    with pytest.raises(ValueError, match="chosen_on 'train'"):
        point_claim("s", "a", "b", "f1", 0.5, statement="x", chosen_on="train", source="t")
    with pytest.raises(ValueError, match="verdict"):
        Claim(*["s"] * 4, 0.0, 0.0, 0.0, 0.0, "diff", "better", "fixed", "", "", "x")


finite = st.floats(-1, 1, allow_nan=False).map(lambda x: round(x, 3))


@given(finite, finite, finite, finite, st.booleans())
def test_a_goal_claim_carries_its_declared_numbers_and_prints_its_line(value, a, b, bar, at_least):
    low, high = min(a, b), max(a, b)
    goal = Goal("gnss-urban", "`gnss-urban` F1 ≥ 90", ("v", "lo", "hi"), bar, at_least)
    claim = goal.claim_of(value, low, high, "`pose_refine`, chosen on validation",
                          study="v2x", subject="pose_refine", source="t.csv")  # fmt: skip
    assert claim.verdict == verdict(low, high, bar, at_least)
    assert claim.bar == pytest.approx(100 * bar) and claim.direction == (">=" if at_least else "<=")
    assert (claim.value, claim.ci_low, claim.ci_high) == pytest.approx(
        (100 * value, 100 * low, 100 * high), abs=0.051
    )
    assert claim.statement == goal.line_of(value, low, high, "`pose_refine`, chosen on validation")
    assert claim.chosen_on == "validation" and claim.clusters == "simulation episodes"


def test_a_goal_text_with_two_numbers_keeps_its_declared_bar():
    """The bar is the Goal's, not a number read from its text: the last "≥ n" of this text
    is the speed (10 m/s), the first the bar (90 %)."""
    goal = Goal(
        "gnss-urban",
        "own tracker: ≥ 90 % of consecutive detections on one track for objects moving ≥ 10 m/s",
        ("continuity", "continuity_low", "continuity_high"),
        0.90,
        chosen_on="fixed",
    )
    claim = goal.claim_of(0.894, 0.833, 0.956, study="temporal", subject="t", source="t.csv")
    assert claim.bar == 90.0 and claim.direction == ">=" and claim.chosen_on == "fixed"
    assert claim.verdict == NOT_SHOWN and claim.value == 89.4
    two = Goal("N ≥ 4", "gain ≥ 5 points at N ≥ 4", ("g", "lo", "hi"), 0.05, unit=" points")
    assert two.claim_of(0.027, 0.003, 0.053, study="m", subject="s", source="t").bar == 5.0


def test_a_goal_without_an_interval_is_not_shown():
    goal = Goal("", "image-only AUC ≤ 0.75", ("a", "b", "c"), 0.75, False, "fixed", 1.0, 3)
    claim = goal.claim_of(0.745, np.nan, np.nan, study="v2x", subject="s", source="t")
    assert claim.verdict == NOT_SHOWN and claim.value == 0.745 and claim.bar == 0.75
    assert math.isnan(claim.ci_low) and claim.clusters == ""
    assert "(no interval)" in claim.statement
