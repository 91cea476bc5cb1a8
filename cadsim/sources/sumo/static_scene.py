"""Static objects derived from a SUMO road network: road surface, ground, building blocks, road
signs and traffic-light poles. World frame (x east, y north, z up, metres); every object is a
box-like WorldObject whose ``yaw`` is its facing direction (signs and lights face the traffic they
regulate).

How they are placed (see docs/scenarios.md):
  * road: one flat box per lane segment (driving lanes, sidewalks, bike lanes), one per pedestrian
    crossing, the minimum-area rectangle of each junction's shape, and a ground plane under all;
  * buildings: rows of blocks along the outer (right-hand) side of every road, ``setback`` metres
    clear of every lane, crossing, walking area and junction, not overlapping each other;
  * signs: on the right of each arm of an observed junction, ``sign_distance`` before the stop line
    (the junction's rule: traffic signals ahead / priority road / yield / stop / crossroads) and on
    each exit, the same distance after the junction (speed limit);
  * traffic lights: a pole with a head per signalised approach, beside its stop line; the head
    shows the state of the approach's signals (filled in per snapshot by the source).
Only objects within ``radius`` of an observed junction are built.
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass, replace

import cv2
import numpy as np
from scipy.spatial import cKDTree

from cadsim import portable_math as pm
from cadsim.object_sizes import draw_size
from cadsim.sources.street_furniture import (
    ROAD_COLOR,
    SIGNAL_COLORS,
    light_object,
    sign_object,
)
from cadsim.sources.sumo.free_space import (  # noqa: F401 (re-exported for callers)
    Region,
    rectangles_clear_of_points,
    right_hand_lanes,
    road_space_points,
)
from cadsim.sources.sumo.network import RoadNetwork, point_at
from cadsim.sources.sumo.roadside_clutter import roadside_clutter
from cadsim.world import WorldObject

SIDEWALK_COLOR = (0.62, 0.62, 0.60)
BIKE_LANE_COLOR = (0.55, 0.30, 0.28)
CROSSING_COLOR = (0.85, 0.85, 0.85)
GROUND_COLOR = (0.42, 0.48, 0.36)
# Tops of the surface layers (m): higher layers win where surfaces overlap.
_LAYER_TOP = {
    "ground": -0.05,
    "junction": -0.02,
    "lane": -0.02,
    "bike": -0.015,
    "sidewalk": -0.01,
    "crossing": -0.005,
}
_SURFACE_THICKNESS = 0.05

# Which signal an approach shows when its links differ: the commonest, ties to the first here.
_SIGNAL_ORDER = "GgyYurRsoO"
_KERB_OFFSET = 0.6  # metres from the outer edge of the outermost lane to a sign or pole


@dataclass(frozen=True)
class SignalHead:
    """A traffic-light object whose colour/state follow link indices of traffic light ``tls``."""

    object: WorldObject
    tls: str
    links: tuple[int, ...]

    def at_state(self, state: str) -> WorldObject:
        """The object showing the signal for the full TLS state string ``state``."""
        chars = [state[i] for i in self.links if i < len(state)]
        char = representative_signal(chars)
        color = SIGNAL_COLORS.get(char, SIGNAL_COLORS["o"])
        return replace(self.object, color=color, state=char)


def representative_signal(chars: list[str]) -> str:
    """The commonest signal character (ties: greener first); "o" (off) for none."""
    if not chars:
        return "o"
    counts = Counter(chars)
    return max(
        counts, key=lambda c: (counts[c], -_SIGNAL_ORDER.find(c) if c in _SIGNAL_ORDER else -99)
    )


@dataclass
class StaticScene:
    """Static objects (``objects``: road, ground, buildings, signs) and the traffic lights."""

    objects: list[WorldObject]
    lights: list[SignalHead]


def build_static_scene(
    network: RoadNetwork, junctions: list[str], scene: dict, seed: int
) -> StaticScene:
    """Static objects around ``junctions`` (ids) of ``network`` from a validated
    ``[traffic.scene]`` table; ``seed`` fixes building heights and colours, each sign's and
    pole's own size (``cadsim.object_sizes``) and the roadside clutter."""
    centres = np.array([network.junction_xy(j) for j in junctions]).reshape(-1, 2)
    region = Region(centres, scene["radius"])
    objects: list[WorldObject] = []
    if scene["road"]:
        objects += road_surface(network, region)
    if scene["buildings"]:
        objects += buildings(network, region, scene, np.random.default_rng(seed))
    if scene["signs"]:
        objects += [own_size(o, seed) for o in signs(network, junctions, scene["sign_distance"])]
    lights = traffic_lights(network, region) if scene["traffic_lights"] else []
    lights = [replace(head, object=own_size(head.object, seed)) for head in lights]
    if scene.get("clutter_spacing", 0.0) > 0:
        furniture = np.array(
            [o.center[:2] for o in objects if o.cls == "sign"]
            + [h.object.center[:2] for h in lights],
            dtype=float,
        ).reshape(-1, 2)
        objects += roadside_clutter(network, region, scene["clutter_spacing"], seed, furniture)
    return StaticScene(objects=objects, lights=lights)


