"""Each agent's own tracker (issue 41): true ids never enter; a planted sequence is tracked."""

from __future__ import annotations

import numpy as np
from sequence_fakes import planted_sequence

from matchers import Problem
from matchers.core.sequence_problem import SequenceProblem
from matchers.tracking.hungarian import link, track_views, with_own_tracks


def _same_partition(ids_a, ids_b) -> bool:
    """Two trackings agree up to renaming the tracks."""
    a, b = np.concatenate(ids_a), np.concatenate(ids_b)
    return len(set(zip(a, b, strict=True))) == len(set(a)) == len(set(b))


def test_scrambled_true_ids_give_the_same_tracks():
    planted = planted_sequence(seed=1, frames=8, clutter=0)
    seq = planted.seq
    rng = np.random.default_rng(0)
    scrambled = SequenceProblem(
        seq.frames,
        [rng.permutation(10_000)[: len(t)] for t in seq.tracks1],
        [rng.permutation(10_000)[: len(t)] for t in seq.tracks2],
        seq.odometry1,
        seq.odometry2,
    )
    first, second = track_views(seq), track_views(scrambled)
    assert all(
        np.array_equal(a, b)
        for a, b in zip(first[0] + first[1], second[0] + second[1], strict=True)
    )


def test_planted_sequence_is_tracked():
    for camera in (False, True):
        planted = planted_sequence(seed=2, frames=10, clutter=0, camera=camera)
        tracks1, tracks2 = track_views(planted.seq)
        assert _same_partition(tracks1, planted.true1)
        assert _same_partition(tracks2, planted.true2)


def test_gap_and_new_tracks_and_degenerate():
    frames = [np.array([[0.0, 0.0]]), np.zeros((0, 2)), np.array([[0.1, 0.0], [9.0, 9.0]])]
    assert [ids.tolist() for ids in link(frames)] == [[0], [], [0, 1]]
    assert [ids.tolist() for ids in link(frames, max_age=1)] == [[0], [], [1, 2]]
    assert link([]) == []
    empty = Problem(np.zeros((0, 2)), np.zeros((0, 2)))
    seq = SequenceProblem([empty], [[]], [[]], np.zeros((1, 3)), np.zeros((1, 3)))
    assert with_own_tracks(seq).tracks1[0].shape == (0,)


def test_an_exact_tie_goes_the_same_way_whatever_the_last_bits():
    """A track at the origin, then two detections equally far from it: which one continues the
    track must not depend on a one-ulp difference in a position (another CPU's arithmetic)."""
    first = np.array([[0.0, 0.0]])
    tied = np.array([[1.0, 0.0], [-1.0, 0.0]])
    want = [ids.tolist() for ids in link([first, tied])]
    for row in (0, 1):  # either detection one ulp closer
        other = tied.copy()
        other[row, 0] = np.nextafter(other[row, 0], 0.0)
        assert [ids.tolist() for ids in link([first, other])] == want, row
