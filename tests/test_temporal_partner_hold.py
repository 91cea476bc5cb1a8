"""The partner hysteresis of the temporal matchers (issue 61, matchers.temporal.partner_hold): a
track pair keeps its partner through a one-frame distractor that switches it at margin 0, and
margin 0 is the output from before the hysteresis, bit for bit."""

from __future__ import annotations

import hashlib

import numpy as np
import pytest
from sequence_fakes import planted_sequence

from matchers import Problem
from matchers.core.search_spaces import TEMPORAL_SEARCH_SPACES
from matchers.core.sequence_problem import SequenceProblem
from matchers.core.temporal_registry import get_temporal, temporal_search_space
from matchers.temporal.partner_hold import NO_LINKS, held_mask, hold_partners, update_links

XY = np.array([[0.0, 0.0], [10.0, 0.0]])


def _frame(world1: np.ndarray, world2: np.ndarray) -> Problem:
    return Problem(
        XY, XY, world1=np.c_[world1, [0, 0]], world2=np.c_[world2, [0, 0]], world_sigma=1.0
    )


def _distracted_sequence() -> SequenceProblem:
    """Six frames, two tracks per view (1 <-> 7, 2 <-> 8 all along): frame 2 tells nothing (every
    pair scores 1), and in frame 3 alone the GNSS positions make the crossed pairing score ~0.002
    higher than the true one — enough to switch a window of 2 frames (2, 3) at margin 0."""
    clear = _frame(XY, XY)
    tie = _frame(np.full((2, 2), 5.0) * [1, 0], np.full((2, 2), 5.0) * [1, 0])
    distractor = _frame(np.array([[4.8, 0.0], [5.2, 0.0]]), np.array([[5.1, 0.0], [4.9, 0.0]]))
    frames = [clear, clear, tie, distractor, clear, clear]
    return SequenceProblem(frames, [[1, 2]] * 6, [[7, 8]] * 6, np.zeros((6, 3)), np.zeros((6, 3)))


def test_a_one_frame_distractor_switches_at_margin_zero_not_with_a_margin():
    seq = _distracted_sequence()
    lifted = get_temporal("windowed:pose")
    plain = lifted(seq, window=2, threshold=0.5)
    assert plain[3].pairs.tolist() == [[0, 1], [1, 0]]  # switched by the distractor
    assert plain[4].pairs.tolist() == [[0, 0], [1, 1]]  # and back
    held = lifted(seq, window=2, threshold=0.5, margin=0.1)
    assert [m.pairs.tolist() for m in held] == [[[0, 0], [1, 1]]] * 6  # partners kept
    assert held[3].info["held_links"] == 2
    assert np.array_equal(held[3].scores, plain[3].scores)  # scores are the evidence, unchanged
    # a margin below the distractor's lead does not hold it
    assert lifted(seq, window=2, threshold=0.5, margin=0.001)[3].pairs.tolist() == [[0, 1], [1, 0]]
    # W = 1 is one frame's evidence: no memory, the base matcher whatever the margin
    assert lifted(seq, window=1, threshold=0.5, margin=0.1)[3].pairs.tolist() == [[0, 1], [1, 0]]


def test_a_clear_change_beyond_the_margin_still_switches():
    """Scores (2 x 2) per frame: the true pairing for two frames, then the crossed one clearly
    better for good (0.9 against 0.2): a margin of 0.3 lets it switch at once."""
    ids1, ids2 = np.array([1, 2]), np.array([7, 8])
    straight, crossed = np.array([[0.9, 0.2], [0.2, 0.9]]), np.array([[0.2, 0.9], [0.9, 0.2]])
    held, got = NO_LINKS, []
    for scores in (straight, straight, crossed, crossed):
        done, held = hold_partners("x", scores, None, 0.0, ids1, ids2, held, 0.3)
        got.append(done.pairs.tolist())
    assert got == [[[0, 0], [1, 1]]] * 2 + [[[0, 1], [1, 0]]] * 2
    assert sorted(map(tuple, held.tolist())) == [(1, 8), (2, 7)]


