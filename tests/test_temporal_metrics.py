"""Temporal metrics (issue 41) on hand-made sequences against hand-computed values."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from eval.protocol.temporal_metrics import (
    combine_sequences,
    correspondence_hota,
    cross_agent_idsw,
    frames_to_first_correct,
    hota,
    hota_arrays,
    partner_changes,
)

A = np.array


def test_hota_of_an_identity_swap():
    # A-x, B-y at t=0; A-y, B-x at t=1: every pair 1/3 alignment, DetA 1, AssA 1/3
    out = hota([["A", "B"], ["A", "B"]], [["x", "y"], ["x", "y"]], [np.eye(2), np.eye(2)[::-1]])
    assert out["DetA"] == pytest.approx(1.0) and out["AssA"] == pytest.approx(1 / 3)
    assert out["HOTA"] == pytest.approx(np.sqrt(1 / 3)) and out["LocA"] == pytest.approx(1.0)


def test_hota_with_misses_and_false_positives():
    # TP 2, FN 1 (t=2), FP 1 (y at t=1): DetA 2/4; A-x matched twice, |A| 3, |x| 2: AssA 2/3
    out = hota(
        [["A"], ["A"], ["A"]],
        [["x"], ["x", "y"], []],
        [A([[1.0]]), A([[1.0, 0.0]]), np.zeros((1, 0))],
    )
    assert out["DetA"] == pytest.approx(0.5) and out["AssA"] == pytest.approx(2 / 3)
    assert out["HOTA"] == pytest.approx(np.sqrt(1 / 3))


def test_hota_degenerate():
    assert hota([[], []], [[], []], [np.zeros((0, 0))] * 2)["HOTA"] == 0.0
    assert hota([["A"]], [[]], [np.zeros((1, 0))])["DetA"] == 0.0


def _swap_sequence():
    true1 = [A([1, 2]), A([1, 2]), A([1, 2])]
    true2 = [A([1, 2]), A([2, 1]), A([1, -1])]  # frame 2: object 2 left view 2, a clutter box
    pairs = [A([[0, 0], [1, 1]]), A([[0, 0], [1, 1]]), A([[0, 0], [1, 1]])]
    return pairs, true1, true2


def test_switches_and_first_correct():
    pairs, true1, true2 = _swap_sequence()
    # t=0 -> 1: both swapped, both partners still visible (2 switches). t=1 -> 2: object 1
    # goes back to 1, but its t=1 partner 2 left view 2 (not counted); object 2 goes from 1 to
    # clutter while 1 is still visible (1 switch). Covisible object-frames 2 + 2 + 1.
    out = partner_changes(pairs, true1, true2)
    assert out == {"switches": 3, "object_frames": 5, "per_100": 60.0}
    first = frames_to_first_correct(pairs, true1, true2)
    assert first["per_object"] == {1: 0, 2: 0} and first["never"] == 0
    late = [A([[0, 1], [1, 0]]), *pairs[1:]]
    first = frames_to_first_correct(late, true1, [A([1, 2]), A([1, 2]), A([1, 2])])
    assert first["per_object"] == {1: 1, 2: 1} and first["mean"] == 1.0


def test_correspondence_hota_keeps_own_track_identity():
    pairs, true1, true2 = _swap_sequence()
    tracks = [A([10, 11])] * 3
    out = correspondence_hota(pairs, true1, true2, tracks, [A([20, 21])] * 3)
    # true pairs: 2 + 2 + 1 = 5; declared 6, right 3 (t=0 both, t=2 object 1): DetA 3/8
    assert out["DetA"] == pytest.approx(3 / 8)


def test_time_offset_error_against_hand_computed_values():
    from eval.protocol.temporal_metrics import time_offset_error

    out = time_offset_error([0.1, None, 0.15, 0.0], 0.1)
    assert out["frames"] == 3
    assert out["mean_abs_s"] == pytest.approx((0 + 0.05 + 0.1) / 3)
    assert out["median_abs_s"] == pytest.approx(0.05) and out["max_abs_s"] == pytest.approx(0.1)
    empty = time_offset_error([None, None], 0.1)
    assert empty["frames"] == 0 and np.isnan(empty["mean_abs_s"])


def _set_arrays(seqs):
    """hota_arrays of each sequence of a fixture set (ids as given, similarity per frame)."""
    return [
        hota_arrays(
            [f["gt"] for f in frames],
            [f["tr"] for f in frames],
            [np.array(f["sim"], dtype=float).reshape(len(f["gt"]), len(f["tr"])) for f in frames],
        )
        for frames in seqs
    ]


def test_combined_hota_equals_trackeval():
    """Random sequence sets: HOTA, DetA, AssA and LocA combined over sequences equal what
    trackeval 1.3.0's HOTA.combine_sequences gave for them (computed once, stored)."""
    fixture = json.loads(
        (Path(__file__).parent / "data" / "hota_combined_trackeval.json").read_text()
    )
    for seqs, want in zip(fixture["sets"], fixture["trackeval_1_3_0"], strict=True):
        got = combine_sequences(_set_arrays(seqs))
        for key in ("HOTA", "DetA", "AssA", "LocA"):
            assert abs(got[key] - want[key]) <= 1e-12, (key, got[key], want[key])


def test_combined_is_not_the_mean_of_sequences():
    """Two sequences of unequal size: the combined AssA weighs each by its true positives, which
    the mean of per-sequence values does not."""
    big = hota_arrays([["A"]] * 4, [["x"]] * 2 + [["y"]] * 2, [np.ones((1, 1))] * 4)
    small = hota_arrays([["B"]], [["z"]], [np.ones((1, 1))])
    combined = combine_sequences([big, small])
    assert combined["AssA"] == pytest.approx((4 * 0.5 + 1 * 1.0) / 5)
    assert combined["DetA"] == 1.0
    mean = (hota([["A"]] * 4, [["x"]] * 2 + [["y"]] * 2, [np.ones((1, 1))] * 4)["AssA"] + 1.0) / 2
    assert combined["AssA"] != pytest.approx(mean)


def test_cross_agent_idsw_of_a_planted_sequence_equals_its_hand_count():
    """Objects 0 and 1 seen by both agents over 5 frames. Object 0: right at t 0 (tracks (5, 8)),
    wrong partner at t 1, right again at t 2 with the same tracks (no IDSW: the last match had
    them), missed at t 3, right at t 4 with view 1's track renamed (1 IDSW). Object 1: right at
    t 0 and t 1 (tracks (6, 9)), then at t 2 with view 2's new track 10 (1 IDSW), at t 3 back to
    9 (1 IDSW). Hand count: 3 IDSW over 10 covisible object-frames. Partner changes: object 0
    t 0 -> 1 (to a wrong partner) and t 1 -> 2 (back) = 2, object 1 none (true partners)."""
    ids = np.array([0, 1])
    true = [ids] * 5
    pairs = [[[0, 0], [1, 1]], [[0, 1]], [[0, 0], [1, 1]], [[1, 1]], [[0, 0], [1, 1]]]
    tracks1 = [np.array([5, 6])] * 4 + [np.array([7, 6])]
    tracks2 = [np.array([8, 9])] * 2 + [np.array([8, 10])] + [np.array([8, 9])] * 2
    pairs = [np.array(p) for p in pairs]
    out = cross_agent_idsw(pairs, true, true, tracks1, tracks2)
    assert out["object_frames"] == 10
    assert out["idsw"] == 3
    assert out["per_100"] == pytest.approx(30.0)
    assert partner_changes(pairs, true, true)["switches"] == 2
