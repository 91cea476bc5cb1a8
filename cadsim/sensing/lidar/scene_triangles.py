"""The triangles a LiDAR sees: every object of a world snapshot, drawn with the renderer's own
meshes (``cadsim.render.meshes``), plus the renderer's ground plane, in the sensor's frame.

Each triangle carries the index of its object in ``snapshot.objects`` (−1 for the ground): the
ground truth a point inherits (``cadsim.sensing.lidar.raycast``). Objects wholly beyond the
sensor's maximum range are left out. Vertices are placed with element-wise float64 arithmetic
(no BLAS), so the same snapshot gives the same bits on every CPU. Imports the render mesh
registry and the world model only — not pyrender.
"""

from __future__ import annotations

import dataclasses
from collections import OrderedDict
from collections.abc import Collection

import numpy as np

from cadsim import portable_math as pm
from cadsim.render.meshes import MeshSpec, build_parts, mesh_spec
from cadsim.render.scene import GROUND_Z, object_matrix
from cadsim.sensing.lidar.mount import rigid_inverse
from cadsim.world import Snapshot

GROUND_INDEX = -1
_CACHE_SIZE = 512
_local_cache: OrderedDict[MeshSpec, np.ndarray] = OrderedDict()


def _local_triangles(spec: MeshSpec) -> np.ndarray:
    """(F, 3, 3) float64 triangles of a mesh in its object frame (before the node scale); cached
    per geometry: the colour of a spec does not change its shape, so look-alikes of every colour
    share one entry."""
    spec = dataclasses.replace(spec, color=(0.5, 0.5, 0.5))
    tri = _local_cache.get(spec)
    if tri is None:
        tri = np.concatenate(
            [np.asarray(p.mesh.triangles, dtype=np.float64) for p in build_parts(spec)]
        )
        tri.setflags(write=False)
        _local_cache[spec] = tri
        if len(_local_cache) > _CACHE_SIZE:
            _local_cache.popitem(last=False)
    else:
        _local_cache.move_to_end(spec)
    return tri


def apply_transform(points: np.ndarray, matrix: np.ndarray) -> np.ndarray:
    """(..., 3) points through the 4×4 ``matrix``, element-wise (no BLAS), float64."""
    p = np.asarray(points, dtype=np.float64)
    m = np.asarray(matrix, dtype=np.float64)
    out = np.empty(p.shape)
    for row in range(3):  # three output coordinates, not a loop over points
        out[..., row] = (
            p[..., 0] * m[row, 0] + p[..., 1] * m[row, 1] + p[..., 2] * m[row, 2] + m[row, 3]
        )
    return out


def scene_triangles(
    snapshot: Snapshot,
    sensor_to_world: np.ndarray,
    max_range_m: float,
    exclude_ids: Collection[str] = (),
) -> tuple[np.ndarray, np.ndarray]:
    """``(triangles, object_index)``: (F, 3, 3) float64 metres in the sensor frame and (F,) int32
    index into ``snapshot.objects`` (−1: ground). ``exclude_ids``: objects left out (the vehicle
    carrying the sensor). The ground is a square of side 2 · (max_range + 10) m at the renderer's
    ground height, centred under the sensor."""
    world_to_sensor = rigid_inverse(sensor_to_world)
    origin = np.asarray(sensor_to_world, dtype=np.float64)[:3, 3]
    parts, owners = [], []
    for index, obj in enumerate(snapshot.objects):  # per object, not per point
        if obj.id in exclude_ids:
            continue
        reach = float(np.sqrt(np.sum(np.square(np.asarray(obj.size, dtype=np.float64))))) / 2.0
        gap = np.asarray(obj.center, dtype=np.float64) - origin
        if float(np.sqrt(np.sum(gap * gap))) - reach > max_range_m:
            continue
        local = _local_triangles(mesh_spec(obj))
        parts.append(apply_transform(local, pm.matmul(world_to_sensor, object_matrix(obj))))
        owners.append(np.full(len(local), index, dtype=np.int32))
    half = float(max_range_m) + 10.0
    x0, y0 = origin[0], origin[1]
    corners = np.array([[x0 - half, y0 - half, GROUND_Z], [x0 + half, y0 - half, GROUND_Z],
                        [x0 + half, y0 + half, GROUND_Z], [x0 - half, y0 + half, GROUND_Z]])  # fmt: skip
    ground = apply_transform(corners[[[0, 1, 2], [0, 2, 3]]], world_to_sensor)
    parts.append(ground)
    owners.append(np.full(2, GROUND_INDEX, dtype=np.int32))
    return np.concatenate(parts), np.concatenate(owners)
