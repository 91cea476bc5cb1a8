"""Mesh builders for the built-in object shapes (see ``cadsim.render.meshes`` for the contract).

SUMO's own models draw cars, vans, persons and traffic lights; trimesh primitives draw the rest
(bus, truck, bicycle, sign, building, road, box, cylinder, cone, tree). Objects are closed solids, so
back faces can be culled.
"""

from __future__ import annotations

import numpy as np
import trimesh

from cadsim.render.mesh_parts import RGB, MeshBuilder, MeshSpec, Part, fit_to_box, transformed
from cadsim.render.sumo_models import sumo_model

GLASS: RGB = (0.16, 0.22, 0.30)
TYRE: RGB = (0.05, 0.05, 0.05)
METAL: RGB = (0.45, 0.45, 0.47)
HOUSING: RGB = (0.08, 0.08, 0.08)
SKIN: RGB = (0.85, 0.67, 0.52)
UNLIT: RGB = (0.12, 0.12, 0.12)


def box(extents, center, color: RGB) -> Part:
    """Axis-aligned box part (object frame, metres)."""
    m = trimesh.creation.box(extents=extents)
    m.apply_translation(center)
    return Part(m, color)


def cylinder(radius: float, length: float, center, axis: str, color: RGB, sections: int = 16):
    """Cylinder part along object axis ``axis`` ("x", "y" or "z")."""
    m = trimesh.creation.cylinder(radius=radius, height=length, sections=sections)
    if axis == "x":
        m.apply_transform(trimesh.transformations.rotation_matrix(np.pi / 2, [0, 1, 0]))
    elif axis == "y":
        m.apply_transform(trimesh.transformations.rotation_matrix(np.pi / 2, [1, 0, 0]))
    m.apply_translation(center)
    return Part(m, color)


def _box_fallback(spec: MeshSpec) -> list[Part]:
    return [box((1.0, 1.0, 1.0), (0.0, 0.0, 0.0), spec.color)]


def _sumo_vehicle(model: str):
    def build(spec: MeshSpec) -> list[Part]:
        parts = sumo_model(model, "+z", spec.color, body_materials=("carmaterial", "bodyColor"))
        if parts is None:
            return _box_fallback(spec)
        return fit_to_box([p for _, p in parts])

    return build


def build_person(spec: MeshSpec) -> list[Part]:
    """SUMO's standing person in the object's colour, head and hands skin-coloured (top 13 %)."""
    parts = sumo_model("humanResting.obj", "+z", spec.color, body_materials=("",))
    if parts is None:
        return [cylinder(0.5, 1.0, (0, 0, 0), "z", spec.color)]
    parts = fit_to_box([p for _, p in parts])
    out = []
    for p in parts:
        face_z = p.mesh.triangles_center[:, 2]
        head = face_z > 0.37
        for mask, color in ((~head, p.color), (head, SKIN)):
            if mask.any():
                out.append(Part(p.mesh.submesh([np.flatnonzero(mask)], append=True), color))
    return out


def _wheels(length: float, width: float, height: float, radius: float, axles) -> list[Part]:
    z = -height / 2 + radius
    return [
        cylinder(radius, 0.3, (x, s * (width / 2 - 0.15), z), "y", TYRE)
        for x in axles
        for s in (-1.0, 1.0)
    ]


def build_bus(spec: MeshSpec) -> list[Part]:
    """Box body in the object's colour, a glass band round it, windscreen and wheels (metres)."""
    L, W, H = spec.size
    r = min(0.5, 0.16 * H)
    base = -H / 2 + 0.5 * r
    body_h = H / 2 - base
    parts = [
        box((L, W, body_h), (0, 0, base + body_h / 2), spec.color),
        box((L * 0.9, W + 0.02, 0.3 * H), (-0.02 * L, 0, 0.17 * H), GLASS),
        box((0.02, W * 0.85, 0.45 * H), (L / 2 + 0.005, 0, 0.1 * H), GLASS),
    ]
    return parts + _wheels(L, W, H, r, (L / 2 - 0.22 * L, -L / 2 + 0.2 * L))


