"""What a mesh builder receives and returns (:class:`MeshSpec` -> :class:`Part` list), and the
geometry helpers builders share. The registry (``cadsim.render.meshes``) and the builders
(``builtin_meshes``, ``sumo_models``, a source's own meshes) import this module; it imports none
of them."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import trimesh

RGB = tuple[float, float, float]


@dataclass(frozen=True)
class MeshSpec:
    """What a builder may look at. color: the object's sRGB colour in [0, 1]. size: (length, width,
    height) metres, or (1, 1, 1) for scalable builders."""

    shape: str
    variant: str
    state: str
    color: RGB
    size: tuple[float, float, float]


@dataclass(frozen=True)
class Part:
    """A piece of a mesh with one flat sRGB colour in [0, 1]."""

    mesh: trimesh.Trimesh
    color: RGB


MeshBuilder = Callable[[MeshSpec], list[Part]]


def fit_to_box(parts: list[Part], size: tuple[float, float, float] = (1.0, 1.0, 1.0)) -> list[Part]:
    """Translate and scale (per axis) ``parts`` together so that their joint bounding box is centred
    at the origin with extents ``size`` (object frame, metres)."""
    bounds = np.array([p.mesh.bounds for p in parts])
    lo, hi = bounds[:, 0].min(axis=0), bounds[:, 1].max(axis=0)
    extent = np.where(hi - lo > 1e-9, hi - lo, 1.0)
    T = np.diag(np.append(np.asarray(size, float) / extent, 1.0))
    T[:3, 3] = -(lo + hi) / 2.0 * T.diagonal()[:3]
    return transformed(parts, T)


def transformed(parts: list[Part], matrix: np.ndarray) -> list[Part]:
    """Copies of ``parts`` with the 4x4 ``matrix`` applied."""
    out = []
    for p in parts:
        m = p.mesh.copy()
        m.apply_transform(matrix)
        out.append(Part(m, p.color))
    return out
