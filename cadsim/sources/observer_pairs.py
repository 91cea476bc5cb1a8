"""Observer pairs: two vehicles approaching the same junction on different arms, each with a
forward camera. Source-agnostic: it reads ``snapshot.meta["approaches"]`` (object id ->
{"junction", "arm", "edge", "distance"}), which a traffic source fills in, and, where the
``[observers]`` table aims cameras at the junction, the junction centres (world x, y metres;
``snapshot.meta["junctions"]`` or given by the source).

Cameras sit at the front of the carrying vehicle (just ahead of its front bumper, so the vehicle
never appears in its own view), ``mount_height`` metres above the ground or on the roof, looking
along the vehicle's heading (``aim = "heading"``) or towards the junction centre (``aim =
"junction"``), tilted by ``pitch_deg``.

Geometry rules beyond "same junction, different arms" (each off by default, so that a table
without them chooses exactly the pairs it always did): ``arm_relations`` (opposite / adjacent /
parallel, from the two vehicles' heading difference) and ``min_shared_area_m2`` (the two
cameras' ground footprints, clipped at ``overlap_range_m``, overlap by at least that area;
``cadsim.sources.frustum_overlap``). docs/scenarios.md describes every key.
"""

from __future__ import annotations

from itertools import combinations

import numpy as np

from cadsim import portable_math as pm
from cadsim.camera import Camera
from cadsim.scenario import CameraConfig
from cadsim.sources.base import ObserverPair
from cadsim.sources.frustum_overlap import frustum_overlap
from cadsim.world import Snapshot, WorldObject, wrap_angle

FRONT_CLEARANCE = 0.05  # metres ahead of the front bumper
ROOF_CLEARANCE = 0.05  # metres above the roof for mount_height = "roof"
# Heading difference (degrees) of the two observers' vehicles: >= OPPOSITE_DEG "opposite" arms,
# < ADJACENT_DEG "parallel", in between "adjacent".
OPPOSITE_DEG = 135.0
ADJACENT_DEG = 45.0


def mount_camera(
    carrier: WorldObject, config: CameraConfig, look_at: np.ndarray | None = None
) -> Camera:
    """The forward camera of ``carrier`` (world frame), looking along the carrier's heading, or
    towards the world point ``look_at`` (x, y metres) when given."""
    center = np.asarray(carrier.center, float)
    length, _, height = carrier.size
    ground = center[2] - height / 2.0
    forward = np.array([np.cos(carrier.yaw), np.sin(carrier.yaw)])
    xy = center[:2] + forward * (length / 2.0 + FRONT_CLEARANCE)
    z = ground + (height + ROOF_CLEARANCE if config.mount_height == "roof" else config.mount_height)
    yaw = carrier.yaw
    if look_at is not None:
        yaw = pm.arctan2(look_at[1] - xy[1], look_at[0] - xy[0])
    return Camera(
        position=(float(xy[0]), float(xy[1]), float(z)),
        yaw=float(yaw),
        pitch=float(np.radians(config.pitch_deg)),
        width=config.width,
        height=config.height,
        hfov_deg=config.hfov_deg,
    )


def arm_relation(yaw1: float, yaw2: float) -> str:
    """ "opposite", "adjacent" or "parallel": the relation of two approach arms from the headings
    (radians) of vehicles on them (see OPPOSITE_DEG, ADJACENT_DEG)."""
    difference = abs(float(np.degrees(wrap_angle(yaw1 - yaw2))))
    if difference >= OPPOSITE_DEG:
        return "opposite"
    return "adjacent" if difference >= ADJACENT_DEG else "parallel"


def eligible_by_junction(snapshot: Snapshot, observers: dict) -> dict[str, list[tuple[str, dict]]]:
    """junction id -> [(object id, approach)] of the vehicles that may carry a camera there: of
    an allowed class and within [min_distance, max_distance] of the junction, in id order."""
    objects = snapshot.by_id()
    allowed = set(observers["classes"])
    lo, hi = observers["min_distance"], observers["max_distance"]
    by_junction: dict[str, list[tuple[str, dict]]] = {}
    for oid, approach in sorted(snapshot.meta.get("approaches", {}).items()):
        obj = objects.get(oid)
        if obj is None or obj.cls not in allowed or not lo <= approach["distance"] <= hi:
            continue
        by_junction.setdefault(approach["junction"], []).append((oid, approach))
    return by_junction


def observer_pairs(
    snapshot: Snapshot,
    camera: CameraConfig,
    observers: dict,
    junction_centres: dict[str, np.ndarray] | None = None,
) -> list[ObserverPair]:
    """Candidate observer pairs of ``snapshot`` under a validated ``[observers]`` table, in a
    deterministic order: by junction id, then nearest to the junction first (sum of the two
    distances), then by object ids. Rules: same junction, different arms, both within
    [min_distance, max_distance] of it, of an allowed class, at least min_separation apart; arms
    in one of ``arm_relations`` (if any); footprints sharing >= ``min_shared_area_m2`` of ground.

    junction_centres: junction id -> (x, y) world metres, needed for ``aim = "junction"``
    (default: ``snapshot.meta["junctions"]``)."""
    objects = snapshot.by_id()
    relations = set(observers.get("arm_relations") or ())
    min_area = float(observers.get("min_shared_area_m2", 0.0))
    aim = observers.get("aim", "heading")
    if junction_centres is None:
        junction_centres = snapshot.meta.get("junctions", {})
    by_junction = eligible_by_junction(snapshot, observers)

    candidates = []
    for junction in sorted(by_junction):
        look_at = None
        if aim == "junction":
            if junction not in junction_centres:
                raise ValueError(
                    f"[observers] aim = 'junction': the source gives no centre for junction "
                    f"{junction!r}"
                )
            look_at = np.asarray(junction_centres[junction], float)[:2]
        for (id1, a1), (id2, a2) in combinations(by_junction[junction], 2):
            if a1["arm"] == a2["arm"]:
                continue
            o1, o2 = objects[id1], objects[id2]
            gap = float(np.hypot(o1.center[0] - o2.center[0], o1.center[1] - o2.center[1]))
            if gap < observers["min_separation"]:
                continue
            extra = {}
            if relations:
                extra["relation"] = arm_relation(o1.yaw, o2.yaw)
                if extra["relation"] not in relations:
                    continue
            cam1, cam2 = mount_camera(o1, camera, look_at), mount_camera(o2, camera, look_at)
            if min_area > 0:
                area = frustum_overlap(cam1, cam2, observers["overlap_range_m"])
                if area < min_area:
                    continue
                extra["shared_area_m2"] = round(area, 3)
            key = (junction, a1["distance"] + a2["distance"], id1, id2)
            candidates.append((key, o1, o2, a1, a2, cam1, cam2, extra))
    candidates.sort(key=lambda c: c[0])
    return [
        ObserverPair(
            camera1=cam1,
            camera2=cam2,
            observer1_id=o1.id,
            observer2_id=o2.id,
            meta={
                "junction": a1["junction"],
                "arms": [a1["arm"], a2["arm"]],
                "edges": [a1["edge"], a2["edge"]],
                "distances": [float(a1["distance"]), float(a2["distance"])],
                "time": float(snapshot.time),
            }
            | extra,
        )
        for _, o1, o2, a1, a2, cam1, cam2, extra in candidates
    ]
