"""Random 2-D point-set matching problems of the RRWHM/BCAGM synthetic benchmarks.

As in the BCAGM code (``makeMatchingProblem`` with the ``setSettings_*`` files): inliers
P1 ~ N(0, I2); view 2 = scale * R(rotation) * P1 + sigma * N(0, I2), plus ``n_outliers`` points
~ N(0, I2) appended to view 2 only; view 2 is then randomly permuted. Unit-free coordinates.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class PointSetPair:
    """points1: (n_inliers, 2); points2: (n_inliers + n_outliers, 2); truth[i] = index in
    points2 of the partner of points1[i]."""

    points1: np.ndarray
    points2: np.ndarray
    truth: np.ndarray


def make_point_sets(
    rng: np.random.Generator,
    n_inliers: int,
    n_outliers: int = 0,
    sigma: float = 0.0,
    scale: float = 1.0,
    rotation_rad: float = 0.0,
) -> PointSetPair:
    """Draw one synthetic problem (see module docstring); deterministic given ``rng``'s state."""
    if n_inliers < 1:
        raise ValueError(f"n_inliers: expected >= 1, got {n_inliers}")
    if n_outliers < 0 or sigma < 0 or scale <= 0:
        raise ValueError(
            f"n_outliers >= 0, sigma >= 0, scale > 0 expected; got {n_outliers}, {sigma}, {scale}"
        )
    p1 = rng.standard_normal((n_inliers, 2))
    outliers = rng.standard_normal((n_outliers, 2))
    c, s = np.cos(rotation_rad), np.sin(rotation_rad)
    rot = np.array([[c, -s], [s, c]])
    inliers2 = scale * p1 @ rot.T + sigma * rng.standard_normal(p1.shape)
    unshuffled = np.concatenate([inliers2, outliers])
    perm = rng.permutation(unshuffled.shape[0])  # points2[k] = unshuffled[perm[k]]
    truth = np.argsort(perm)[:n_inliers]
    return PointSetPair(points1=p1, points2=unshuffled[perm], truth=truth)
