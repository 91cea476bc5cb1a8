"""The junction layout of a highway-env intersection, read from its road network, in world frame.

highway-env names the lanes of its intersection ``(o{k}, ir{k})`` for the incoming lane of arm k
(outer node -> inner right node, the stop line is its end) and ``(il{k}, o{k})`` for the outgoing
one. Everything static that cadsim adds (road surface, buildings, lights, signs) and the choice of
observers is derived from these lanes, so a change of the env's geometry carries through.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cadsim.sources.highway.frames import highway_direction_to_world, highway_to_world


@dataclass(frozen=True)
class Approach:
    """One incoming arm. arm: highway-env's index k. stop_line: (2,) world point where the
    incoming lane's centre meets the junction [m]. direction: (2,) unit vector of travel towards
    the junction (world). lane_width [m]. length: incoming lane length [m]. priority: the lane's
    right-of-way level (higher = major road)."""

    arm: int
    stop_line: np.ndarray
    direction: np.ndarray
    lane_width: float
    length: float
    priority: int

    @property
    def right(self) -> np.ndarray:
        """(2,) unit vector to the right of the direction of travel (world)."""
        return np.array([self.direction[1], -self.direction[0]])

    @property
    def outward(self) -> np.ndarray:
        """(2,) unit vector from the junction out along this arm (world)."""
        return -self.direction


@dataclass(frozen=True)
class JunctionLayout:
    """All approaches (sorted by arm), the junction centre (2,) [m, world] and the half width of
    each arm's carriageway (one lane each way) [m]."""

    approaches: list[Approach]
    center: np.ndarray
    road_half_width: float

    def approach(self, arm: int) -> Approach:
        for a in self.approaches:
            if a.arm == arm:
                return a
        raise KeyError(f"no approach for arm {arm}")


def incoming_arm(lane_index: tuple) -> int | None:
    """Arm k if ``lane_index`` is highway-env's incoming lane ``(o{k}, ir{k}, i)``, else None."""
    start, end = lane_index[0], lane_index[1]
    if start.startswith("o") and end.startswith("ir") and start[1:] == end[2:]:
        return int(start[1:])
    return None


def read_layout(road_network) -> JunctionLayout:
    """Read the approaches of a highway-env intersection ``RoadNetwork`` (``env.unwrapped.road.
    network``). Raises ValueError when the network has fewer than two incoming arms."""
    approaches: list[Approach] = []
    for start, ends in road_network.graph.items():
        for end, lanes in ends.items():
            arm = incoming_arm((start, end, 0))
            if arm is None:
                continue
            lane = lanes[0]
            p0, p1 = (
                np.asarray(lane.position(0.0, 0.0)),
                np.asarray(lane.position(lane.length, 0.0)),
            )
            (s0, s1), _ = highway_to_world(np.stack([p0, p1]), np.zeros(2))
            direction = highway_direction_to_world(p1 - p0)
            approaches.append(
                Approach(
                    arm=arm,
                    stop_line=s1,
                    direction=direction / np.linalg.norm(direction),
                    lane_width=float(lane.width_at(lane.length)),
                    length=float(lane.length),
                    priority=int(lane.priority),
                )
            )
    if len(approaches) < 2:
        raise ValueError(
            f"highway-env road network has {len(approaches)} incoming arm(s) named (o<k>, ir<k>); "
            "an intersection environment with at least two is needed"
        )
    approaches.sort(key=lambda a: a.arm)
    # Each arm's road centre line runs half a lane to the left of its incoming lane's centre; the
    # junction centre is where those lines meet (least squares over all arms).
    normals = np.stack([a.right for a in approaches])
    points = np.stack([a.stop_line - a.right * a.lane_width / 2.0 for a in approaches])
    center, *_ = np.linalg.lstsq(normals, np.einsum("ij,ij->i", normals, points), rcond=None)
    half_width = max(a.lane_width for a in approaches)
    return JunctionLayout(approaches=approaches, center=center, road_half_width=half_width)
