"""V2X-Reg++'s box selection: which of a view's boxes take part in the association.

From the v2i-calib repository's filter (facts, not code): a box is kept when its centre lies
within ``distance_m`` (120 m) of its own sensor on the ground plane; the kept boxes are ranked
by class priority — bus, truck, car first, in that order, every other class after — then by
size (larger first), and the first ``k`` are used (``k`` ≤ 0: all). Their size key is the box
volume; a :class:`~matchers.core.problem.Problem` carries no box sizes, so ties within a class
are broken here by range (nearer first) — the difference is stated in docs/matchers.md.

Imports nothing from ``cadsim`` or ``eval``.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

PRIORITY = ("bus", "truck", "car")
DISTANCE_M = 120.0


def ground_xy(points: np.ndarray) -> np.ndarray:
    """(k, 2) ground-plane coordinates of a view's positions: (x, z) of 3-D camera-frame points
    (x right, y down, z forward), the points themselves when 2-D."""
    points = np.asarray(points, dtype=float)
    return points[:, [0, 2]] if points.shape[1] == 3 else points[:, :2]


def top_k_boxes(
    points: np.ndarray, classes: Sequence[str] | None, k: int, distance_m: float = DISTANCE_M
) -> np.ndarray:
    """Indices (ascending) of the boxes V2X-Reg++ would keep (module docstring).

    >>> top_k_boxes(np.array([[0, 0, 5.0], [0, 0, 150.0], [0, 0, 9.0], [0, 0, 3.0]]),
    ...             ["pedestrian", "car", "truck", "car"], 2).tolist()
    [2, 3]
    """
    xy = ground_xy(points)
    rng = np.hypot(xy[:, 0], xy[:, 1])
    near = np.flatnonzero(rng <= distance_m)
    if k <= 0 or len(near) <= k:
        return near
    names = [str(c).lower() for c in classes] if classes is not None else [""] * len(xy)
    rank = np.array([PRIORITY.index(n) if n in PRIORITY else len(PRIORITY) for n in names])
    order = np.lexsort((near, rng[near], rank[near]))  # class priority, then range, then index
    return np.sort(near[order[:k]])


__all__ = ["DISTANCE_M", "PRIORITY", "ground_xy", "top_k_boxes"]
