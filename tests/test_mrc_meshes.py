"""The robot mesh: fills its box, look-alike variants differ only in the marker's colour."""

from __future__ import annotations

import numpy as np
import pytest

from cadsim.render.meshes import MeshSpec, build_parts, mesh_spec, registered_shapes
from cadsim.sources.arena.robot_meshes import marker_rgb
from cadsim.world import WorldObject

SIZE = (0.45, 0.38, 0.32)
BODY = (0.16, 0.16, 0.18)


def robot(variant: str) -> WorldObject:
    return WorldObject("r", "robot", "robot", (0, 0, 0.16), 0.0, SIZE, BODY, variant=variant)


def test_robot_shape_is_registered_and_fills_its_box():
    assert "robot" in registered_shapes()
    parts = build_parts(mesh_spec(robot("tab:red")))
    bounds = np.array([p.mesh.bounds for p in parts])
    np.testing.assert_allclose(bounds[:, 0].min(axis=0), -np.array(SIZE) / 2, atol=1e-9)
    np.testing.assert_allclose(bounds[:, 1].max(axis=0), np.array(SIZE) / 2, atol=1e-9)
    assert all(p.mesh.is_watertight for p in parts)


def test_variants_differ_only_in_a_small_marker():
    red = build_parts(mesh_spec(robot("tab:red")))
    blue = build_parts(mesh_spec(robot("tab:blue")))
    assert len(red) == len(blue)
    differing = [i for i, (a, b) in enumerate(zip(red, blue, strict=True)) if a.color != b.color]
    assert len(differing) == 1
    (k,) = differing
    assert red[k].color == pytest.approx(marker_rgb("tab:red"))
    assert blue[k].color == pytest.approx(marker_rgb("tab:blue"))
    for a, b in zip(red, blue, strict=True):
        np.testing.assert_array_equal(a.mesh.vertices, b.mesh.vertices)
    # The marker is seen from above; it covers a small part of the robot's top-down footprint.
    marker_top = np.prod(red[k].mesh.extents[:2])
    assert marker_top / (SIZE[0] * SIZE[1]) < 0.2
    assert red[k].mesh.bounds[1, 2] == pytest.approx(SIZE[2] / 2)  # on top: visible from above


def test_unknown_variant_is_named():
    with pytest.raises(ValueError, match="'plaid' is not a colour name"):
        build_parts(MeshSpec("robot", "plaid", "", BODY, SIZE))
