"""Roadside clutter: the non-target objects a street has beside its kerbs — street trees, poles
(lamp posts, bollards), wheelie bins and parked trailers — that a LiDAR detector meets and must
not report (docs/lidar.md, "False positives by source").

Along the right-hand side of every normal edge (a SUMO edge's first lane is its outermost: the
sidewalk where there is one), objects stand ``KERB_GAP_M`` beyond the lane's outer edge, one
every ``spacing`` · U(0.5, 1.5) metres, each of a kind drawn with :data:`KIND_SHARES`. Each
object's size comes from its class's spread (``cadsim.object_sizes``) and its own id. Objects
that would overlap road space (another edge's lanes near a junction, crossings, walking areas),
stand within ``FURNITURE_CLEARANCE_M`` of a sign or a signal pole, or lie outside the scene's
region are dropped (their draws still made). World frame: x east, y north, z up, metres.
Everything is drawn from the scenario seed (stream :data:`CLUTTER_STREAM`), in edge-id order.
"""

from __future__ import annotations

import numpy as np

from cadsim.object_sizes import draw_size
from cadsim.sources.sumo.free_space import (
    Region,
    rectangles_clear_of_points,
    right_hand_lanes,
    road_space_points,
)
from cadsim.sources.sumo.network import RoadNetwork, point_at
from cadsim.world import WorldObject

CLUTTER_STREAM = 8
"""Spawn key of the roadside-clutter placement stream under the scenario seed."""
KERB_GAP_M = 0.5
FURNITURE_CLEARANCE_M = 1.5
# kind -> (share, mesh shape, colours)
KIND_SHARES: dict[str, tuple[float, str, tuple[tuple[float, float, float], ...]]] = {
    "tree": (0.35, "tree", ((0.22, 0.42, 0.18), (0.30, 0.50, 0.22), (0.18, 0.35, 0.20))),
    "pole": (0.30, "cylinder", ((0.45, 0.45, 0.47), (0.25, 0.25, 0.27))),
    "bin": (0.20, "box", ((0.15, 0.35, 0.20), (0.30, 0.30, 0.32), (0.20, 0.25, 0.50))),
    "trailer": (0.15, "box", ((0.85, 0.85, 0.85), (0.55, 0.56, 0.58), (0.60, 0.20, 0.15))),
}


def roadside_clutter(
    network: RoadNetwork,
    region: Region,
    spacing: float,
    seed: int,
    furniture_xy: np.ndarray,
) -> list[WorldObject]:
    """The clutter objects (``target=False``) of the scene (module docstring); ``furniture_xy``
    (k, 2) world positions of signs and signal poles to keep clear of."""
    rng = np.random.default_rng(np.random.SeedSequence(int(seed), spawn_key=(CLUTTER_STREAM,)))
    kinds = list(KIND_SHARES)
    shares = np.array([KIND_SHARES[k][0] for k in kinds])
    cum_share = np.cumsum(shares / shares.sum())
    objects: list[WorldObject] = []
    for lane0, xy, cum in right_hand_lanes(network):
        n = int(np.ceil(cum[-1] / (0.5 * spacing))) + 1
        steps = spacing * (0.5 + rng.random(n))
        pick = rng.random(n)
        colour_pick = rng.random(n)
        s = np.cumsum(steps)
        keep = s < cum[-1]
        s, pick, colour_pick = s[keep], pick[keep], colour_pick[keep]
        if not len(s):
            continue
        p, heading = point_at(xy, cum, s)
        right = np.column_stack([np.sin(heading), -np.cos(heading)])
        for k in range(len(s)):  # per object (a few per edge), not per tensor entry
            kind = kinds[int(np.searchsorted(cum_share, pick[k], side="right"))]
            _, shape, colours = KIND_SHARES[kind]
            oid = f"roadside:{kind}:{lane0.getEdge().getID()}:{k}"
            size = draw_size(seed, oid, kind)
            offset = lane0.getWidth() / 2.0 + KERB_GAP_M + size[1] / 2.0
            centre = p[k] + right[k] * offset
            colour = colours[min(int(colour_pick[k] * len(colours)), len(colours) - 1)]
            objects.append(
                WorldObject(
                    id=oid,
                    cls=kind,
                    shape=shape,
                    center=(float(centre[0]), float(centre[1]), size[2] / 2.0),
                    yaw=float(heading[k]),
                    size=size,
                    color=colour,
                    target=False,
                )
            )
    if not objects:
        return []
    return _clear(objects, network, region, furniture_xy)


def _clear(
    objects: list[WorldObject], network: RoadNetwork, region: Region, furniture_xy: np.ndarray
) -> list[WorldObject]:
    """``objects`` inside ``region``, clear of road space and of street furniture."""
    centres = np.array([o.center[:2] for o in objects], dtype=float)
    yaws = np.array([o.yaw for o in objects], dtype=float)
    half = np.array([o.size[:2] for o in objects], dtype=float) / 2.0
    keep = region.contains(centres)
    pts, half_width = road_space_points(network)
    furniture = np.asarray(furniture_xy, dtype=float).reshape(-1, 2)
    if len(furniture):
        pts = np.concatenate([pts, furniture])
        half_width = np.concatenate([half_width, np.full(len(furniture), FURNITURE_CLEARANCE_M)])
    for kind in KIND_SHARES:  # one clearance test per kind, with that kind's largest extents
        rows = np.flatnonzero(keep & np.array([o.cls == kind for o in objects]))
        if not len(rows):
            continue
        hl, hw = half[rows].max(axis=0)
        keep[rows] = rectangles_clear_of_points(
            centres[rows], yaws[rows], float(hl), float(hw), pts, half_width
        )
    return [o for o, k in zip(objects, keep, strict=True) if k]


__all__ = ["CLUTTER_STREAM", "KIND_SHARES", "roadside_clutter"]
