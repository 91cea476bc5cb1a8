"""The "robot" mesh of the MRC arena, built from trimesh primitives, and its registration.

Contract as in ``cadsim.render.meshes``: the builder returns coloured ``Part``s in the object frame
(x forward, y left, z up, metres), centred on the bounding-box centre and filling exactly the
object's (length, width, height) box. It is registered size-dependent, so it builds in metres and
wheels stay round whatever the robot's proportions.

A robot is four dark wheels, a chassis and a top plate in the body colour (``WorldObject.color``),
a dark sensor column, and a marker plate on top towards the front in the marker colour (the
object's ``variant``: any matplotlib colour name). All robots share the geometry; the marker, a few
percent of the visible surface, is what tells the groups apart: look-alike, not identical.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import trimesh
from matplotlib.colors import to_rgb

from cadsim.render.mesh_parts import RGB, MeshSpec, Part
from cadsim.render.meshes import register_mesh, registered_shapes

WHEEL_RGB: RGB = (0.05, 0.05, 0.05)
COLUMN_RGB: RGB = (0.10, 0.10, 0.11)
_SECTIONS = 24


def marker_rgb(variant: str) -> RGB:
    """The marker colour of a robot variant (a matplotlib colour name); ValueError if unknown."""
    try:
        r, g, b = to_rgb(variant)
    except ValueError:
        raise ValueError(
            f"robot variant {variant!r} is not a colour name (e.g. 'tab:red')"
        ) from None
    return (float(r), float(g), float(b))


def _box(extents: Sequence[float], center: Sequence[float], color: RGB) -> Part:
    m = trimesh.creation.box(extents=extents)
    m.apply_translation(center)
    return Part(m, tuple(float(c) for c in color))


def _cylinder(
    radius: float, length: float, center: Sequence[float], axis_y: bool, color: RGB
) -> Part:
    m = trimesh.creation.cylinder(radius=radius, height=length, sections=_SECTIONS)
    if axis_y:
        m.apply_transform(trimesh.transformations.rotation_matrix(np.pi / 2, [1, 0, 0]))
    m.apply_translation(center)
    return Part(m, color)


def robot_parts(size: Sequence[float], body: RGB, marker: RGB) -> list[Part]:
    """A wheeled ground robot filling the box ``size`` = (length, width, height), metres."""
    L, W, H = (float(v) for v in size)
    z0 = -H / 2.0
    r_wheel, t_wheel = 0.2 * H, 0.14 * W
    parts = [
        _cylinder(
            r_wheel,
            t_wheel,
            (sx * (L / 2 - r_wheel), sy * (W / 2 - t_wheel / 2), z0 + r_wheel),
            True,
            WHEEL_RGB,
        )
        for sx in (-1.0, 1.0)
        for sy in (-1.0, 1.0)
    ]
    chassis_h, column_h, plate_h, marker_h = 0.38 * H, 0.32 * H, 0.06 * H, 0.16 * H
    parts += [
        _box((L, W - 2 * t_wheel, chassis_h), (0, 0, z0 + 0.08 * H + chassis_h / 2), body),
        _cylinder(
            0.22 * min(L, W),
            column_h,
            (-0.1 * L, 0, z0 + 0.46 * H + column_h / 2),
            False,
            COLUMN_RGB,
        ),
        _box((0.8 * L, 0.72 * W, plate_h), (0, 0, z0 + 0.78 * H + plate_h / 2), body),
        _box((0.34 * L, 0.5 * W, marker_h), (0.15 * L, 0, z0 + 0.84 * H + marker_h / 2), marker),
    ]
    return parts


def build_robot(spec: MeshSpec) -> list[Part]:
    """Mesh builder for shape "robot": body colour = spec.color, marker colour = spec.variant."""
    return robot_parts(spec.size, spec.color, marker_rgb(spec.variant))


def register_robot_mesh() -> None:
    """Make the renderer draw shape "robot" (idempotent)."""
    if "robot" not in registered_shapes():
        register_mesh("robot", build_robot, size_dependent=True)


register_robot_mesh()
