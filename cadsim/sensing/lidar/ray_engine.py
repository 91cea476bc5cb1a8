"""The ray engine: first hits of many rays against one triangle soup, through Embree (``embreex``).

Chosen by measurement (docs/lidar.md, "Ray engine"): Embree through ``embreex`` (a 45 MB wheel)
casts a 64 × 1024 sweep over a 38 k-triangle street in ≈ 6 ms on two cores (≈ 11 M rays/s);
Open3D's ``RaycastingScene`` is ≈ 2× faster but a 0.9 GB install; trimesh's pure-numpy engine
needs ``rtree`` and manages ≈ 120 rays/s on such a scene, far too slow to be a fallback. When
``embreex`` is missing, :func:`first_hits` raises :class:`RayEngineMissing` with a one-line fix.

Embree works in float32 and its traversal order depends on the CPU's SIMD width, so only the
*index of the hit triangle* is taken from it; the hit distance is recomputed in float64 from that
triangle's plane with plain arithmetic (the same bits on every CPU). Two triangles tied at a ray
(a shared edge) give the same distance either way, up to the float32 plane's slack.
"""

from __future__ import annotations

import numpy as np


class RayEngineMissing(RuntimeError):
    """The ``embreex`` package is not installed."""


def _embree():
    try:
        from embreex import rtcore_scene
        from embreex.mesh_construction import TriangleMesh
    except ImportError as exc:  # pragma: no cover - depends on the environment
        raise RayEngineMissing(
            "the LiDAR needs the Embree ray engine: pip install 'embreex==4.4.0.post1' "
            f"(import failed: {exc})"
        ) from None
    return rtcore_scene, TriangleMesh


def first_hits(triangles: np.ndarray, directions: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """First hit of each ray from the origin along ``directions`` (n, 3) unit vectors against
    ``triangles`` (F, 3, 3) metres, in the same frame.

    Returns ``(face, distance)``: (n,) int64 index of the hit triangle (−1: no hit) and (n,)
    float64 distance along the ray (metres; inf where nothing is hit).
    """
    tri = np.ascontiguousarray(triangles, dtype=np.float64).reshape(-1, 3, 3)
    d = np.ascontiguousarray(directions, dtype=np.float64).reshape(-1, 3)
    n = len(d)
    face = np.full(n, -1, dtype=np.int64)
    dist = np.full(n, np.inf)
    if n == 0 or len(tri) == 0:
        return face, dist
    rtcore_scene, TriangleMesh = _embree()
    scene = rtcore_scene.EmbreeScene()
    TriangleMesh(scene, tri.astype(np.float32))
    origins = np.zeros((n, 3), dtype=np.float32)
    face = np.asarray(scene.run(origins, d.astype(np.float32)), dtype=np.int64)
    hit = np.flatnonzero(face >= 0)
    dist[hit] = plane_distance(tri[face[hit]], d[hit])
    face[hit[~np.isfinite(dist[hit])]] = -1
    return face, dist


def plane_distance(triangles: np.ndarray, directions: np.ndarray) -> np.ndarray:
    """(k,) distance from the origin along each direction to its triangle's plane (metres; inf
    for a ray parallel to it or a plane behind the origin). Element-wise float64 arithmetic only."""
    v0, v1, v2 = triangles[:, 0], triangles[:, 1], triangles[:, 2]
    e1, e2 = v1 - v0, v2 - v0
    nx = e1[:, 1] * e2[:, 2] - e1[:, 2] * e2[:, 1]
    ny = e1[:, 2] * e2[:, 0] - e1[:, 0] * e2[:, 2]
    nz = e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]
    num = nx * v0[:, 0] + ny * v0[:, 1] + nz * v0[:, 2]
    den = nx * directions[:, 0] + ny * directions[:, 1] + nz * directions[:, 2]
    with np.errstate(divide="ignore", invalid="ignore"):
        t = num / den
    return np.where(np.isfinite(t) & (t > 0), t, np.inf)
