"""The sequence contract (issue 41): shapes validated, degenerate input safe, positions moved into
each agent's frame-0 ground plane through mount and odometry."""

from __future__ import annotations

import numpy as np
import pytest
from sequence_fakes import apply, planted_sequence, pose_matrix

from matchers import Problem
from matchers.core.sequence_problem import SequenceProblem, ground_positions, to_frame0


def test_empty_sequence_and_empty_frames():
    empty = SequenceProblem([], [], [], np.zeros((0, 3)), [])
    assert empty.num_frames == 0 and ground_positions(empty, 1) == []
    frame = Problem(np.zeros((0, 3)), np.zeros((0, 3)))
    seq = SequenceProblem([frame, frame], [[], []], [[], []], np.zeros((2, 3)), np.zeros((2, 3)))
    assert [g.shape for g in ground_positions(seq, 2)] == [(0, 2), (0, 2)]
    assert seq.window(1, 5).num_frames == 1


@pytest.mark.parametrize(
    "change, field",
    [
        ({"tracks1": [[0, 1]]}, "tracks1"),  # 2 ids for 1 detection
        ({"tracks1": [[0.5]]}, "tracks1"),  # not an integer
        ({"tracks2": [[3, 3]]}, "tracks2"),  # repeated within a frame
        ({"tracks2": []}, "tracks2"),  # frame count
        ({"odometry1": np.zeros((1, 2))}, "odometry1"),
        ({"odometry2": [[0, 0, np.nan]]}, "odometry2"),
        ({"mount1": np.eye(3)}, "mount1"),
    ],
)
def test_bad_input_names_the_field(change, field):
    frame = Problem(np.zeros((1, 2)), np.ones((2, 2)))
    args = {"frames": [frame], "tracks1": [[4]], "tracks2": [[1, 2]]}
    args |= {"odometry1": np.zeros((1, 3)), "odometry2": np.zeros((1, 3))} | change
    with pytest.raises(ValueError, match=field):
        SequenceProblem(**args)


def test_mount_needs_3d_points():
    frame = Problem(np.zeros((1, 2)), np.ones((1, 2)))
    with pytest.raises(ValueError, match="mount1"):
        SequenceProblem([frame], [[0]], [[0]], np.zeros((1, 3)), np.zeros((1, 3)), np.eye(4))


def test_to_frame0_is_the_odometry_pose():
    xy = np.array([[1.0, 2.0], [-3.0, 0.5]])
    pose = (4.0, -1.0, 0.7)
    assert np.allclose(to_frame0(xy, np.array(pose)), apply(pose_matrix(*pose), xy))


@pytest.mark.parametrize("camera", [False, True])
def test_a_parked_object_stands_still_in_the_frame0_plane(camera):
    planted = planted_sequence(seed=3, frames=4, noise=0.0, camera=camera)
    ground = ground_positions(planted.seq, 1)
    # the same true object at every frame: same frame-0 position unless it moves
    moving = set()
    for t in range(1, 4):
        for obj in set(planted.true1[0]) & set(planted.true1[t]) - {-1}:
            a = ground[0][planted.true1[0] == obj][0]
            b = ground[t][planted.true1[t] == obj][0]
            if np.linalg.norm(a - b) > 1e-9:
                moving.add(obj)
    assert 0 < len(moving) < len(set(planted.true1[0]) - {-1})
