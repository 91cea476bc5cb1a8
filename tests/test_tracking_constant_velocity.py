"""The own-agent constant-velocity tracker: moving objects keep one id, static ones are not split,
the gate stretches along the sensor's ray, true ids never enter."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from sequence_fakes import planted_sequence

from matchers import Problem
from matchers.core.sequence_problem import SequenceProblem
from matchers.tracking.constant_velocity import link
from matchers.tracking.own_tracks import track_views, tracked_sequence


def _scene(seed: int, frames: int = 10, noise: float = 0.15):
    """A car at 15 m/s crossing 4 parked objects 3 m from its path (one per frame: a detection
    list per frame, the car first), detections with N(0, noise²) m per axis, 0.2 s apart."""
    rng = np.random.default_rng(seed)
    parked = np.array([[5.0, 3.0], [12.0, -3.0], [20.0, 3.0], [26.0, -3.0]])
    out = []
    for t in range(frames):
        car = np.array([[-2.0 + 15.0 * 0.2 * t, 0.0]])
        xy = np.r_[car, parked] + rng.normal(0, noise, (1 + len(parked), 2))
        out.append(xy)
    return out


@settings(max_examples=25, deadline=None)
@given(st.integers(0, 10_000))
def test_a_car_at_15_m_s_keeps_one_id_and_no_parked_object_splits(seed):
    ids = link(_scene(seed), interval_s=0.2)
    per_object = np.array([i.tolist() for i in ids])  # (frames, objects): rows in one order
    assert all(len(set(per_object[:, k])) == 1 for k in range(per_object.shape[1]))
    assert len(set(per_object[0])) == per_object.shape[1]


def test_the_old_fixed_gate_would_lose_the_car():
    """The same scene with the gate no wider than the motion allows: at 3 m a frame the car is
    out of a 1.5 m round gate once its velocity is unknown (max_speed 0), so it splits."""
    ids = link(_scene(0), interval_s=0.2, max_speed=0.0)
    assert len({int(i[0]) for i in ids}) > 1


def test_a_missed_frame_is_bridged_and_a_long_gap_is_not():
    frames = _scene(1)
    gap = [f if t != 5 else f[1:] for t, f in enumerate(frames)]  # the car missed at frame 5
    ids = link(gap, interval_s=0.2)
    assert ids[4][0] == ids[6][0] == ids[0][0]
    long_gap = [f if t not in (4, 5, 6) else f[1:] for t, f in enumerate(frames)]
    ids = link(long_gap, interval_s=0.2, max_age=2)
    assert ids[7][0] != ids[3][0]  # unseen for 3 frames > max_age: a new track


def test_a_tentative_track_is_deleted_after_one_miss():
    here, none = np.array([[0.0, 0.0]]), np.zeros((0, 2))
    assert [i.tolist() for i in link([here, none, here], max_speed=0.0)] == [[0], [], [1]]
    confirmed = [here, here, none, here]
    assert [i.tolist() for i in link(confirmed, max_speed=0.0)] == [[0], [0], [], [0]]


def test_the_gate_stretches_along_the_ray_not_across_it():
    """A parked object 60 m ahead whose depth jumps by 4 m between frames (a camera's depth error
    at 60 m) stays one track; the same jump across the ray is another object."""
    origins = np.zeros((2, 2))
    along = [np.array([[60.0, 0.0]]), np.array([[64.0, 0.0]])]
    across = [np.array([[60.0, 0.0]]), np.array([[60.0, 4.0]])]
    opts = {"max_speed": 0.0, "range_gate": 0.002, "origins": origins}
    assert [i.tolist() for i in link(along, **opts)] == [[0], [0]]
    assert [i.tolist() for i in link(across, **opts)] == [[0], [1]]
    assert [i.tolist() for i in link(along, max_speed=0.0, range_gate=0.0)] == [[0], [1]]


def test_confirmed_tracks_choose_before_tentative_ones():
    """A new detection beside a confirmed track's prediction cannot steal its detection."""
    frames = [np.array([[0.0, 0.0]]), np.array([[0.0, 0.0]]), np.array([[0.5, 0.0], [1.0, 0.0]])]
    ids = link(frames)
    assert ids[2][0] == 0


def test_planted_sequences_are_tracked_and_true_ids_never_enter():
    for camera in (False, True):
        planted = planted_sequence(seed=2, frames=10, clutter=0, camera=camera)
        tracks1, tracks2 = track_views(planted.seq)
        for own, true in ((tracks1, planted.true1), (tracks2, planted.true2)):
            a, b = np.concatenate(own), np.concatenate(true)
            assert len(set(zip(a, b, strict=True))) == len(set(a)) == len(set(b))
    seq = planted.seq
    rng = np.random.default_rng(0)
    scrambled = SequenceProblem(
        seq.frames,
        [rng.permutation(10_000)[: len(t)] for t in seq.tracks1],
        [rng.permutation(10_000)[: len(t)] for t in seq.tracks2],
        seq.odometry1,
        seq.odometry2,
        seq.mount1,
        seq.mount2,
        dict(seq.meta),
    )
    first, second = track_views(seq), track_views(scrambled)
    assert all(
        np.array_equal(x, y)
        for x, y in zip(first[0] + first[1], second[0] + second[1], strict=True)
    )


def test_degenerate_input():
    assert link([]) == []
    assert [i.tolist() for i in link([np.zeros((0, 2)), np.zeros((0, 2))])] == [[], []]
    empty = Problem(np.zeros((0, 2)), np.zeros((0, 2)))
    seq = tracked_sequence([empty], np.zeros((1, 3)), np.zeros((1, 3)))
    assert seq.tracks1[0].shape == (0,)
    try:
        link([np.zeros((1, 2))], origins=np.zeros((2, 2)))
    except ValueError as err:
        assert "origins" in str(err)
    else:
        raise AssertionError("origins of the wrong length accepted")
