"""Which objects cannot appear in a view: pyrender draws every node of the scene in both passes
(colour and segmentation), each at a fixed Python cost, and most objects of an intersection lie
outside a camera's frustum. Leaving those out changes no pixel — an object wholly outside one
plane of the (convex) frustum produces no fragment — and is tested bit for bit against the
unculled render (tests/test_render.py).
"""

from __future__ import annotations

import numpy as np

from cadsim import portable_math as pm

# corner k of an axis-aligned box is (x[k & 1], y[k >> 1 & 1], z[k >> 2 & 1]) of its (2, 3) bounds
_CORNER_BITS = np.array([[k & 1, (k >> 1) & 1, (k >> 2) & 1] for k in range(8)])
_MARGIN_PX = 2.0  # pixels added to each side: a box touching the border is always drawn


def box_corners_world(bounds: np.ndarray, matrices: np.ndarray) -> np.ndarray:
    """(k, 8, 3) world corners of k local boxes: ``bounds`` (k, 2, 3) min/max in each node's
    mesh frame, ``matrices`` (k, 4, 4) node-to-world poses (scale included)."""
    corners = np.take_along_axis(
        bounds, np.broadcast_to(_CORNER_BITS, (len(bounds), 8, 3)), axis=1
    )  # (k, 8, 3)
    return pm.matmul(corners, matrices[:, :3, :3].transpose(0, 2, 1)) + matrices[:, None, :3, 3]


def outside_frustum(
    corners_cam: np.ndarray, width: int, height: int, focal: float, znear: float, zfar: float
) -> np.ndarray:
    """(k,) bool: box k lies wholly beyond one plane of the pinhole frustum (principal point at
    the image centre, OpenCV camera axes: x right, y down, z forward, metres; ``focal`` in
    pixels). Conservative: a box the frustum might touch is never reported outside."""
    x, y, z = corners_cam[..., 0], corners_cam[..., 1], corners_cam[..., 2]
    half_w = (width / 2.0 + _MARGIN_PX) / focal
    half_h = (height / 2.0 + _MARGIN_PX) / focal
    beyond = (
        (z < znear * 0.999).all(axis=1)
        | (z > zfar * 1.001).all(axis=1)
        | (x > half_w * z).all(axis=1)
        | (-x > half_w * z).all(axis=1)
        | (y > half_h * z).all(axis=1)
        | (-y > half_h * z).all(axis=1)
    )
    return beyond
