"""Where things may stand in a SUMO scene: the region around the junctions of interest, the
road space (lanes, crossings, junction outlines) as discs, and rectangles clear of it.
Positions in SUMO's network frame (metres, x east, y north); yaws in radians from +x."""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np
from scipy.spatial import cKDTree

from cadsim.sources.sumo.network import RoadNetwork, polyline_points


class Region:
    """Points within ``radius`` metres of any of ``centres`` (k, 2)."""

    def __init__(self, centres: np.ndarray, radius: float) -> None:
        self.tree = cKDTree(centres)
        self.radius = radius

    def contains(self, points: np.ndarray, margin: float = 0.0) -> np.ndarray:
        points = np.asarray(points, float).reshape(-1, 2)
        d, _ = self.tree.query(points)
        return d <= self.radius + margin


# --------------------------------------------------------------------------------------------
# Road surface.


def road_space_points(network: RoadNetwork, step: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """Points every ``step`` m along every lane (internal lanes, crossings and walking areas
    included) with the lane's half width, plus junction outlines (half width 0)."""
    pts, hw = [], []
    for edge in network.net.getEdges(withInternal=True):
        for lane in edge.getLanes():
            p, _ = polyline_points(lane.getShape(), step)
            pts.append(p)
            hw.append(np.full(len(p), lane.getWidth() / 2.0))
    for node in network.net.getNodes():
        shape = node.getShape()
        if len(shape) >= 2:
            p, _ = polyline_points([*shape, shape[0]], step)
            pts.append(p)
            hw.append(np.zeros(len(p)))
            pts.append(np.asarray([node.getCoord()[:2]], float))
            hw.append(np.zeros(1))
    return np.concatenate(pts), np.concatenate(hw)


def rectangles_clear_of_points(
    centres: np.ndarray,
    yaws: np.ndarray,
    half_length: float,
    half_width: float,
    points: np.ndarray,
    point_radius: np.ndarray,
) -> np.ndarray:
    """(k,) bool: rectangle k (centre, yaw, half extents) contains no disc (point, radius)."""
    tree = cKDTree(points)
    reach = np.hypot(half_length, half_width) + point_radius.max()
    neighbours = tree.query_ball_point(centres, reach)
    counts = np.array([len(n) for n in neighbours])
    clear = np.ones(len(centres), bool)
    if counts.sum() == 0:
        return clear
    rect = np.repeat(np.arange(len(centres)), counts)
    idx = np.concatenate([np.asarray(n, int) for n in neighbours])
    d = points[idx] - centres[rect]
    c, s = np.cos(yaws[rect]), np.sin(yaws[rect])
    along = np.abs(d[:, 0] * c + d[:, 1] * s)
    across = np.abs(-d[:, 0] * s + d[:, 1] * c)
    r = point_radius[idx] - 1e-6
    hit = (along < half_length + r) & (across < half_width + r)
    clear[np.unique(rect[hit])] = False
    return clear


def right_hand_lanes(network: RoadNetwork) -> Iterator[tuple[object, np.ndarray, np.ndarray]]:
    """Per normal edge, in id order: its right-most lane (sumolib), the lane's (k, 2) polyline
    and the arc length (k,) at each vertex, metres — the line buildings and roadside clutter
    are placed along. Edges whose lane has fewer than two points are skipped."""
    for edge in sorted(network.normal_edges, key=lambda e: e.getID()):
        lane0 = edge.getLanes()[0]
        xy = np.asarray([p[:2] for p in lane0.getShape()], float)
        if len(xy) < 2:
            continue
        seg = np.diff(xy, axis=0)
        yield lane0, xy, np.concatenate([[0.0], np.cumsum(np.hypot(seg[:, 0], seg[:, 1]))])
