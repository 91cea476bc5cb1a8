"""How much of the ground two cameras both look at: the overlap of their view frusta on the
ground plane, within a range.

A camera's *footprint* is the horizontal wedge of its field of view (apex at the camera's ground
point, half-angle hfov/2 either side of its yaw) cut off at ``max_range`` metres: a convex
polygon whose far edge is the range arc, approximated by a chord polyline. Pitch and mount height
are ignored — for the street-level cameras this rule serves (|pitch| well below half the vertical
field of view) everything standing on the ground within the range and inside the wedge is in the
frustum. Two footprints' overlap is the intersection of two convex polygons (Sutherland–Hodgman
clipping); its area says whether two observers can share most of what they see. World frame:
``cadsim.world`` (x east, y north, metres). Imports only numpy and ``cadsim.camera``.
"""

from __future__ import annotations

import numpy as np

from cadsim.camera import Camera

ARC_SEGMENTS = 16  # chords approximating the range arc (area within 0.3 % of the sector's at 90°)


def ground_footprint(
    camera: Camera, max_range: float, arc_segments: int = ARC_SEGMENTS
) -> np.ndarray:
    """(arc_segments + 2, 2) counter-clockwise convex polygon, world x/y metres: the camera's
    horizontal field of view on the ground out to ``max_range`` metres. For hfov > 180° the wedge
    would not be convex; cameras here have hfov <= 170° (``[camera] hfov_deg``)."""
    half = np.radians(camera.hfov_deg) / 2.0
    angles = camera.yaw + np.linspace(-half, half, arc_segments + 1)
    apex = np.asarray(camera.position[:2], float)
    arc = apex + max_range * np.column_stack([np.cos(angles), np.sin(angles)])
    return np.vstack([apex, arc])


def polygon_area(polygon: np.ndarray) -> float:
    """Area (m²) of a simple polygon (k, 2) by the shoelace formula; 0 for fewer than 3 vertices."""
    p = np.asarray(polygon, float).reshape(-1, 2)
    if len(p) < 3:
        return 0.0
    x, y = p[:, 0], p[:, 1]
    # sums, not np.dot: BLAS kernels differ by CPU (portable_math.matmul)
    return float(abs(np.sum(x * np.roll(y, -1)) - np.sum(y * np.roll(x, -1))) / 2.0)


def convex_intersection(subject: np.ndarray, clip: np.ndarray) -> np.ndarray:
    """(k, 2) intersection of two convex counter-clockwise polygons (k = 0 when they are
    disjoint): ``subject`` clipped by each edge half-plane of ``clip`` in turn."""
    out = np.asarray(subject, float).reshape(-1, 2)
    clip = np.asarray(clip, float).reshape(-1, 2)
    for a, b in zip(clip, np.roll(clip, -1, axis=0), strict=True):
        if len(out) == 0:
            break
        edge = b - a
        # signed distance (times |edge|) of each vertex to the left of a -> b: inside if >= 0
        side = edge[0] * (out[:, 1] - a[1]) - edge[1] * (out[:, 0] - a[0])
        nxt = np.roll(out, -1, axis=0)
        side_next = np.roll(side, -1)
        inside = side >= 0
        crosses = (side >= 0) != (side_next >= 0)
        t = np.divide(side, side - side_next, out=np.zeros_like(side), where=crosses)
        hits = out + t[:, None] * (nxt - out)
        # each vertex contributes itself if inside, then the crossing point of its edge if any
        pieces = np.stack([out, hits], axis=1)
        keep = np.stack([inside, crosses], axis=1)
        out = pieces[keep]
    return out


def frustum_overlap(camera1: Camera, camera2: Camera, max_range: float) -> float:
    """Ground-plane area (m²) both cameras look at within ``max_range`` metres of each.

    >>> from cadsim.camera import Camera
    >>> facing = Camera((0, 0, 1.6), 0.0), Camera((30, 0, 1.6), np.pi)
    >>> frustum_overlap(*facing, 40.0) > 300
    True
    >>> frustum_overlap(Camera((0, 0, 1.6), 0.0), Camera((-5, 0, 1.6), np.pi), 40.0)
    0.0
    """
    shared = convex_intersection(
        ground_footprint(camera1, max_range), ground_footprint(camera2, max_range)
    )
    return polygon_area(shared)


__all__ = ["convex_intersection", "frustum_overlap", "ground_footprint", "polygon_area"]