def build_truck(spec: MeshSpec) -> list[Part]:
    """Cab (object colour) with windscreen, a grey-white cargo box behind it, wheels (metres)."""
    L, W, H = spec.size
    r = min(0.5, 0.15 * H)
    cab_l = min(2.2, 0.3 * L)
    cab_h = 0.8 * H
    floor = -H / 2 + 1.6 * r
    x_cab = L / 2 - cab_l / 2
    parts = [
        box(
            (cab_l, W, cab_h - 0.6 * r),
            (x_cab, 0, -H / 2 + 0.6 * r + (cab_h - 0.6 * r) / 2),
            spec.color,
        ),
        box((0.02, W * 0.85, 0.3 * H), (L / 2 + 0.005, 0, -H / 2 + cab_h - 0.2 * H), GLASS),
        box(
            (L - cab_l - 0.15, W, H / 2 - floor),
            (-cab_l / 2 - 0.075, 0, (floor + H / 2) / 2),
            (0.82, 0.82, 0.80),
        ),
        box((L - 0.2, W * 0.6, 0.25), (0, 0, -H / 2 + r), METAL),
    ]
    return parts + _wheels(L, W, H, r, (x_cab, -L / 2 + 0.25 * L, -L / 2 + 0.12 * L))


def build_bicycle(spec: MeshSpec) -> list[Part]:
    """Two wheels, a frame in the object's colour and a rider (SUMO person) on top (metres)."""
    L, W, H = spec.size
    r = min(0.35, 0.22 * L)
    zw = -H / 2 + r
    frame = [cylinder(r, 0.06, (x, 0, zw), "y", TYRE, sections=20) for x in (L / 2 - r, -L / 2 + r)]
    frame.append(box((L - 2 * r, 0.06, 0.06), (0, 0, zw + 0.25 * r), spec.color))
    frame.append(box((0.06, 0.06, 1.3 * r), (-0.1 * L, 0, zw + 0.7 * r), spec.color))
    rider_h = max(H - (zw + 1.3 * r + H / 2) + 0.25, 0.5 * H)
    rider = build_person(MeshSpec("person", "", "", spec.color, (1, 1, 1)))
    rider = fit_to_box(rider, (0.45, min(W, 0.55), rider_h))
    T = np.eye(4)
    T[:3, 3] = (-0.05 * L, 0, H / 2 - rider_h / 2)
    return frame + transformed(rider, T)


_LIT_LAMPS = {"r": "tlr", "s": "tlr", "y": "tly", "G": "tlg", "g": "tlg", "u": "tlu"}


def build_traffic_light(spec: MeshSpec) -> list[Part]:
    """SUMO's pole and signal head (lamps facing +x); ``state`` (a SUMO signal character) picks the
    lit lamp, drawn in the object's colour; other states show all lamps off (metres)."""
    L, W, H = spec.size
    model = _LIT_LAMPS.get(spec.state, "tlr")
    lit = spec.state in _LIT_LAMPS
    head = sumo_model(f"{model}.obj", "-x", HOUSING)
    head_h = min(1.0, 0.35 * H)
    pole_top = H / 2 - head_h
    pole = cylinder(
        min(0.07, 0.3 * W), pole_top + H / 2, (0, 0, (pole_top - H / 2) / 2), "z", METAL
    )
    if head is None:
        return [
            pole,
            box((min(L, 0.35), min(W, 0.35), head_h), (0, 0, H / 2 - head_h / 2), HOUSING),
        ]
    parts = [
        Part(
            p.mesh,
            (spec.color if lit else UNLIT) if name in ("Red", "Yellow", "Green") else HOUSING,
        )
        for name, p in head
    ]
    scale = head_h / 1.24  # the head model is 1.24 units tall; keep its proportions
    parts = fit_to_box(parts, (0.34 * scale, 0.30 * scale, head_h))
    T = np.eye(4)
    T[:3, 3] = (0.0, 0.0, H / 2 - head_h / 2)
    return [pole] + transformed(parts, T)


