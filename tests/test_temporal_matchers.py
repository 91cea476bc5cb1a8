"""Temporal matchers (issue 41): ``windowed:<name>`` (W = 1 is the base matcher exactly) and
``temporal_pose`` (recovers a planted sequence's pose and association)."""

from __future__ import annotations

import numpy as np
import pytest
from sequence_fakes import as_xyyaw, planted_sequence, true_pairs

from matchers import Problem, available, get
from matchers.core.sequence_problem import SequenceProblem
from matchers.core.temporal_registry import get_temporal, register_temporal, temporal_available


def test_registry_family_and_builtin():
    assert temporal_available() == ["temporal_pose", "trajectory_pose"]
    assert "temporal_pose" not in available()  # two-view harnesses never see them
    assert get_temporal("windowed:pose").requires == get("pose").requires
    with pytest.raises(ValueError, match="nosuch"):
        get_temporal("windowed:nosuch")
    with pytest.raises(ValueError, match="family"):
        register_temporal("windowed:x", lambda seq: [])


@pytest.mark.parametrize("base", ["pose", "sm", "pose_refine"])
def test_window_one_is_the_base_matcher(base):
    seq = planted_sequence(seed=4, frames=3).seq
    lifted = get_temporal(f"windowed:{base}")(seq, threshold=0.2, window=1)
    for frame, got in zip(seq.frames, lifted, strict=True):
        want = get(base)(frame, threshold=0.2)
        assert np.array_equal(got.pairs, want.pairs) and np.array_equal(got.scores, want.scores)


@pytest.mark.parametrize("base", ["pose", "consistency"])
def test_over_windows_equals_one_call_per_window(base):
    seq = planted_sequence(seed=5, frames=6).seq
    lifted = get_temporal(f"windowed:{base}")
    many = lifted.over_windows(seq, [1, 3, 10], threshold=0.2, reduce="sum")
    assert sorted(many) == [1, 3, 10]
    for window, matchings in many.items():
        one = lifted(seq, threshold=0.2, window=window, reduce="sum")
        for got, want in zip(matchings, one, strict=True):
            assert np.array_equal(got.pairs, want.pairs)
            assert np.array_equal(got.scores, want.scores)
    with pytest.raises(ValueError, match="window"):
        lifted.over_windows(seq, [0])


def test_window_accumulates_along_tracks():
    """Two frames, two tracks per view: frame 1 alone is ambiguous, frame 0 decides it."""
    xy = np.array([[0.0, 0.0], [10.0, 0.0]])
    f0 = Problem(xy, xy, world1=np.c_[xy, [0, 0]], world2=np.c_[xy, [0, 0]], world_sigma=1.0)
    tie = np.c_[np.array([[5.0, 0.0], [5.0, 0.0]]), [0, 0]]
    f1 = Problem(xy, xy[::-1], world1=tie, world2=tie, world_sigma=1.0)
    seq = SequenceProblem(
        [f0, f1], [[1, 2], [1, 2]], [[7, 8], [8, 7]], np.zeros((2, 3)), np.zeros((2, 3))
    )
    out = get_temporal("windowed:pose")(seq, window=2)
    assert out[1].pairs.tolist() == [[0, 1], [1, 0]]  # track 1 <-> 7, 2 <-> 8 carried over
    assert np.allclose(out[1].scores, [[0.5, 1.0], [1.0, 0.5]])
    summed = get_temporal("windowed:pose")(seq, window=2, reduce="sum")
    assert np.allclose(summed[1].scores, [[0.5, 1.0], [1.0, 0.5]])


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_temporal_pose_recovers_a_planted_sequence(seed):
    planted = planted_sequence(seed=seed, camera=seed % 2 == 1)
    out = get_temporal("temporal_pose")(planted.seq, threshold=0.3)
    truth = as_xyyaw(planted.relative)
    last = out[-1].info
    assert np.linalg.norm(np.array(last["shift_m"]) - truth[:2]) < 0.3
    assert abs(np.radians(last["yaw_deg"]) - truth[2]) < np.radians(0.5)
    found = wanted = wrong = 0
    for matching, a, b in zip(out, planted.true1, planted.true2, strict=True):
        got, want = set(map(tuple, matching.pairs.tolist())), true_pairs(a, b)
        found, wanted, wrong = found + len(got & want), wanted + len(want), wrong + len(got - want)
    assert found == wanted  # every covisible pair, despite clutter and non-covisible tracks
    assert wrong <= 0.05 * found  # only clutter that happens to land on an object


