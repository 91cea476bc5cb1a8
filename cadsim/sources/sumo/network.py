"""A SUMO road network as the source needs it: which junctions two vehicles can approach from
different arms, how far a vehicle is from the next such junction, and lane geometry.

Coordinates are SUMO network coordinates, which are the world frame (x east, y north, metres).
A junction is *usable* when vehicles can reach it on normal edges from at least two different
neighbouring nodes (its arms) and it connects at least three neighbouring nodes (a junction, not a
bend in a road). An arm is identified by the node its incoming edge comes from, so parallel edges
from the same neighbour count as one arm.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import sumolib

from cadsim import portable_math as pm
from cadsim.sources.sumo.xml_files import check_size

# A road that any of these may use can carry an observer.
MOTOR_CLASSES = ("passenger", "delivery", "bus", "truck")
_SKIPPED_NODE_TYPES = {"internal", "dead_end"}


@dataclass(frozen=True)
class Approach:
    """A vehicle approaching a usable junction: the junction, the arm (neighbour node id), the
    incoming edge it will enter the junction from and the distance to the junction (metres, along
    its route, from its front bumper to the stop line)."""

    junction: str
    arm: str
    edge: str
    distance: float

    def as_dict(self) -> dict:
        return {
            "junction": self.junction,
            "arm": self.arm,
            "edge": self.edge,
            "distance": float(self.distance),
        }


class RoadNetwork:
    """A .net.xml read with sumolib (internal lanes, crossings and walking areas included)."""

    def __init__(self, path: str | Path) -> None:
        self.path = Path(path)
        check_size(self.path)  # sumolib reads .gz itself, whole: a bomb is refused before that
        self.net = sumolib.net.readNet(
            str(self.path), withInternal=True, withPedestrianConnections=True
        )
        self.normal_edges = [
            e for e in self.net.getEdges(withInternal=False) if e.getFunction() == ""
        ]
        self.edge_to = {e.getID(): e.getToNode().getID() for e in self.normal_edges}
        self.edge_from = {e.getID(): e.getFromNode().getID() for e in self.normal_edges}
        self.edge_length = {e.getID(): e.getLength() for e in self.normal_edges}
        self.lane_length = {
            lane.getID(): lane.getLength()
            for e in self.net.getEdges(withInternal=True)
            for lane in e.getLanes()
        }
        self.junction_arms = usable_junctions(self.net)

    def junction_xy(self, junction: str) -> np.ndarray:
        return np.asarray(self.net.getNode(junction).getCoord()[:2], float)

    def approach(
        self,
        route: tuple[str, ...] | list[str],
        route_index: int,
        lane_id: str,
        lane_position: float,
        max_distance: float,
        junctions: set[str] | None = None,
    ) -> Approach | None:
        """The next usable junction (of ``junctions`` if given) on a vehicle's route within
        ``max_distance`` metres, or None. The vehicle is on ``lane_id`` at ``lane_position``
        (metres from the lane start, front bumper); vehicles inside a junction get None."""
        if lane_id.startswith(":") or not (0 <= route_index < len(route)):
            return None
        distance = self.lane_length.get(lane_id, 0.0) - lane_position
        for k in range(route_index, len(route)):
            edge = route[k]
            if k > route_index:
                distance += self.edge_length.get(edge, 0.0)
            if distance > max_distance:
                return None
            node = self.edge_to.get(edge)
            if node in self.junction_arms and (junctions is None or node in junctions):
                return Approach(node, self.edge_from[edge], edge, max(distance, 0.0))
        return None


def usable_junctions(net: sumolib.net.Net) -> dict[str, list[str]]:
    """Usable junction id -> ids of its incoming motor-vehicle edges, sorted; junctions sorted."""
    out: dict[str, list[str]] = {}
    for node in net.getNodes():
        if node.getType() in _SKIPPED_NODE_TYPES:
            continue
        incoming = [e for e in node.getIncoming() if _is_motor_road(e)]
        outgoing = [e for e in node.getOutgoing() if _is_motor_road(e)]
        arms = {e.getFromNode().getID() for e in incoming}
        neighbours = arms | {e.getToNode().getID() for e in outgoing}
        neighbours.discard(node.getID())
        arms.discard(node.getID())
        if len(arms) >= 2 and len(neighbours) >= 3:
            out[node.getID()] = sorted(e.getID() for e in incoming)
    return dict(sorted(out.items()))


def _is_motor_road(edge) -> bool:
    return edge.getFunction() == "" and any(edge.allows(c) for c in MOTOR_CLASSES)


def polyline_points(shape: list, step: float) -> tuple[np.ndarray, np.ndarray]:
    """Points every ``step`` metres along a polyline (its vertices included) and the heading
    (radians CCW from +x) of the segment each lies on. Shape: [(x, y[, z]), ...]."""
    xy = np.asarray([p[:2] for p in shape], float)
    if len(xy) < 2:
        return xy.reshape(-1, 2), np.zeros(len(xy))
    seg = np.diff(xy, axis=0)
    seg_len = np.hypot(seg[:, 0], seg[:, 1])
    cum = np.concatenate([[0.0], np.cumsum(seg_len)])
    s = np.unique(np.concatenate([np.arange(0.0, cum[-1], step), cum]))
    return point_at(xy, cum, s)


def point_at(xy: np.ndarray, cum: np.ndarray, s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Positions and headings at arc lengths ``s`` along polyline ``xy`` with cumulative
    lengths ``cum``."""
    seg = np.diff(xy, axis=0)
    k = np.clip(np.searchsorted(cum, s, side="right") - 1, 0, len(seg) - 1)
    seg_len = np.maximum(cum[k + 1] - cum[k], 1e-9)
    t = ((s - cum[k]) / seg_len)[:, None]
    points = xy[k] + t * seg[k]
    headings = pm.arctan2(seg[k, 1], seg[k, 0])
    return points, headings
