"""Registry of mesh builders: one builder per object ``shape``; the only place shapes become geometry.

A builder takes a ``MeshSpec`` and returns coloured ``Part``s in the object frame (x forward, y left,
z up, metres, origin at the object's bounding-box centre; "forward" = a vehicle's front, the face of
a traffic-light head or sign). Two kinds of builders:

- scalable (default): the builder gets ``spec.size == (1, 1, 1)`` and must fill the unit box
  [-0.5, 0.5]^3; each object's node is scaled by its (length, width, height). One mesh per
  (shape, variant, state, colour), shared by all objects that look alike.
- size-dependent (``size_dependent=True``, e.g. a pole whose head must not stretch): the builder
  gets the object's size and builds in metres; one mesh per distinct size as well.

Add a shape with ``register_mesh("robot", build_robot)``; see ``cadsim.render.builtin_meshes``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cadsim.render.builtin_meshes import BUILTIN_BUILDERS
from cadsim.render.mesh_parts import RGB, MeshBuilder, MeshSpec, Part
from cadsim.world import WorldObject

__all__ = [
    "RGB",
    "MeshBuilder",
    "MeshSpec",
    "Part",
    "mesh_spec",
    "register_mesh",
    "registered_shapes",
]

MIN_SIZE_M = 1e-3


@dataclass(frozen=True)
class _Entry:
    builder: MeshBuilder
    size_dependent: bool


_REGISTRY: dict[str, _Entry] = {}
_builtins_loaded = False


def register_mesh(
    shape: str, builder: MeshBuilder, *, size_dependent: bool = False, replace: bool = False
) -> None:
    """Register ``builder`` for objects whose ``shape`` is ``shape`` (see the module docstring)."""
    _load_builtins()
    if shape in _REGISTRY and not replace:
        raise ValueError(f"mesh shape {shape!r} is already registered (pass replace=True)")
    _REGISTRY[shape] = _Entry(builder, size_dependent)


def registered_shapes() -> list[str]:
    """Shapes the renderer can draw, sorted."""
    _load_builtins()
    return sorted(_REGISTRY)


def _load_builtins() -> None:
    global _builtins_loaded
    if _builtins_loaded:
        return
    _builtins_loaded = True
    for shape, (builder, size_dependent) in BUILTIN_BUILDERS.items():
        _REGISTRY.setdefault(shape, _Entry(builder, size_dependent))


def mesh_spec(obj: WorldObject) -> MeshSpec:
    """The spec (and cache key) of the mesh that draws ``obj``; colours rounded to 1/1000 and sizes
    to millimetres so that look-alike objects share one mesh."""
    _load_builtins()
    entry = _REGISTRY.get(obj.shape)
    if entry is None:
        raise KeyError(
            f"object {obj.id!r} has shape {obj.shape!r}, which no mesh builder handles; "
            f"registered shapes: {', '.join(sorted(_REGISTRY))} (add one with register_mesh)"
        )
    color = tuple(round(float(c), 3) for c in obj.color)
    if entry.size_dependent:
        size = tuple(max(round(float(s), 3), MIN_SIZE_M) for s in obj.size)
    else:
        size = (1.0, 1.0, 1.0)
    return MeshSpec(obj.shape, obj.variant, obj.state, color, size)


def node_scale(obj: WorldObject) -> np.ndarray:
    """(3,) scale applied to the object's node: its size for scalable shapes, 1 otherwise. Sizes
    are floored at 1 mm: a zero scale would make the normal matrix singular (NaN shading)."""
    _load_builtins()
    if _REGISTRY[obj.shape].size_dependent:
        return np.ones(3)
    return np.maximum(np.asarray(obj.size, dtype=float), MIN_SIZE_M)


def build_parts(spec: MeshSpec) -> list[Part]:
    """Run the registered builder for ``spec``; checks that it returned non-empty parts."""
    _load_builtins()
    parts = _REGISTRY[spec.shape].builder(spec)
    if not parts or any(len(p.mesh.faces) == 0 for p in parts):
        raise ValueError(f"mesh builder for shape {spec.shape!r} returned an empty part list/mesh")
    return parts
