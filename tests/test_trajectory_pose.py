"""``trajectory_pose``: the relative pose and the association from the agents' own tracks alone
(no GNSS prior), and with the prior as a soft term; it refuses no localisation preset."""

from __future__ import annotations

import numpy as np
import pytest
from sequence_fakes import planted_sequence, true_pairs

from matchers import Problem
from matchers.core.sequence_problem import SequenceProblem
from matchers.core.temporal_registry import get_temporal, temporal_search_space


def _without_prior(seq: SequenceProblem) -> SequenceProblem:
    """``seq`` as an agent without GNSS has it: positions, own tracks, odometry, mounts."""
    frames = [Problem(f.points1, f.points2) for f in seq.frames]
    return SequenceProblem(
        frames, seq.tracks1, seq.tracks2, seq.odometry1, seq.odometry2,
        seq.mount1, seq.mount2, dict(seq.meta),
    )  # fmt: skip


def _motion_error(matching, relative: np.ndarray) -> tuple[float, float]:
    """(|yaw error| degrees, |shift error| metres) of a frame's estimated frame-0 motion."""
    yaw = np.radians(matching.info["yaw_deg"]) - np.arctan2(relative[1, 0], relative[0, 0])
    yaw = (yaw + np.pi) % (2 * np.pi) - np.pi
    shift = np.asarray(matching.info["shift_m"]) - relative[:2, 2]
    return abs(float(np.degrees(yaw))), float(np.linalg.norm(shift))


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
@pytest.mark.parametrize("camera", [False, True])
def test_recovers_a_planted_planar_motion_from_tracks_alone(seed, camera):
    """Half the objects moving at N(0, 6²) m/s per axis, 2 clutter boxes per view per frame,
    agent 2 approaching from 40 m ahead: no GNSS at all, yet the last frame's motion is within
    0.5° / 0.3 m and every covisible pair of the last frame is declared, nothing else."""
    planted = planted_sequence(seed=seed, frames=8, moving=0.5, speed_sigma=6.0, camera=camera)
    seq = _without_prior(planted.seq)
    out = get_temporal("trajectory_pose")(seq, seed=0, threshold=0.3, window=8)
    assert not out[-1].info["prior"]
    yaw_err, shift_err = _motion_error(out[-1], planted.relative)
    assert yaw_err < 0.5 and shift_err < 0.3, (yaw_err, shift_err)
    declared = {tuple(p) for p in out[-1].pairs.tolist()}
    assert declared == true_pairs(planted.true1[-1], planted.true2[-1])


def test_a_wrong_prior_does_not_pull_the_motion_far():
    """With a GNSS prior (σ 1.2 m, 2° per frame) the prior is one hypothesis and a soft term:
    the motion stays within 0.5 m of the truth."""
    planted = planted_sequence(seed=5, frames=8, moving=0.5, speed_sigma=6.0, gnss_sigma=1.2)
    out = get_temporal("trajectory_pose")(planted.seq, threshold=0.3, window=8, prior_weight=1.0)
    assert out[-1].info["prior"]
    assert _motion_error(out[-1], planted.relative)[1] < 0.5


def test_refuses_none_of_the_presets():
    from eval.core.abstention import cannot_run
    from eval.studies.temporal.evaluation import PRESETS

    assert get_temporal("trajectory_pose").requires == frozenset()
    assert not any(cannot_run("trajectory_pose", p, temporal=True) for p in (*PRESETS, "exact"))
    assert len(temporal_search_space("trajectory_pose")) == 8


@pytest.mark.parametrize("seed", [2, 4, 5])
def test_the_window_helps_where_one_frame_is_ambiguous(seed):
    """Three covisible objects, all moving, 5 clutter boxes per view per frame: one frame's
    segments cannot tell the motion from coincidences; over the window the moving tracks
    propose it from their velocities, and the window finds more true pairs."""
    planted = planted_sequence(
        seed=seed, frames=8, moving=1.0, speed_sigma=6.0, clutter=5, covisible=3, only=3, noise=0.3
    )
    seq = _without_prior(planted.seq)
    fn = get_temporal("trajectory_pose")

    def found(window: int) -> int:
        out = fn(seq, threshold=0.3, window=window)
        return sum(
            len({tuple(p) for p in m.pairs.tolist()} & true_pairs(a, b))
            for m, a, b in zip(out, planted.true1, planted.true2, strict=True)
        )

    assert found(8) > found(1) + 8


def test_deterministic_for_a_seed():
    seq = _without_prior(planted_sequence(seed=3, frames=4).seq)
    fn = get_temporal("trajectory_pose")
    first, second = fn(seq, seed=4, window=3), fn(seq, seed=4, window=3)
    assert all(np.array_equal(a.scores, b.scores) for a, b in zip(first, second, strict=True))
