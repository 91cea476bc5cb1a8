"""The persistent pyrender scene: one node per world object, meshes shared between look-alikes.

``ObjectScene.sync(snapshot)`` adds nodes for new objects, removes those that left, replaces the
mesh of an object whose appearance changed (e.g. a signal turning green) and updates every pose.
Each distinct mesh is converted to a GPU primitive once and kept in a cache. Lights: one
directional "sun" fixed in the world plus ambient light. A large ground plane (not an object:
instance -1) follows the camera just below z = 0.
"""

from __future__ import annotations

from collections import OrderedDict
from collections.abc import Collection
from types import ModuleType

import numpy as np

from cadsim import portable_math as pm
from cadsim.render.meshes import MeshSpec, Part, build_parts, mesh_spec, node_scale
from cadsim.world import Snapshot, WorldObject

GROUND_Z = -0.03  # metres; just below roads drawn at z = 0 to avoid z-fighting
GROUND_HALF_SIZE = 2000.0  # metres


DEFAULT_SUN_AZIMUTH_DEG = -60.0  # from the south-east
DEFAULT_SUN_ELEVATION_DEG = 55.0


def sun_pose(azimuth_deg: float, elevation_deg: float) -> np.ndarray:
    """4x4 world pose of a directional light shining from (azimuth CCW from +x, elevation),
    degrees: the light shines along its node's -z."""
    el, az = np.radians(elevation_deg), np.radians(azimuth_deg)
    towards_sun = np.array([np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)])
    z = towards_sun
    x = np.cross([0.0, 0.0, 1.0], z)
    x /= np.sqrt(np.sum(x * x))  # not BLAS: its kernel depends on the CPU (portable_math.matmul)
    pose = np.eye(4)
    pose[:3, :3] = np.column_stack([x, np.cross(z, x), z])
    return pose


def srgb_to_linear(c: np.ndarray) -> np.ndarray:
    """sRGB [0, 1] -> linear RGB (pyrender lights in linear space and gamma-encodes its output)."""
    c = np.clip(np.asarray(c, dtype=np.float32), 0.0, 1.0)
    return np.where(c <= 0.04045, c / 12.92, pm.power((c + 0.055) / 1.055, 2.4))


def parts_to_mesh(pyrender: ModuleType, parts: list[Part], material) -> object:
    """Flat-shaded single-primitive pyrender.Mesh with per-vertex colours from the parts."""
    positions, normals, colors = [], [], []
    for p in parts:
        tri = np.asarray(p.mesh.triangles, dtype=np.float32)  # (F, 3, 3)
        n = np.asarray(p.mesh.face_normals, dtype=np.float32)
        positions.append(tri.reshape(-1, 3))
        normals.append(np.repeat(n, 3, axis=0))
        rgba = np.append(srgb_to_linear(p.color), 1.0).astype(np.float32)
        colors.append(np.broadcast_to(rgba, (tri.shape[0] * 3, 4)))
    primitive = pyrender.Primitive(
        positions=np.concatenate(positions),
        normals=np.concatenate(normals),
        color_0=np.concatenate(colors),
        material=material,
        mode=pyrender.constants.GLTF.TRIANGLES,
    )
    return pyrender.Mesh([primitive])


def object_matrix(obj: WorldObject) -> np.ndarray:
    """4x4 world pose of the object's node, including the mesh scale."""
    T = obj.pose()
    T[:3, :3] = T[:3, :3] * node_scale(obj)[None, :]
    return T