def own_size(obj: WorldObject, seed: int) -> WorldObject:
    """``obj`` standing on the ground with its own size, drawn around its class's default
    (``cadsim.object_sizes``) from ``seed`` and its id."""
    size = draw_size(seed, obj.id, obj.cls, obj.size)
    return replace(obj, size=size, center=(obj.center[0], obj.center[1], size[2] / 2.0))


def road_surface(network: RoadNetwork, region: Region) -> list[WorldObject]:
    out: list[WorldObject] = []
    all_points = []
    for edge in sorted(network.net.getEdges(withInternal=True), key=lambda e: e.getID()):
        function = edge.getFunction()
        if function not in ("", "crossing"):
            continue
        for lane in edge.getLanes():
            kind = "crossing" if function == "crossing" else _lane_kind(lane)
            xy = np.asarray([p[:2] for p in lane.getShape()], float)
            if len(xy) < 2:
                continue
            mid = (xy[1:] + xy[:-1]) / 2.0
            seg = np.diff(xy, axis=0)
            length = np.hypot(seg[:, 0], seg[:, 1])
            keep = region.contains(mid, margin=length.max() / 2.0) & (length > 1e-3)
            all_points.append(xy)
            for k in np.flatnonzero(keep):
                out.append(
                    _surface(
                        f"road:{lane.getID()}:{k}",
                        kind,
                        mid[k],
                        float(pm.arctan2(seg[k, 1], seg[k, 0])),
                        (float(length[k]) + (0.0 if kind == "crossing" else 0.2), lane.getWidth()),
                    )
                )
    for node in sorted(network.net.getNodes(), key=lambda n: n.getID()):
        shape = np.asarray([p[:2] for p in node.getShape()], np.float32)
        if len(shape) < 3 or not region.contains(shape.mean(axis=0))[0]:
            continue
        (cx, cy), (w, h), angle = cv2.minAreaRect(shape)
        if min(w, h) < 0.1:  # a dead end's shape is a line
            continue
        out.append(
            _surface(
                f"road:junction:{node.getID()}", "junction", (cx, cy), np.radians(angle), (w, h)
            )
        )
    if all_points:
        pts = np.concatenate(all_points)
        pts = pts[region.contains(pts, margin=50.0)]
        if len(pts):
            lo, hi = pts.min(axis=0) - 40.0, pts.max(axis=0) + 40.0
            top = _LAYER_TOP["ground"]
            out.append(
                WorldObject(
                    id="ground",
                    cls="ground",
                    shape="box",
                    center=(*(float(v) for v in (lo + hi) / 2.0), top - 0.05),
                    yaw=0.0,
                    size=(float(hi[0] - lo[0]), float(hi[1] - lo[1]), 0.1),
                    color=GROUND_COLOR,
                    target=False,
                    variant="ground",
                )
            )
    return out


def _lane_kind(lane) -> str:
    if lane.allows("passenger"):
        return "lane"
    if lane.allows("pedestrian"):
        return "sidewalk"
    return "bike" if lane.allows("bicycle") else "lane"


def _surface(oid: str, kind: str, xy, yaw: float, lw: tuple[float, float]) -> WorldObject:
    top = _LAYER_TOP[kind]
    color = {
        "sidewalk": SIDEWALK_COLOR,
        "bike": BIKE_LANE_COLOR,
        "crossing": CROSSING_COLOR,
    }.get(kind, ROAD_COLOR)
    return WorldObject(
        id=oid,
        cls="road",
        shape="box",
        center=(float(xy[0]), float(xy[1]), top - _SURFACE_THICKNESS / 2.0),
        yaw=float(yaw),
        size=(float(lw[0]), float(lw[1]), _SURFACE_THICKNESS),
        color=color,
        target=False,
        variant=kind,
    )


