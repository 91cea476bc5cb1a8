"""Street furniture every road source shares: road signs and traffic-light poles as world objects,
their sizes and colours, and the road-surface colour. World frame (x east, y north, z up, metres);
``yaw`` is the facing direction, radians CCW from +x. Imports no source."""

from __future__ import annotations

from cadsim.world import WorldObject

ROAD_COLOR = (0.25, 0.25, 0.27)

SIGN_SIZE = (0.08, 0.75, 2.6)  # depth, panel width, total height (pole + panel), metres
SIGN_COLORS = {
    "stop": (0.75, 0.10, 0.10),
    "yield": (0.92, 0.92, 0.92),
    "priority_road": (0.95, 0.80, 0.10),
    "traffic_signals": (0.92, 0.92, 0.92),
    "crossroads": (0.92, 0.92, 0.92),
    "speed_limit": (0.92, 0.92, 0.92),
}
LIGHT_SIZE = (0.4, 0.4, 3.5)  # pole + head: depth, width, height, metres
# SUMO signal characters -> head colour.
SIGNAL_COLORS = {
    "G": (0.10, 0.85, 0.20),
    "g": (0.10, 0.85, 0.20),
    "y": (1.00, 0.75, 0.00),
    "Y": (1.00, 0.75, 0.00),
    "u": (1.00, 0.50, 0.00),
    "r": (0.90, 0.10, 0.10),
    "R": (0.90, 0.10, 0.10),
    "s": (0.90, 0.10, 0.10),
    "o": (0.20, 0.20, 0.20),
    "O": (0.20, 0.20, 0.20),
}


def sign_object(oid: str, kind: str, xy, yaw: float, value: str = "") -> WorldObject:
    """A road sign of ``kind`` (a SIGN_COLORS key, also its ``variant``) standing on the ground at
    ``xy`` (world frame, metres), facing ``yaw`` (radians CCW from +x); ``value`` (e.g. a speed
    limit) is its ``state``. Shared by every source's static scene."""
    return WorldObject(
        id=oid,
        cls="sign",
        shape="sign",
        center=(float(xy[0]), float(xy[1]), SIGN_SIZE[2] / 2.0),
        yaw=float(yaw),
        size=SIGN_SIZE,
        color=SIGN_COLORS[kind],
        variant=kind,
        state=value,
    )


def light_object(oid: str, xy, yaw: float, state: str) -> WorldObject:
    """A traffic-light pole + head standing on the ground at ``xy`` (world frame, metres), facing
    ``yaw`` (radians CCW from +x), showing the SUMO signal character ``state``."""
    return WorldObject(
        id=oid,
        cls="traffic_light",
        shape="traffic_light",
        center=(float(xy[0]), float(xy[1]), LIGHT_SIZE[2] / 2.0),
        yaw=float(yaw),
        size=LIGHT_SIZE,
        color=SIGNAL_COLORS[state],
        state=state,
    )
