"""Off-screen rendering of world snapshots (pyrender on the CPU: OSMesa or EGL).

Heavy parts are imported lazily: importing this package (e.g. for ``RenderedView`` or
``select_backend``) neither binds the OpenGL platform nor loads trimesh. The first access to
``Renderer`` runs ``select_backend`` before OpenGL is imported.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from cadsim.render.backend import select_backend
from cadsim.render.view import RenderedView

if TYPE_CHECKING:
    from cadsim.render.meshes import MeshSpec, Part, register_mesh, registered_shapes
    from cadsim.render.renderer import Renderer

__all__ = [
    "MeshSpec",
    "Part",
    "RenderedView",
    "Renderer",
    "register_mesh",
    "registered_shapes",
    "select_backend",
]

_LAZY = {
    "Renderer": "cadsim.render.renderer",
    "MeshSpec": "cadsim.render.meshes",
    "Part": "cadsim.render.meshes",
    "register_mesh": "cadsim.render.meshes",
    "registered_shapes": "cadsim.render.meshes",
}


def __getattr__(name: str):
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module 'cadsim.render' has no attribute {name!r}")
    import importlib

    return getattr(importlib.import_module(module), name)