# --------------------------------------------------------------------------------------------
# Buildings.


def buildings(
    network: RoadNetwork, region: Region, scene: dict, rng: np.random.Generator
) -> list[WorldObject]:
    """Rows of blocks along the right-hand side of every normal edge, clear of all road space."""
    frontage, depth = scene["building_frontage"], scene["building_depth"]
    gap, setback = scene["building_gap"], scene["building_setback"]
    centres, yaws = [], []
    for lane0, xy, cum in right_hand_lanes(network):
        s = np.arange(gap / 2.0 + frontage / 2.0, cum[-1] - frontage / 2.0 + 1e-9, frontage + gap)
        if len(s) == 0:
            continue
        p, h = point_at(xy, cum, s)
        right = np.column_stack([np.sin(h), -np.cos(h)])
        centres.append(p + right * (lane0.getWidth() / 2.0 + setback + depth / 2.0))
        yaws.append(h)
    if not centres:
        return []
    centres = np.concatenate(centres)
    yaws = np.concatenate(yaws)
    keep = region.contains(centres)
    centres, yaws = centres[keep], yaws[keep]

    # Clear of road space: no lane sample point (disc of its half width) within the setback.
    pts, half_width = road_space_points(network)
    clear = rectangles_clear_of_points(
        centres, yaws, frontage / 2.0 + setback, depth / 2.0 + setback, pts, half_width
    )
    centres, yaws = centres[clear], yaws[clear]
    chosen = non_overlapping(centres, yaws, frontage / 2.0 + gap / 2.0, depth / 2.0 + gap / 2.0)
    centres, yaws = centres[chosen], yaws[chosen]

    lo, hi = scene["building_heights"]
    heights = rng.uniform(lo, hi, size=len(centres))
    palette = [hex_to_rgb(c) for c in scene["building_colors"]]
    colors = rng.integers(0, len(palette), size=len(centres))
    return [
        WorldObject(
            id=f"building:{k}",
            cls="building",
            shape="box",
            center=(float(c[0]), float(c[1]), float(hgt / 2.0)),
            yaw=float(y),
            size=(frontage, depth, float(hgt)),
            color=palette[ci],
            target=False,
        )
        for k, (c, y, hgt, ci) in enumerate(zip(centres, yaws, heights, colors, strict=True))
    ]


def non_overlapping(
    centres: np.ndarray, yaws: np.ndarray, half_length: float, half_width: float
) -> np.ndarray:
    """Indices of a greedy (input order) subset of equal rectangles with no two overlapping."""
    n = len(centres)
    if n == 0:
        return np.zeros(0, int)
    pairs = cKDTree(centres).query_pairs(
        2.0 * np.hypot(half_length, half_width), output_type="ndarray"
    )
    overlapping = pairs[_rectangles_overlap(centres, yaws, pairs, half_length, half_width)]
    conflicts: list[list[int]] = [[] for _ in range(n)]
    for a, b in overlapping:
        conflicts[max(a, b)].append(min(a, b))
    accepted = np.zeros(n, bool)
    for k in range(n):
        accepted[k] = not any(accepted[j] for j in conflicts[k])
    return np.flatnonzero(accepted)


def _rectangles_overlap(centres, yaws, pairs, hl, hw) -> np.ndarray:
    """Separating-axis test for pairs (p, 2) of equal oriented rectangles."""
    if len(pairs) == 0:
        return np.zeros(0, bool)
    a, b = pairs[:, 0], pairs[:, 1]
    d = centres[b] - centres[a]
    axes = []
    for yaw in (yaws[a], yaws[b]):
        axes.append(np.column_stack([np.cos(yaw), np.sin(yaw)]))
        axes.append(np.column_stack([-np.sin(yaw), np.cos(yaw)]))
    separated = np.zeros(len(pairs), bool)
    for u in axes:
        reach = 0.0
        for yaw in (yaws[a], yaws[b]):
            ex = np.column_stack([np.cos(yaw), np.sin(yaw)])
            ey = np.column_stack([-np.sin(yaw), np.cos(yaw)])
            reach = reach + hl * np.abs((ex * u).sum(1)) + hw * np.abs((ey * u).sum(1))
        separated |= np.abs((d * u).sum(1)) >= reach - 1e-9
    return ~separated


