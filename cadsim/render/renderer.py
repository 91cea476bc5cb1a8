"""Off-screen CPU renderer: colour, exact depth and instance ids of a snapshot seen by a camera.

Two passes per view over one persistent scene (``cadsim.render.scene``): a lit colour pass, then a
segmentation pass in which every object's node is drawn in a flat colour that encodes its index in
``snapshot.objects`` (index + 1 packed into 24-bit RGB; 0 = background). Depth and instance ids are
both taken from the segmentation pass, so depth and ids come from the same rasterisation. No pass
is multisampled, and EGL draws as OSMesa does (``cadsim.render.shims``): the same scenario and
seed give the same bytes on either backend. ``Renderer.gl`` says which GL driver drew.
"""

from __future__ import annotations

import logging
from collections.abc import Collection

import numpy as np

from cadsim.camera import Camera
from cadsim.render.backend import BACKENDS, ROWS_REVERSED, gl_identity, install_hint, load_pyrender
from cadsim.render.frustum_culling import box_corners_world, outside_frustum
from cadsim.render.scene import DEFAULT_SUN_AZIMUTH_DEG, DEFAULT_SUN_ELEVATION_DEG, ObjectScene
from cadsim.render.shading import use_lambert_shading
from cadsim.render.view import RenderedView
from cadsim.world import Snapshot

log = logging.getLogger(__name__)


def index_color(index: int) -> tuple[int, int, int]:
    """Segmentation colour of object ``index`` (0-based): index + 1 as 24-bit RGB."""
    k = index + 1
    return (k >> 16) & 0xFF, (k >> 8) & 0xFF, k & 0xFF


def decode_instances(seg: np.ndarray) -> np.ndarray:
    """(H, W, 3) uint8 segmentation image -> (H, W) int32 object index, -1 = background."""
    s = seg.astype(np.int32)
    return ((s[..., 0] << 16) | (s[..., 1] << 8) | s[..., 2]) - 1


