"""The 3-D models shipped in SUMO's wheel (``$SUMO_HOME/data/3D/*.obj``), as coloured parts.

The OBJ files are y-up at roughly unit scale. Vehicles and the person face +z (head lights at +z),
traffic-light heads face -x. They are rotated here, once, into the object frame (x forward, y left,
z up). Materials become flat part colours; the material named by ``body_materials`` takes the
object's own colour. Models are read once per process and cached.
"""

from __future__ import annotations

import logging
import os
from functools import cache

import numpy as np
import trimesh

from cadsim.render.mesh_parts import RGB, Part

log = logging.getLogger(__name__)

# Model axes -> object axes. Rows: object x (forward), y (left), z (up) in model coordinates.
_FACING_PLUS_Z = np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
_FACING_MINUS_X = np.array([[-1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, 1.0, 0.0]])
FACING = {"+z": _FACING_PLUS_Z, "-x": _FACING_MINUS_X}

BODY = "__body__"  # marks parts painted in the object's own colour at build time


def models_dir() -> str | None:
    """``$SUMO_HOME/data/3D`` if the SUMO wheel (or SUMO_HOME) provides it, else None."""
    home = os.environ.get("SUMO_HOME")
    if not home:
        try:
            import sumo

            home = sumo.SUMO_HOME
        except ImportError:
            return None
    path = os.path.join(home, "data", "3D")
    return path if os.path.isdir(path) else None


@cache
def _load(name: str, facing: str, body_materials: tuple[str, ...]) -> tuple | None:
    folder = models_dir()
    path = os.path.join(folder, name) if folder else None
    if path is None or not os.path.exists(path):
        log.warning("SUMO 3-D model %s not found; using primitive geometry", name)
        return None
    loaded = trimesh.load(path, force="scene", process=False)
    R = np.eye(4)
    R[:3, :3] = FACING[facing]
    parts = []
    for geom_name, geom in loaded.geometry.items():
        mesh = trimesh.Trimesh(geom.vertices, geom.faces, process=False)
        mesh.apply_transform(R)
        material = getattr(geom.visual, "material", None)
        if any(b in geom_name for b in body_materials):
            color: RGB | str = BODY
        elif material is not None and getattr(material, "diffuse", None) is not None:
            color = tuple(float(c) / 255.0 for c in material.diffuse[:3])
        else:
            color = BODY
        parts.append((geom_name, mesh, color))
    return tuple(parts)


def sumo_model(
    name: str, facing: str, body_color: RGB, body_materials: tuple[str, ...] = ()
) -> list[tuple[str, Part]] | None:
    """(material name, part) pairs of model ``name`` in the object frame (not yet fitted to a box),
    with ``body_materials`` (substrings of material names; all parts if a material has no colour)
    coloured ``body_color``. None if the model is not available."""
    loaded = _load(name, facing, tuple(body_materials))
    if loaded is None:
        return None
    return [
        (geom_name, Part(mesh.copy(), body_color if color == BODY else color))
        for geom_name, mesh, color in loaded
    ]