def hex_to_rgb(text: str) -> tuple[float, float, float]:
    """ "#rrggbb" -> RGB in [0, 1]."""
    return tuple(int(text[i : i + 2], 16) / 255.0 for i in (1, 3, 5))


# --------------------------------------------------------------------------------------------
# Signs and traffic lights.


def _kerb_point(lane, from_end: float, at_end: bool) -> tuple[np.ndarray, float]:
    """A point beside the outer edge of ``lane`` (its right side), ``from_end`` metres from its
    end (at_end) or start, and the lane heading there (radians CCW from +x)."""
    xy = np.asarray([p[:2] for p in lane.getShape()], float)
    seg = np.diff(xy, axis=0)
    cum = np.concatenate([[0.0], np.cumsum(np.hypot(seg[:, 0], seg[:, 1]))])
    d = min(from_end, 0.8 * cum[-1])
    s = cum[-1] - d if at_end else d
    p, h = point_at(xy, cum, np.array([s]))
    right = np.array([np.sin(h[0]), -np.cos(h[0])])
    return p[0] + right * (lane.getWidth() / 2.0 + _KERB_OFFSET), float(h[0])


def signs(network: RoadNetwork, junctions: list[str], distance: float) -> list[WorldObject]:
    out = []
    for j in junctions:
        node = network.net.getNode(j)
        arms = [network.net.getEdge(e) for e in network.junction_arms[j]]
        top_priority = max(e.getPriority() for e in arms)
        for edge in arms:
            kind = _approach_sign(node.getType(), edge.getPriority() == top_priority)
            xy, heading = _kerb_point(edge.getLanes()[0], distance, at_end=True)
            out.append(_sign(f"sign:{j}:{edge.getID()}:in", kind, "", xy, heading + np.pi))
        for edge in sorted(node.getOutgoing(), key=lambda e: e.getID()):
            if edge.getID() not in network.edge_to or not any(
                edge.allows(c) for c in ("passenger", "bus", "truck", "delivery")
            ):
                continue
            xy, heading = _kerb_point(edge.getLanes()[0], distance, at_end=False)
            limit = f"{round(edge.getSpeed() * 3.6):d}"
            out.append(
                _sign(f"sign:{j}:{edge.getID()}:out", "speed_limit", limit, xy, heading + np.pi)
            )
    return out


def _approach_sign(junction_type: str, is_major: bool) -> str:
    if junction_type.startswith("traffic_light"):
        return "traffic_signals"
    if junction_type == "allway_stop":
        return "stop"
    if junction_type in ("priority", "priority_stop", "zipper"):
        if is_major:
            return "priority_road"
        return "stop" if junction_type == "priority_stop" else "yield"
    return "crossroads"


def _sign(oid: str, kind: str, value: str, xy: np.ndarray, yaw: float) -> WorldObject:
    return sign_object(oid, kind, xy, float(pm.arctan2(np.sin(yaw), np.cos(yaw))), value)


def traffic_lights(network: RoadNetwork, region: Region) -> list[SignalHead]:
    """One pole + head per (traffic light, incoming normal edge) it controls, beside the stop line."""
    out = []
    for tls in sorted(network.net.getTrafficLights(), key=lambda t: t.getID()):
        links: dict[str, set[int]] = {}
        for in_lane, _out_lane, index in tls.getConnections():
            edge = in_lane.getEdge()
            if edge.getFunction() == "":
                links.setdefault(edge.getID(), set()).add(int(index))
        for edge_id in sorted(links):
            edge = network.net.getEdge(edge_id)
            xy, heading = _kerb_point(edge.getLanes()[0], 1.0, at_end=True)
            if not region.contains(xy)[0]:
                continue
            yaw = float(pm.arctan2(np.sin(heading + np.pi), np.cos(heading + np.pi)))
            obj = light_object(f"tls:{tls.getID()}:{edge_id}", xy, yaw, "o")
            out.append(SignalHead(obj, tls.getID(), tuple(sorted(links[edge_id]))))
    return out