def test_temporal_pose_beats_the_raw_prior():
    correct = {"temporal_pose": 0, "windowed:pose": 0}
    for seed in range(3):
        planted = planted_sequence(seed=seed)
        for name in correct:
            for m, a, b in zip(
                get_temporal(name)(planted.seq, threshold=0.3),
                planted.true1,
                planted.true2,
                strict=True,
            ):
                correct[name] += len(set(map(tuple, m.pairs.tolist())) & true_pairs(a, b))
    assert correct["temporal_pose"] > correct["windowed:pose"]


@pytest.mark.parametrize(
    "name", ["temporal_pose", "trajectory_pose", "windowed:sm", "windowed:pose"]
)
def test_degenerate_sequences(name):
    fn = get_temporal(name)
    assert fn(SequenceProblem([], [], [], np.zeros((0, 3)), np.zeros((0, 3)))) == []
    empty = Problem(
        np.zeros((0, 3)),
        np.zeros((0, 3)),
        world1=np.zeros((0, 3)),
        world2=np.zeros((0, 3)),
        world_sigma=1.0,
    )
    one = Problem(
        np.zeros((1, 3)),
        np.ones((1, 3)),
        world1=np.zeros((1, 3)),
        world2=np.ones((1, 3)),
        world_sigma=1.0,
    )
    seq = SequenceProblem(
        [empty, one, empty], [[], [3], []], [[], [4], []], np.zeros((3, 3)), np.zeros((3, 3))
    )
    out = fn(seq, threshold=0.1)
    assert [m.scores.shape for m in out] == [(0, 0), (1, 1), (0, 0)]
    assert all(np.all((m.scores >= 0) & (m.scores <= 1)) for m in out)


def test_temporal_pose_needs_the_prior():
    frame = Problem(np.zeros((2, 2)), np.ones((2, 2)))
    seq = SequenceProblem([frame], [[0, 1]], [[0, 1]], np.zeros((1, 3)), np.zeros((1, 3)))
    with pytest.raises(ValueError, match="world1"):
        get_temporal("temporal_pose")(seq)
    with pytest.raises(TypeError, match="SequenceProblem"):
        get_temporal("temporal_pose")(frame)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_temporal_pose_estimates_a_planted_time_offset(seed):
    """Agent 2's detections 0.3 s old, objects moving: the estimate finds the offset (within two
    grid steps), and matching with it beats matching as if the latency were 0."""
    from eval.protocol.temporal_metrics import time_offset_error

    planted = planted_sequence(seed=seed, frames=8, latency=0.3, moving=0.6, speed_sigma=6.0)
    run = get_temporal("temporal_pose")
    found = run(planted.seq, threshold=0.3, window=8, max_offset_s=0.6)
    estimates = [m.info.get("time_offset_s") for m in found[2:]]  # from three frames on
    assert time_offset_error(estimates, 0.3)["mean_abs_s"] <= 0.1
    assert found[0].info["time_offset_s"] == 0.0  # one frame: no velocity, the smaller offset

    def correct(out):
        return sum(
            len(set(map(tuple, m.pairs.tolist())) & true_pairs(a, b))
            for m, a, b in zip(out, planted.true1, planted.true2, strict=True)
        )

    assert correct(found) >= correct(run(planted.seq, threshold=0.3, window=8))
    # no latency: no offset found; and the default (no estimate) has no such field
    still = planted_sequence(seed=seed, frames=8, moving=0.6, speed_sigma=6.0)
    estimates = [m.info["time_offset_s"] for m in run(still.seq, window=8, max_offset_s=0.6)]
    assert time_offset_error(estimates, 0.0)["mean_abs_s"] <= 0.05
    assert "time_offset_s" not in run(still.seq, window=8)[-1].info
    with pytest.raises(ValueError, match="interval_s"):
        run(SequenceProblem(still.seq.frames, still.seq.tracks1, still.seq.tracks2,
                            still.seq.odometry1, still.seq.odometry2), max_offset_s=0.5)  # fmt: skip
