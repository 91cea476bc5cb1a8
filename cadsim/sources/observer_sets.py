"""N-view observer sets (DESIGN §12): ``count`` vehicles approaching one junction plus
``roadside_units`` pole-mounted cameras at its corners. Source-agnostic like
:mod:`cadsim.sources.observer_pairs`, whose camera mount and eligibility rules it shares: a
vehicle is eligible when it is of an allowed class and within [min_distance, max_distance] of
the junction (``snapshot.meta["approaches"]``).

Choice of the vehicles, per junction: arms in order of their nearest eligible vehicle; rounds
over the arms take each arm's next-nearest vehicle that is at least ``min_separation`` from
every one chosen, until ``count`` are chosen (a junction with fewer eligible vehicles gives no
set). So the vehicles spread over the arms before a second one of an arm is taken. The pair
rules ``arm_relations`` and ``min_shared_area_m2`` do not apply to sets.

Roadside units: camera ``k`` on a pole ``roadside_offset_m`` from the junction centre along a
corner's diagonal (world bearings 45°, 225°, 135°, 315° in that order, so two units face each
other across the junction), ``roadside_height_m`` above the ground (z = 0), looking at the
centre, tilted by ``roadside_pitch_deg``; the pole itself is not drawn. World frame: x east,
y north, metres; yaw radians counter-clockwise from +x.
"""

from __future__ import annotations

import numpy as np

from cadsim.camera import Camera
from cadsim.scenario import CameraConfig
from cadsim.sources.base import ObserverSet
from cadsim.sources.observer_pairs import eligible_by_junction, mount_camera
from cadsim.world import Snapshot

ROADSIDE_BEARINGS_DEG = (45.0, 225.0, 135.0, 315.0)


def roadside_id(junction: str, k: int) -> str:
    """The observer id of roadside unit ``k`` (0-based) of ``junction``."""
    return f"rsu:{junction}:{k}"


def roadside_cameras(
    junction: str, centre: np.ndarray, camera: CameraConfig, observers: dict
) -> list[tuple[str, Camera]]:
    """(id, camera) of the junction's ``roadside_units`` cameras; ``centre`` (x, y) world metres."""
    offset = float(observers["roadside_offset_m"])
    cams = []
    for k in range(int(observers["roadside_units"])):
        bearing = np.radians(ROADSIDE_BEARINGS_DEG[k])
        x = float(centre[0]) + offset * float(np.cos(bearing))
        y = float(centre[1]) + offset * float(np.sin(bearing))
        yaw = float(np.arctan2(float(centre[1]) - y, float(centre[0]) - x))
        cam = Camera(
            position=(x, y, float(observers["roadside_height_m"])),
            yaw=yaw,
            pitch=float(np.radians(observers["roadside_pitch_deg"])),
            width=camera.width,
            height=camera.height,
            hfov_deg=camera.hfov_deg,
        )
        cams.append((roadside_id(junction, k), cam))
    return cams


def _choose_vehicles(eligible: list[tuple[str, dict]], objects: dict, count: int, gap: float) -> list[tuple[str, dict]]:  # fmt: skip
    """``count`` vehicles spread over the arms (see the module docstring), or [] if too few."""
    by_arm: dict[str, list[tuple[str, dict]]] = {}
    for oid, approach in sorted(eligible, key=lambda e: (e[1]["distance"], e[0])):
        by_arm.setdefault(approach["arm"], []).append((oid, approach))
    arms = sorted(by_arm, key=lambda a: (by_arm[a][0][1]["distance"], a))
    chosen: list[tuple[str, dict]] = []
    while len(chosen) < count and any(by_arm[a] for a in arms):
        for arm in arms:
            while by_arm[arm]:
                oid, approach = by_arm[arm].pop(0)
                here = np.asarray(objects[oid].center[:2], float)
                if all(
                    np.hypot(*(here - np.asarray(objects[o].center[:2], float))) >= gap
                    for o, _ in chosen
                ):
                    chosen.append((oid, approach))
                    break
            if len(chosen) == count:
                break
    return chosen if len(chosen) == count else []


def observer_sets(
    snapshot: Snapshot,
    camera: CameraConfig,
    observers: dict,
    junction_centres: dict[str, np.ndarray] | None = None,
) -> list[ObserverSet]:
    """One candidate set per junction (in junction-id order) that has ``count`` eligible,
    separated vehicles; cameras as :func:`~cadsim.sources.observer_pairs.mount_camera` (aim as
    ``[observers] aim``), then the roadside units. junction_centres: junction id -> (x, y)
    world metres (default: ``snapshot.meta["junctions"]``)."""
    objects = snapshot.by_id()
    if junction_centres is None:
        junction_centres = snapshot.meta.get("junctions", {})
    by_junction = eligible_by_junction(snapshot, observers)
    sets = []
    for junction in sorted(by_junction):
        if junction not in junction_centres:
            raise ValueError(f"[observers]: the source gives no centre for junction {junction!r}")
        centre = np.asarray(junction_centres[junction], float)[:2]
        chosen = _choose_vehicles(
            by_junction[junction], objects, int(observers["count"]), observers["min_separation"]
        )
        if not chosen:
            continue
        look_at = centre if observers.get("aim", "heading") == "junction" else None
        cameras = [mount_camera(objects[oid], camera, look_at) for oid, _ in chosen]
        ids = [oid for oid, _ in chosen]
        for rsu, cam in roadside_cameras(junction, centre, camera, observers):
            ids.append(rsu)
            cameras.append(cam)
        kinds = ("vehicle",) * len(chosen) + ("roadside",) * int(observers["roadside_units"])
        meta = {
            "junction": junction,
            "arms": [a["arm"] for _, a in chosen],
            "edges": [a["edge"] for _, a in chosen],
            "distances": [float(a["distance"]) for _, a in chosen],
            "time": float(snapshot.time),
        }
        sets.append(ObserverSet(tuple(cameras), tuple(ids), kinds, meta))
    return sets