class Renderer:
    """Off-screen renderer on the CPU (OSMesa or EGL, chosen by ``select_backend``).

    One per process: the scene is built once and updated per snapshot (new objects get nodes,
    departed ones are removed, poses move). width, height: pixels; every camera passed to
    ``render`` must have this size. background: sky colour (sRGB, [0, 1]). ground_color: colour of
    an endless ground plane just below z = 0, or None for none. znear, zfar: clip distances in
    metres (depth beyond zfar reads 0 = no hit). ambient, sun_intensity: lighting strengths.
    ``cull`` (default True): leave out objects wholly outside the camera's frustum
    (:mod:`cadsim.render.frustum_culling`; no pixel changes).
    """

    def __init__(
        self,
        width: int = 640,
        height: int = 480,
        *,
        background: tuple[float, float, float] = (0.62, 0.75, 0.90),
        ground_color: tuple[float, float, float] | None = (0.40, 0.43, 0.36),
        znear: float = 0.2,
        zfar: float = 500.0,
        ambient: float = 0.45,
        sun_intensity: float = 0.7,
    ) -> None:
        if width <= 0 or height <= 0:
            raise ValueError(f"Renderer: width and height must be positive, got {width}x{height}")
        if not 0 < znear < zfar:
            raise ValueError(f"Renderer: need 0 < znear < zfar, got znear={znear}, zfar={zfar}")
        self._znear, self._zfar = float(znear), float(zfar)
        self.cull = True
        self.default_lighting = (
            DEFAULT_SUN_AZIMUTH_DEG,
            DEFAULT_SUN_ELEVATION_DEG,
            float(sun_intensity),
            float(ambient),
        )
        pyrender, self.backend = load_pyrender()
        self.width, self.height = int(width), int(height)
        self._flags = pyrender.RenderFlags
        try:
            self._gl = pyrender.OffscreenRenderer(self.width, self.height)
        except Exception as exc:  # context creation failures come in many exception types
            raise RuntimeError(
                f"could not create an off-screen OpenGL context with the {self.backend} backend "
                f"({type(exc).__name__}: {exc}). Install the GL libraries with: "
                f"{install_hint(BACKENDS[self.backend])}, or choose the other backend with "
                "CADSIM_GL_BACKEND=osmesa|egl"
            ) from exc
        self._rows_reversed = self.backend in ROWS_REVERSED
        self._gl._platform.make_current()
        self.gl: dict = gl_identity(self.backend)  # backend, vendor, renderer: for the manifest
        use_lambert_shading(pyrender, self._gl)
        self._scene = ObjectScene(
            pyrender,
            ground_color=ground_color,
            background=background,
            ambient=ambient,
            sun_intensity=sun_intensity,
        )
        self._camera = pyrender.IntrinsicsCamera(
            fx=1.0, fy=1.0, cx=self.width / 2, cy=self.height / 2, znear=znear, zfar=zfar
        )
        log.debug("Renderer %dx%d on %s", self.width, self.height, self.backend)

    def render(
        self, snapshot: Snapshot, camera: Camera, exclude_ids: Collection[str] = ()
    ) -> RenderedView:
        """Render ``snapshot`` from ``camera``; objects in ``exclude_ids`` (e.g. the observer's own
        vehicle) are left out of this view. Returns colour, depth (metres along the optical axis,
        0 = no hit) and the instance map (index into ``snapshot.objects``, -1 = background)."""
        if self._gl is None:
            raise RuntimeError("Renderer.render called after close()")
        if (camera.width, camera.height) != (self.width, self.height):
            raise ValueError(
                f"camera image size {camera.width}x{camera.height} differs from the renderer's "
                f"{self.width}x{self.height}"
            )
        nodes = self._scene.sync(snapshot)
        K = camera.intrinsics()
        cam = self._camera
        cam.fx, cam.fy, cam.cx, cam.cy = K[0, 0], K[1, 1], K[0, 2], K[1, 2]
        self._scene.place_camera(cam, camera.pose_gl())
        seg_map = {node: index_color(i) for i, node in enumerate(nodes)}
        if self._scene.ground is not None:
            seg_map[self._scene.ground] = (0, 0, 0)
        scene = self._scene.scene
        self._scene.hide([*exclude_ids, *self._culled(snapshot, nodes, camera)])
        try:
            color, _ = self._gl.render(scene, flags=self._flags.NONE)
            seg, depth = self._gl.render(scene, flags=self._flags.SEG, seg_node_map=seg_map)
        finally:
            self._scene.unhide()
        if self._rows_reversed:  # drawn top row first, as OSMesa draws (cadsim.render.shims)
            color, seg, depth = color[::-1], seg[::-1], depth[::-1]
        return RenderedView(
            color=np.ascontiguousarray(color[..., :3]),
            depth=np.ascontiguousarray(depth, dtype=np.float32),
            instance=decode_instances(seg),
        )

    def set_lighting(
        self, azimuth_deg: float, elevation_deg: float, sun_intensity: float, ambient: float
    ) -> None:
        """Move the sun (azimuth CCW from +x, elevation; degrees) and set the sun's intensity and
        the ambient level (``cadsim.render.appearance``: an episode's illumination)."""
        self._scene.set_lighting(azimuth_deg, elevation_deg, sun_intensity, ambient)

    def _culled(self, snapshot: Snapshot, nodes: list, camera: Camera) -> list[str]:
        """Ids of the objects wholly outside ``camera``'s frustum (:mod:`frustum_culling`)."""
        if not self.cull or not nodes:
            return []
        bounds = np.stack([node.mesh.bounds for node in nodes])
        matrices = np.stack([node.matrix for node in nodes])
        corners = box_corners_world(bounds, matrices)
        cam = camera.world_to_camera(corners.reshape(-1, 3)).reshape(corners.shape)
        outside = outside_frustum(
            cam, camera.width, camera.height, camera.fx, self._znear, self._zfar
        )
        return [obj.id for obj, out in zip(snapshot.objects, outside, strict=True) if out]

    def close(self) -> None:
        """Free the GL context (idempotent)."""
        if self._gl is not None:
            self._gl.delete()
            self._gl = None

    def __enter__(self) -> Renderer:
        return self

    def __exit__(self, *exc) -> None:
        self.close()