class ObjectScene:
    """pyrender scene mirroring the objects of the latest snapshot."""

    def __init__(
        self,
        pyrender: ModuleType,
        *,
        ground_color: tuple[float, float, float] | None,
        background: tuple[float, float, float],
        ambient: float,
        sun_intensity: float,
        mesh_cache_size: int = 1024,
    ) -> None:
        self._pr = pyrender
        self.scene = pyrender.Scene(
            bg_color=np.append(np.asarray(background, float), 1.0),
            ambient_light=np.full(3, ambient),
        )
        self._material = pyrender.MetallicRoughnessMaterial(
            baseColorFactor=[1.0, 1.0, 1.0, 1.0],
            metallicFactor=0.0,
            roughnessFactor=0.75,
            alphaMode="OPAQUE",
        )
        self._meshes: OrderedDict[MeshSpec, object] = OrderedDict()
        self._mesh_cache_size = mesh_cache_size
        self._nodes: dict[str, tuple[object, MeshSpec]] = {}
        self._hidden: list[object] = []
        self.ground = None
        if ground_color is not None:
            import trimesh

            plane = trimesh.Trimesh(
                vertices=[[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]],
                faces=[[0, 1, 2], [0, 2, 3]],
                process=False,
            )
            mesh = parts_to_mesh(pyrender, [Part(plane, tuple(ground_color))], self._material)
            self.ground = self.scene.add(mesh, name="__ground__")
        # Sun: elevation 55 deg, from the south-east; fixed in the world so both views agree
        # (an [appearance] table moves it per episode: set_lighting).
        self._sun = self.scene.add(
            pyrender.DirectionalLight(color=np.ones(3), intensity=sun_intensity),
            pose=sun_pose(DEFAULT_SUN_AZIMUTH_DEG, DEFAULT_SUN_ELEVATION_DEG),
        )
        self.camera_node = None

    def set_lighting(
        self, azimuth_deg: float, elevation_deg: float, sun_intensity: float, ambient: float
    ) -> None:
        """Move the sun (azimuth CCW from +x, elevation, degrees) and set the light strengths."""
        self.scene.set_pose(self._sun, sun_pose(azimuth_deg, elevation_deg))
        self._sun.light.intensity = float(sun_intensity)
        self.scene.ambient_light = np.full(3, float(ambient))

    def _mesh(self, spec: MeshSpec):
        mesh = self._meshes.get(spec)
        if mesh is None:
            mesh = parts_to_mesh(self._pr, build_parts(spec), self._material)
            self._meshes[spec] = mesh
            if len(self._meshes) > self._mesh_cache_size:
                in_use = {s for _, s in self._nodes.values()}
                for old in [s for s in self._meshes if s not in in_use][: len(self._meshes) // 4]:
                    del self._meshes[old]
        else:
            self._meshes.move_to_end(spec)
        return mesh

    def sync(self, snapshot: Snapshot) -> list[object]:
        """Mirror ``snapshot``; returns the node of each object, in ``snapshot.objects`` order."""
        seen = set()
        nodes = []
        for obj in snapshot.objects:
            if obj.id in seen:
                raise ValueError(
                    f"snapshot at t={snapshot.time} has duplicate object id {obj.id!r}"
                )
            seen.add(obj.id)
            spec = mesh_spec(obj)
            pose = object_matrix(obj)
            entry = self._nodes.get(obj.id)
            if entry is not None and entry[1] != spec:
                self.scene.remove_node(entry[0])
                entry = None
            if entry is None:
                node = self.scene.add(self._mesh(spec), pose=pose)
                self._nodes[obj.id] = (node, spec)
            else:
                node = entry[0]
                self.scene.set_pose(node, pose)
            nodes.append(node)
        for obj_id in [i for i in self._nodes if i not in seen]:
            self.scene.remove_node(self._nodes.pop(obj_id)[0])
        return nodes

    def hide(self, object_ids: Collection[str]) -> None:
        """Take these objects' nodes out of the scene until ``unhide``."""
        for obj_id in object_ids:
            entry = self._nodes.get(obj_id)
            if entry is not None and entry[0] in self.scene.nodes:
                self.scene.remove_node(entry[0])
                self._hidden.append(entry[0])

    def unhide(self) -> None:
        for node in self._hidden:
            self.scene.add_node(node)
        self._hidden.clear()

    def place_camera(self, camera_model, pose_gl: np.ndarray) -> None:
        """Set the main camera (a pyrender camera) and its OpenGL-axes pose; move the ground."""
        if self.camera_node is None:
            self.camera_node = self.scene.add(camera_model, pose=pose_gl)
        elif self.camera_node.camera is not camera_model:
            raise ValueError("ObjectScene.place_camera: use one pyrender camera per scene")
        else:
            self.scene.set_pose(self.camera_node, pose_gl)
        if self.ground is not None:
            g = np.diag([GROUND_HALF_SIZE, GROUND_HALF_SIZE, 1.0, 1.0])
            g[:2, 3] = pose_gl[:2, 3]
            g[2, 3] = GROUND_Z
            self.scene.set_pose(self.ground, g)
