"""highway-env's 2-D frame -> cadsim's world frame. The only place the conversion happens.

highway-env draws its road on a pygame surface: pixel column grows with x, pixel row grows with y,
so its y axis points *down* the screen (south, in the intersection env's own naming: arm 0 is
"south" and lies at y > 0). A vehicle's velocity is ``speed * (cos h, sin h)``, so the heading h is
measured from +x towards +y, i.e. clockwise on the screen. Our world frame is x east, y north,
z up with yaw counter-clockwise from +x (``cadsim.world``). Mirroring y keeps the picture the
env renders (north up) and its right-hand traffic:

    world x = x,   world y = -y,   yaw = -heading   (wrapped to [-pi, pi))

See docs/highway-env.md for the diagram.
"""

from __future__ import annotations

import numpy as np

from cadsim.world import wrap_angle  # re-exported: part of this module's API


def highway_to_world(xy: np.ndarray, heading: np.ndarray | float) -> tuple[np.ndarray, np.ndarray]:
    """Convert highway-env positions (k, 2) [m] and headings (k,) [rad, clockwise on screen] into
    world-frame positions (k, 2) [m, x east, y north] and yaws (k,) [rad CCW from +x, in
    [-pi, pi)]. Also accepts a single (2,) point with a scalar heading."""
    p = np.asarray(xy, dtype=float)
    h = np.asarray(heading, dtype=float)
    if p.shape[-1] != 2:
        raise ValueError(f"highway_to_world: xy must have shape (k, 2) or (2,), got {p.shape}")
    world = p * np.array([1.0, -1.0])
    yaw = wrap_angle(-h)
    return world, yaw


def highway_direction_to_world(direction: np.ndarray) -> np.ndarray:
    """A highway-env direction vector (k, 2) or (2,) -> the same direction in the world frame."""
    return np.asarray(direction, dtype=float) * np.array([1.0, -1.0])
