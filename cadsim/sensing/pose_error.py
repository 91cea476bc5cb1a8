"""An observer's pose error and what it does to the world positions seen through that pose.

A pose error is one rigid ground-plane transform per view: a heading error dyaw (radians, about
the vertical through the observer's body origin) and a translation (dx, dy) in metres. Drawn by
the i.i.d. model (``LocalisationConfig.draw_error``, :mod:`cadsim.sensing.localisation`) or the
GNSS-like one (:mod:`cadsim.sensing.gnss_error`); applied by :func:`perturbed_world`. This module
knows neither model: both import it, it imports numpy only.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class PoseError:
    """One observer's pose error: ground-plane translation dx, dy (metres), heading dyaw (rad)."""

    dx: float
    dy: float
    dyaw: float


def perturbed_world(world: np.ndarray, pivot: np.ndarray, error: PoseError) -> np.ndarray:
    """(k, 3) world positions (metres, z up) as seen through a pose with ``error``: rotated by
    dyaw about the vertical through ``pivot`` (the observer's body origin, world metres), then
    shifted by (dx, dy); z unchanged."""
    world = np.asarray(world, dtype=float).reshape(-1, 3)
    out = world.copy()
    if error.dyaw != 0.0:  # (no heading error: no round trip through the pivot, exact)
        pivot = np.asarray(pivot, dtype=float)[:2]
        c, s = np.cos(error.dyaw), np.sin(error.dyaw)
        rel = world[:, :2] - pivot
        out[:, 0] = c * rel[:, 0] - s * rel[:, 1] + pivot[0]
        out[:, 1] = s * rel[:, 0] + c * rel[:, 1] + pivot[1]
    out[:, 0] += error.dx
    out[:, 1] += error.dy
    return out