def test_held_links_survive_an_unseen_track_and_are_forgotten_when_taken():
    held = np.array([[1, 7], [2, 8]])
    # track 2 unseen this frame: its link stays; track 1 took partner 9: (1, 7) goes
    after = update_links(held, np.array([1, 3]), np.array([7, 9]), np.array([[1, 9]]))
    assert sorted(map(tuple, after.tolist())) == [(1, 9), (2, 8)]
    mask = held_mask(np.array([2, 5, 1]), np.array([9, 8]), after)
    assert mask.tolist() == [[False, True], [False, False], [True, False]]


def test_held_links_do_not_depend_on_the_threshold():
    """The evaluation runs with threshold=None and cuts at τ afterwards: the same pairs as a run
    at τ."""
    seq = planted_sequence(seed=3, frames=6).seq
    fn = get_temporal("trajectory_pose")
    free = fn(seq, threshold=None, window=3, margin=0.2)
    cut = fn(seq, threshold=0.3, window=3, margin=0.2)
    for a, b in zip(free, cut, strict=True):
        keep = a.scores[a.pairs[:, 0], a.pairs[:, 1]] >= 0.3
        assert np.array_equal(a.pairs[keep], b.pairs)


# Digests of (pairs, scores) over every frame of planted_sequence(seed=1, frames=6) with
# threshold=None, made by the code of b2fd3b6 (before the hysteresis existed).
BEFORE = {
    ("trajectory_pose", 3): "8046977583db4d89",
    ("temporal_pose", 3): "53cd88b08bdd89bb",
    ("windowed:pose_refine", 3): "5b9c4046e68dc1c3",
    ("windowed:pose_refine", 1): "b85997158a930f38",
}


@pytest.mark.parametrize(("name", "window"), sorted(BEFORE))
def test_margin_zero_is_the_output_from_before(name, window):
    seq = planted_sequence(seed=1, frames=6).seq
    out = get_temporal(name)(seq, threshold=None, window=window, margin=0.0)
    h = hashlib.sha256()
    for m in out:
        h.update(np.ascontiguousarray(m.pairs, dtype=np.int64).tobytes())
        h.update(np.ascontiguousarray(m.scores, dtype=float).tobytes())
    assert h.hexdigest()[:16] == BEFORE[(name, window)]


@pytest.mark.parametrize("name", ["trajectory_pose", "temporal_pose", "windowed:pose_refine"])
def test_the_margin_is_tuned_within_the_equal_budget(name):
    space = temporal_search_space(name)
    assert len(space) == 8
    assert {} in space  # margin 0, the behaviour before, stays a grid point
    assert any(c.get("margin", 0) > 0 for c in space)
    assert name in TEMPORAL_SEARCH_SPACES


def test_margin_is_checked():
    seq = _distracted_sequence()
    with pytest.raises(ValueError, match="margin"):
        get_temporal("windowed:pose")(seq, window=1, margin=-0.1)
    with pytest.raises(ValueError, match="margin"):
        get_temporal("trajectory_pose")(seq, margin=2.0)


def test_trajectory_pose_holds_its_motion_by_the_margin():
    """On a steady planted sequence the previous frame's motion is kept (it is as good as any
    new one, and it has the margin); without ``hold_motion`` it never is, and at margin 0 the
    option changes nothing."""
    seq = planted_sequence(seed=2, frames=6).seq
    fn = get_temporal("trajectory_pose")
    held = fn(seq, threshold=0.3, window=3, margin=0.05)
    assert not held[0].info["held_motion"]  # nothing to hold at the first frame
    assert all(m.info["held_motion"] for m in held[1:])
    free = fn(seq, threshold=0.3, window=3, margin=0.05, hold_motion=False)
    assert not any(m.info.get("held_motion") for m in free)
    zero = fn(seq, threshold=0.3, window=3, margin=0.0)
    off = fn(seq, threshold=0.3, window=3, margin=0.0, hold_motion=False)
    for a, b in zip(zero, off, strict=True):
        assert np.array_equal(a.pairs, b.pairs) and np.array_equal(a.scores, b.scores)
