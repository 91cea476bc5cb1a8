"""The LiDAR detector's size error beyond what its points show: a box regressor's scatter, larger
for boxes of fewer points (docs/lidar.md, "Box sizes with the points' noise").

The fitted box already carries the points' own errors — the footprint of the faces it saw,
completed to its class's size where it saw too little, and a height from the road plane to the
highest return, short of the true top by up to one beam spacing at its range. What a learned box
detector adds is a regression scatter that grows as the points thin out: each of the completed
box's length, width and height is multiplied by exp(σ · ε), ε ~ N(0, 1), with
σ = :data:`REFERENCE_SD` · √(:data:`REFERENCE_POINTS` / n) for a box of n points, at most
:data:`MAX_SD` (log units). :data:`REFERENCE_SD` is set from PointPillars' average scale error on
nuScenes (docs/lidar.md); :data:`REFERENCE_POINTS` is the median point count of a box on
cad-v2x-lidar. Three normals per box, in box order, from the view's own size stream.
"""

from __future__ import annotations

import numpy as np

from cadsim import portable_math as pm

REFERENCE_SD = 0.12
REFERENCE_POINTS = 40.0
MAX_SD = 0.5


def size_sd(point_counts: np.ndarray) -> np.ndarray:
    """(k,) σ (log units) of the size error of boxes of ``point_counts`` points."""
    n = np.maximum(np.asarray(point_counts, dtype=float).reshape(-1), 1.0)
    return np.minimum(REFERENCE_SD * np.sqrt(REFERENCE_POINTS / n), MAX_SD)


def noisy_sizes(
    sizes: np.ndarray, point_counts: np.ndarray, rng: np.random.Generator
) -> np.ndarray:
    """(k, 3) box sizes (metres) with the regression scatter of boxes of ``point_counts`` points.

    >>> noisy_sizes(np.array([[4.5, 1.8, 1.5]]), np.array([40]), np.random.default_rng(0)).shape
    (1, 3)
    """
    s = np.asarray(sizes, dtype=float).reshape(-1, 3)
    eps = rng.standard_normal(s.shape)
    return s * pm.exp(size_sd(point_counts)[:, None] * eps).reshape(s.shape)


__all__ = ["MAX_SD", "REFERENCE_POINTS", "REFERENCE_SD", "noisy_sizes", "size_sd"]
