"""A problem's own length scale: the median distance between objects of one view, pooled over
both views — what the relative (``*_scale``) kernel-width options of the matchers multiply, so
that one tuning grid serves a 2 m robot arena and an 18 m road junction alike.

Imports nothing from ``cadsim`` or ``eval``.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.distance import pdist


def median_spacing(positions1: np.ndarray, positions2: np.ndarray) -> float:
    """Median of the positive distances between two objects of the same view, over both views
    pooled (units of the positions: metres for 3-D points, pixels for box centres).

    Zero distances (duplicate positions) are left out so that duplicates cannot collapse the
    scale to 0. With no positive distance at all (fewer than two distinct objects in each view)
    it returns 1.0: every within-view distance is then 0, so any kernel of distance differences
    is flat and the width does not matter.

    >>> median_spacing(np.array([[0.0, 0.0], [3.0, 0.0]]), np.array([[0.0, 0.0], [0.0, 5.0]]))
    4.0
    """
    distances = np.concatenate(
        [pdist(np.asarray(p, dtype=float)) for p in (positions1, positions2)]
    )
    positive = distances[distances > 0]
    return float(np.median(positive)) if positive.size else 1.0
