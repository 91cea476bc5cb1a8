"""highway-env -> world frame conversion: hand-built cases, a property test, and the real env's
junction layout read through it (right-hand traffic, arm 0 in the south)."""

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from cadsim.sources.highway.frames import highway_direction_to_world, highway_to_world, wrap_angle


def test_hand_built_vehicles():
    # highway-env: arm 0 ("south") lies at y > 0; its incoming lane runs at x = +2 towards -y,
    # heading -pi/2. A westbound vehicle on the arm-3 side: (84, -2), heading pi.
    xy = np.array([[2.0, 47.0], [84.0, -2.0], [-10.0, 3.0]])
    heading = np.array([-np.pi / 2, np.pi, np.pi / 4])
    world, yaw = highway_to_world(xy, heading)
    np.testing.assert_allclose(world, [[2.0, -47.0], [84.0, 2.0], [-10.0, -3.0]])
    # north-bound, west-bound (wrapped to -pi), south-east (clockwise on screen = -45 deg CCW)
    np.testing.assert_allclose(yaw, [np.pi / 2, -np.pi, -np.pi / 4])


def test_single_point_and_bad_shape():
    world, yaw = highway_to_world(np.array([1.0, 2.0]), 0.5)
    np.testing.assert_allclose(world, [1.0, -2.0])
    assert yaw == pytest.approx(-0.5)
    with pytest.raises(ValueError, match=r"\(k, 2\)"):
        highway_to_world(np.zeros((4, 3)), np.zeros(4))


@given(
    st.floats(-200, 200),
    st.floats(-200, 200),
    st.floats(-10, 10),
    st.floats(0.1, 30),
    st.floats(0.1, 5),
)
def test_motion_is_consistent(x, y, heading, speed, dt):
    """Moving along the heading in highway-env lands where moving along the yaw lands in world."""
    p0 = np.array([x, y])
    p1 = p0 + speed * dt * np.array([np.cos(heading), np.sin(heading)])
    (w0, w1), yaw = highway_to_world(np.stack([p0, p1]), np.array([heading, heading]))
    expected = w0 + speed * dt * np.array([np.cos(yaw[0]), np.sin(yaw[0])])
    np.testing.assert_allclose(w1, expected, atol=1e-9)
    assert -np.pi <= yaw[0] < np.pi
    np.testing.assert_allclose(highway_direction_to_world(p1 - p0), w1 - w0, atol=1e-9)


def test_wrap_angle():
    np.testing.assert_allclose(
        wrap_angle([np.pi, -np.pi, 3 * np.pi / 2, 0.0]), [-np.pi, -np.pi, -np.pi / 2, 0.0]
    )


def test_real_intersection_layout_in_world_frame():
    from cadsim.sources.highway.geometry import read_layout
    from cadsim.sources.highway.source import import_highway_env

    gym = import_highway_env()
    env = gym.make("intersection-v2", disable_env_checker=True)
    try:
        env.reset(seed=0)
        layout = read_layout(env.unwrapped.road.network)
    finally:
        env.close()
    np.testing.assert_allclose(layout.center, [0.0, 0.0], atol=1e-9)
    by_arm = {a.arm: a for a in layout.approaches}
    assert sorted(by_arm) == [0, 1, 2, 3]
    # highway-env's own names: 0 south, 1 west, 2 north, 3 east; incoming traffic heads inwards.
    np.testing.assert_allclose(by_arm[0].direction, [0, 1], atol=1e-9)
    np.testing.assert_allclose(by_arm[1].direction, [1, 0], atol=1e-9)
    np.testing.assert_allclose(by_arm[2].direction, [0, -1], atol=1e-9)
    np.testing.assert_allclose(by_arm[3].direction, [-1, 0], atol=1e-9)
    assert by_arm[0].stop_line[1] < 0 and by_arm[2].stop_line[1] > 0
    for a in layout.approaches:
        # right-hand traffic: the incoming lane lies right of the arm's centre line
        offset = np.dot(a.stop_line - layout.center, a.right)
        assert offset == pytest.approx(a.lane_width / 2.0)
    # the east-west road is highway-env's major road
    assert by_arm[1].priority > by_arm[0].priority and by_arm[3].priority > by_arm[2].priority
