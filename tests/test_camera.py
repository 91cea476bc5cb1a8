"""Camera model: world <-> camera <-> pixel round trips and the OpenGL pose pyrender gets."""

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from cadsim.camera import Camera

angles = st.floats(-np.pi, np.pi, allow_nan=False)
pitches = st.floats(-1.2, 1.2, allow_nan=False)
coords = st.floats(-200.0, 200.0, allow_nan=False)


@settings(max_examples=60, deadline=None)
@given(
    x=coords,
    y=coords,
    z=st.floats(0.5, 30.0),
    yaw=angles,
    pitch=pitches,
    seed=st.integers(0, 10_000),
)
def test_world_to_pixel_and_back_round_trip(x, y, z, yaw, pitch, seed):
    cam = Camera(position=(x, y, z), yaw=yaw, pitch=pitch, hfov_deg=80.0)
    rng = np.random.default_rng(seed)
    # Points in front of the camera, built in the camera frame and moved to the world.
    pc = np.column_stack([rng.uniform(-5, 5, 20), rng.uniform(-5, 5, 20), rng.uniform(0.5, 80, 20)])
    pw = cam.camera_to_world(pc)
    uv = cam.project(cam.world_to_camera(pw))
    back = cam.camera_to_world(cam.back_project(uv, cam.world_to_camera(pw)[:, 2]))
    np.testing.assert_allclose(back, pw, atol=1e-6)


def test_principal_axis_hits_image_centre_and_right_is_plus_u():
    cam = Camera(position=(1.0, 2.0, 1.6), yaw=np.pi / 2)  # looking north (+y)
    ahead = np.array([[1.0, 12.0, 1.6]])
    np.testing.assert_allclose(cam.project(cam.world_to_camera(ahead)), [[320.0, 240.0]])
    right = np.array([[3.0, 12.0, 1.6]])  # east of the optical axis = image right
    up = np.array([[1.0, 12.0, 3.6]])
    assert cam.project(cam.world_to_camera(right))[0, 0] > 320.0
    assert cam.project(cam.world_to_camera(up))[0, 1] < 240.0


def test_focal_length_matches_horizontal_field_of_view():
    cam = Camera(position=(0, 0, 0), yaw=0.0, hfov_deg=90.0, width=640, height=480)
    # A point at 45 degrees to the right lands on the right image edge.
    edge = cam.project(cam.world_to_camera(np.array([[10.0, -10.0, 0.0]])))
    np.testing.assert_allclose(edge, [[640.0, 240.0]], atol=1e-9)


@settings(max_examples=30, deadline=None)
@given(yaw=angles, pitch=pitches)
def test_gl_pose_looks_along_minus_z_with_y_up(yaw, pitch):
    cam = Camera(position=(5.0, -3.0, 2.0), yaw=yaw, pitch=pitch)
    T = cam.pose_gl()
    R = T[:3, :3]
    np.testing.assert_allclose(R.T @ R, np.eye(3), atol=1e-12)
    assert np.isclose(np.linalg.det(R), 1.0)
    forward_world = cam.rotation_cam_to_world()[:, 2]
    np.testing.assert_allclose(-R[:, 2], forward_world, atol=1e-12)
    down_world = cam.rotation_cam_to_world()[:, 1]
    np.testing.assert_allclose(R[:, 1], -down_world, atol=1e-12)
