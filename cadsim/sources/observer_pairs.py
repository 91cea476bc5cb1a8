"""Observer pairs: two vehicles approaching the same junction on different arms, each with a
forward camera. Source-agnostic: it reads ``snapshot.meta["approaches"]`` (object id ->
{"junction", "arm", "edge", "distance"}), which a traffic source fills in.

Cameras sit at the front of the carrying vehicle (just ahead of its front bumper, so the vehicle
never appears in its own view), ``mount_height`` metres above the ground or on the roof, looking
along the vehicle's heading, tilted by ``pitch_deg``.
"""

from __future__ import annotations

from itertools import combinations

import numpy as np

from cadsim.camera import Camera
from cadsim.scenario import CameraConfig
from cadsim.sources.base import ObserverPair
from cadsim.world import Snapshot, WorldObject

FRONT_CLEARANCE = 0.05  # metres ahead of the front bumper
ROOF_CLEARANCE = 0.05  # metres above the roof for mount_height = "roof"


def mount_camera(carrier: WorldObject, config: CameraConfig) -> Camera:
    """The forward camera of ``carrier`` (world frame)."""
    center = np.asarray(carrier.center, float)
    length, _, height = carrier.size
    ground = center[2] - height / 2.0
    forward = np.array([np.cos(carrier.yaw), np.sin(carrier.yaw)])
    xy = center[:2] + forward * (length / 2.0 + FRONT_CLEARANCE)
    z = ground + (height + ROOF_CLEARANCE if config.mount_height == "roof" else config.mount_height)
    return Camera(
        position=(float(xy[0]), float(xy[1]), float(z)),
        yaw=float(carrier.yaw),
        pitch=float(np.radians(config.pitch_deg)),
        width=config.width,
        height=config.height,
        hfov_deg=config.hfov_deg,
    )


def observer_pairs(snapshot: Snapshot, camera: CameraConfig, observers: dict) -> list[ObserverPair]:
    """Candidate observer pairs of ``snapshot`` under a validated ``[observers]`` table, in a
    deterministic order: by junction id, then nearest to the junction first (sum of the two
    distances), then by object ids. Rules: same junction, different arms, both within
    [min_distance, max_distance] of it, of an allowed class, at least min_separation apart."""
    objects = snapshot.by_id()
    allowed = set(observers["classes"])
    lo, hi = observers["min_distance"], observers["max_distance"]
    by_junction: dict[str, list[tuple[str, dict]]] = {}
    for oid, approach in sorted(snapshot.meta.get("approaches", {}).items()):
        obj = objects.get(oid)
        if obj is None or obj.cls not in allowed or not lo <= approach["distance"] <= hi:
            continue
        by_junction.setdefault(approach["junction"], []).append((oid, approach))

    candidates = []
    for junction in sorted(by_junction):
        for (id1, a1), (id2, a2) in combinations(by_junction[junction], 2):
            if a1["arm"] == a2["arm"]:
                continue
            o1, o2 = objects[id1], objects[id2]
            gap = float(np.hypot(o1.center[0] - o2.center[0], o1.center[1] - o2.center[1]))
            if gap < observers["min_separation"]:
                continue
            key = (junction, a1["distance"] + a2["distance"], id1, id2)
            candidates.append((key, o1, o2, a1, a2))
    candidates.sort(key=lambda c: c[0])
    return [
        ObserverPair(
            camera1=mount_camera(o1, camera),
            camera2=mount_camera(o2, camera),
            observer1_id=o1.id,
            observer2_id=o2.id,
            meta={
                "junction": a1["junction"],
                "arms": [a1["arm"], a2["arm"]],
                "edges": [a1["edge"], a2["edge"]],
                "distances": [float(a1["distance"]), float(a2["distance"])],
                "time": float(snapshot.time),
            },
        )
        for _, o1, o2, a1, a2 in candidates
    ]