_PLATE_SECTIONS = {"stop": 8, "yield": 3, "priority": 4, "priority_road": 4, "square": 4}


def build_sign(spec: MeshSpec) -> list[Part]:
    """A pole and a plate facing +x in the object's colour; ``variant`` picks the plate outline:
    "stop" (octagon), "yield" (triangle), "priority"/"priority_road" (diamond), "square" (4 sides),
    else round (metres)."""
    L, W, H = spec.size
    plate_d = min(W, 0.9, 0.4 * H)
    sections = _PLATE_SECTIONS.get(spec.variant, 24)
    plate = cylinder(plate_d / 2, min(L, 0.04), (0, 0, 0), "x", spec.color, sections=sections)
    # The plate's first vertex points down; turn it so that "stop" has a flat top and "square"
    # straight sides ("yield" keeps its point down, "priority" stays a diamond).
    turn = {"stop": np.pi / 8, "square": np.pi / 4}.get(spec.variant, 0.0)
    if turn:
        plate = transformed([plate], trimesh.transformations.rotation_matrix(turn, [1, 0, 0]))[0]
    zc = H / 2 - plate_d / 2
    plate = transformed([plate], trimesh.transformations.translation_matrix((min(L, 0.04), 0, zc)))[
        0
    ]
    pole = cylinder(0.04, H - plate_d / 2, (-0.02, 0, -plate_d / 4), "z", METAL)
    return [pole, plate]


def build_box(spec: MeshSpec) -> list[Part]:
    """Unit box in the object's colour (buildings, road slabs, generic boxes)."""
    return [box((1.0, 1.0, 1.0), (0.0, 0.0, 0.0), spec.color)]


def build_cylinder(spec: MeshSpec) -> list[Part]:
    """Unit upright cylinder in the object's colour."""
    return [cylinder(0.5, 1.0, (0, 0, 0), "z", spec.color, sections=20)]


def build_cone(spec: MeshSpec) -> list[Part]:
    """Traffic cone: a cone in the object's colour on a dark square base, a white band."""
    cone = trimesh.creation.cone(radius=0.42, height=0.92, sections=20)
    cone.apply_translation((0, 0, -0.42))
    band = trimesh.creation.cylinder(radius=0.25, height=0.12, sections=20)
    band.apply_translation((0, 0, 0.02))
    return [
        Part(cone, spec.color),
        Part(band, (0.95, 0.95, 0.95)),
        box((1.0, 1.0, 0.08), (0, 0, -0.46), HOUSING),
    ]


def build_tree(spec: MeshSpec) -> list[Part]:
    """Street tree in the unit box: a brown trunk over the lower 45 %, a crown (a flattened
    icosphere in the object's colour) filling the upper part and the full width."""
    crown = trimesh.creation.icosphere(subdivisions=1, radius=1.0)
    crown.apply_scale((0.5, 0.5, 0.3))
    crown.apply_translation((0.0, 0.0, 0.2))
    trunk = cylinder(0.06, 0.5, (0.0, 0.0, -0.25), "z", (0.35, 0.24, 0.14), sections=10)
    return [trunk, Part(crown, spec.color)]


# shape -> (builder, size_dependent)
BUILTIN_BUILDERS: dict[str, tuple[MeshBuilder, bool]] = {
    "car": (_sumo_vehicle("car-normal-citrus.obj"), False),
    "van": (_sumo_vehicle("car-microcargo-citrus.obj"), False),
    "minibus": (_sumo_vehicle("car-minibus-citrus.obj"), False),
    "bus": (build_bus, True),
    "truck": (build_truck, True),
    "bicycle": (build_bicycle, True),
    "person": (build_person, False),
    "traffic_light": (build_traffic_light, True),
    "sign": (build_sign, True),
    "building": (build_box, False),
    "road": (build_box, False),
    "box": (build_box, False),
    "cylinder": (build_cylinder, False),
    "cone": (build_cone, False),
    "tree": (build_tree, False),
}
