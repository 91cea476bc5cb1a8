"""The box feature vector and the heading convention of box-only detections."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from cadsim.dataset.detections import ViewDetections
from cadsim.sensing.box_features import (
    BOX_FEATURE_DIM,
    box_feature_vector,
    heading_from_lidar_yaw,
    lidar_to_camera_convention,
)


def _cos(a: np.ndarray, b: np.ndarray) -> float:
    return float(a @ b / np.linalg.norm(a) / np.linalg.norm(b))


def test_equal_sizes_are_identical_and_different_classes_are_far_apart() -> None:
    car, car2, ped, bus = box_feature_vector(
        [[4.5, 1.8, 1.5], [4.5, 1.8, 1.5], [0.6, 0.6, 1.7], [12.0, 2.5, 3.2]]
    )
    assert box_feature_vector([[4.5, 1.8, 1.5]]).shape == (1, BOX_FEATURE_DIM)
    assert _cos(car, car2) == pytest.approx(1.0)
    assert _cos(car, ped) < 0.5
    assert _cos(ped, bus) < 0.2
    assert _cos(car, box_feature_vector([[4.8, 1.9, 1.5]])[0]) > 0.95


@given(st.floats(0.25, 4.0), st.floats(1.1, 3.0))
def test_similarity_falls_as_one_dimension_grows(size: float, ratio: float) -> None:
    base = box_feature_vector([[size, 1.0, 1.0]])[0]
    near = box_feature_vector([[size * ratio, 1.0, 1.0]])[0]
    far = box_feature_vector([[size * ratio * ratio, 1.0, 1.0]])[0]
    assert _cos(base, near) > _cos(base, far)


def test_bad_sizes_are_refused() -> None:
    with pytest.raises(ValueError, match="size_lwh"):
        box_feature_vector([[1.0, np.nan, 1.0]])
    with pytest.raises(ValueError, match="size_lwh"):
        box_feature_vector([1.0, 2.0, 3.0])


def test_lidar_frame_maps_to_the_camera_convention() -> None:
    # forward 10 m, left 2 m, up 1 m  ->  x right -2, y down -1, z forward 10
    assert np.allclose(lidar_to_camera_convention([[10.0, 2.0, 1.0]]), [[-2.0, -1.0, 10.0]])
    # a box turned 90 degrees to the left (yaw +pi/2) points to the camera's -x: heading -pi/2
    assert heading_from_lidar_yaw(np.pi / 2) == pytest.approx(-np.pi / 2)
    d = lidar_to_camera_convention([[np.cos(0.3), np.sin(0.3), 0.0]])[0]
    assert np.arctan2(d[0], d[2]) == pytest.approx(float(heading_from_lidar_yaw(0.3)))


def test_headings_travel_through_arrays_and_take() -> None:
    det = ViewDetections(
        positions=np.arange(6.0).reshape(2, 3), boxes=np.zeros((2, 4)),
        features=box_feature_vector([[4.5, 1.8, 1.5], [0.6, 0.6, 1.7]]),
        object_ids=["a", "b"], true_classes=["car", "person"], pixels=np.zeros(2),
        reported_classes=["car", "person"], headings=np.array([0.1, -2.0]),
    )  # fmt: skip
    back = ViewDetections.from_arrays(det.to_arrays("view1"), "view1", "test")
    assert back.equals(det)
    assert np.array_equal(det.take([1]).headings, [-2.0])
    assert not det.equals(ViewDetections.from_arrays(
        {k: v for k, v in det.to_arrays("view1").items() if not k.endswith("headings")}, "view1", "t"))  # fmt: skip
    with pytest.raises(ValueError, match="headings"):
        ViewDetections(**{**det.__dict__, "headings": np.array([np.nan, 0.0])})
