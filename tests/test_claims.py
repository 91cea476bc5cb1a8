"""The claim record (eval/protocol/claims.py): verdicts, the refusal of a choice on test, and
goal lines read back into their numbers."""

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from eval.protocol.claims import (
    AHEAD,
    BEHIND,
    NOT_SHOWN,
    Claim,
    difference_claim,
    difference_verdict,
    parse_goal_line,
    point_claim,
)
from eval.protocol.goal_verdict import goal_line, verdict


def test_a_difference_is_ahead_or_behind_only_when_its_interval_excludes_zero():
    assert difference_verdict(0.01, 0.05) == AHEAD
    assert difference_verdict(-0.05, -0.01) == BEHIND
    assert difference_verdict(-0.01, 0.05) == NOT_SHOWN
    assert difference_verdict(float("nan"), 0.05) == NOT_SHOWN


def test_no_claim_is_chosen_on_test():
    with pytest.raises(ValueError, match="chosen_on 'test'"):
        difference_claim("s", "a", "b", "f1", 0.1, 0.0, 0.2, statement="x", chosen_on="test",
                         clusters="", source="t.csv")  # fmt: skip
    claim = point_claim("s", "a", "b", "f1", 0.5, statement="x", chosen_on="fixed", source="t")
    assert claim.verdict == "point value" and math.isnan(claim.ci_low)
    with pytest.raises(ValueError, match="verdict"):
        Claim(*["s"] * 4, 0.0, 0.0, 0.0, 0.0, "diff", "better", "fixed", "", "", "x")


finite = st.floats(-100, 100, allow_nan=False).map(lambda x: round(x, 1))


@given(finite, finite, finite, finite, st.booleans())
def test_a_goal_line_reads_back_as_its_numbers_and_verdict(value, a, b, bar, at_least):
    low, high = min(a, b), max(a, b)
    line = goal_line("`gnss-urban` F1 ≥ 90", value, low, high, bar, at_least, scale=1.0,
                     detail="`pose_refine`, chosen on validation")  # fmt: skip
    parsed = parse_goal_line(f"- {line}.")
    assert parsed["verdict"] == verdict(low, high, bar, at_least)
    assert (parsed["value"], parsed["low"], parsed["high"]) == pytest.approx((value, low, high))
    assert parsed["goal"] == "`gnss-urban` F1 ≥ 90" and "chosen on validation" in parsed["detail"]


def test_a_goal_line_without_an_interval_is_not_shown():
    parsed = parse_goal_line(goal_line("image-only AUC ≤ 0.75", 0.745, np.nan, np.nan, 0.75,
                                       at_least=False, scale=1.0, digits=3))  # fmt: skip
    assert parsed["verdict"] == NOT_SHOWN and parsed["value"] == 0.745
    assert math.isnan(parsed["low"]) and parse_goal_line("no verdict here") is None
