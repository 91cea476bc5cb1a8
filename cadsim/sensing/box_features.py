"""The box feature vector: what a matcher gets as "appearance" for a detection that is a 3-D box
and nothing else (imported LiDAR / label boxes, cadsim's own LiDAR detector).

A box has a centre, a size (length × width × height, metres) and a heading. The centre becomes the
detection's position and the reported class its class, as for camera detections; the size becomes
the feature vector below; the heading is stored beside it (``ViewDetections.headings``) because it
is frame-dependent — the same car has different headings in two sensors' frames — so it must not
enter a similarity that compares rows across views.

Feature vector (``BOX_FEATURE_DIM`` = 3 × 16 = 48 entries, float32, non-negative): for each of
length, width and height, a Gaussian radial-basis encoding of log₂(size) on 16 centres spaced half
an octave apart from 0.25 m to 45 m (σ = half an octave). The cosine similarity of two rows is the
mean over the three dimensions of ≈ exp(−Δ²), Δ the dimension's ratio in octaves: 1 for equal
boxes, ≈ 0.9 for one dimension 1.5× larger, ≈ 0.35 for a pedestrian against a car. Sizes are
clipped to [0.05, 100] m before encoding. Logarithms, exponentials and the heading's arctangent
go through :mod:`cadsim.portable_math`, so the stored features and headings are the same bytes on
every CPU.

Frames. Box centres use the camera-frame convention of every cadsim detection (OpenCV: x right,
y down, z forward, metres) with the *sensor* as origin; a LiDAR's own frame (x forward, y left,
z up) maps there with :func:`lidar_to_camera_convention`. Heading (radians, in (−π, π]) is the
direction of the box's length axis in that frame, seen from above: ``atan2(d_x, d_z)`` — 0 along
the sensor's forward axis, +π/2 to its right. A LiDAR-frame yaw ψ (counter-clockwise about z up
from x forward) is heading −ψ (:func:`heading_from_lidar_yaw`).
"""

from __future__ import annotations

import numpy as np

from cadsim import portable_math as pm

SIZE_NAMES = ("length_m", "width_m", "height_m")
OCTAVE_CENTRES = np.arange(-2.0, 6.0, 0.5)  # log2 metres: 0.25 m … 45 m
OCTAVE_SIGMA = 0.5
BOX_FEATURE_DIM = len(SIZE_NAMES) * len(OCTAVE_CENTRES)
BOX_CUES = ("position", "class", "size", "heading")
"""What a box-only record carries for matchers (no pixels, no image appearance)."""

_SIZE_CLIP_M = (0.05, 100.0)
_LIDAR_TO_CAMERA = np.array([[0.0, -1.0, 0.0], [0.0, 0.0, -1.0], [1.0, 0.0, 0.0]])
"""Rows: camera x (right) = −lidar y, camera y (down) = −lidar z, camera z (forward) = lidar x."""


def box_feature_vector(size_lwh: np.ndarray) -> np.ndarray:
    """(k, 48) float32 size encoding of k boxes; ``size_lwh`` (k, 3) metres (length, width,
    height). Raises ``ValueError`` for a wrong shape or a non-finite size."""
    size = np.asarray(size_lwh, dtype=np.float64)
    if size.ndim != 2 or size.shape[1] != 3:
        raise ValueError(f"size_lwh: expected (k, 3) metres, got shape {size.shape}")
    if not np.isfinite(size).all():
        raise ValueError("size_lwh: non-finite box size")
    octaves = pm.log2(np.clip(size, *_SIZE_CLIP_M)).reshape(size.shape)
    rbf = pm.exp(-0.5 * ((octaves[:, :, None] - OCTAVE_CENTRES) / OCTAVE_SIGMA) ** 2)
    return rbf.reshape(len(size), BOX_FEATURE_DIM).astype(np.float32)


def lidar_to_camera_convention(points: np.ndarray) -> np.ndarray:
    """(k, 3) points from a LiDAR frame (x forward, y left, z up) to the camera-frame convention
    (x right, y down, z forward), same origin, metres."""
    pts = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    return pts @ _LIDAR_TO_CAMERA.T


def heading_from_lidar_yaw(yaw: np.ndarray) -> np.ndarray:
    """Heading in the camera-frame convention (radians, (−π, π]) of a LiDAR-frame yaw (radians,
    counter-clockwise about z up from x forward)."""
    h = -np.asarray(yaw, dtype=np.float64)
    return np.asarray(pm.arctan2(np.sin(h), np.cos(h)), dtype=np.float64).reshape(h.shape)
