"""Cheaper lighting for the colour pass: a Lambertian fragment shader in place of pyrender's PBR one.

pyrender's ``mesh.frag`` evaluates a metallic-roughness BRDF per fragment, which dominates the cost
of the colour pass on llvmpipe. For appearance features (HOG, colour histograms) a diffuse sun plus
ambient light is enough. ``use_lambert_shading`` swaps the shader in one pyrender renderer's program
cache; everything else (vertex shader, segmentation and depth passes) stays pyrender's own.
"""

from __future__ import annotations

import os
from types import ModuleType

LAMBERT_FRAG = os.path.join(
    os.path.dirname(os.path.dirname(__file__)), "assets", "shaders", "lambert.frag"
)


def use_lambert_shading(pyrender: ModuleType, offscreen_renderer) -> None:
    """Make ``offscreen_renderer`` (a pyrender.OffscreenRenderer) shade meshes with lambert.frag."""
    from pyrender.shader_program import ShaderProgramCache

    class LambertProgramCache(ShaderProgramCache):
        def get_program(self, vertex_shader, fragment_shader, geometry_shader=None, defines=None):
            if fragment_shader == "mesh.frag":
                fragment_shader = LAMBERT_FRAG  # os.path.join keeps an absolute path as is
            return super().get_program(vertex_shader, fragment_shader, geometry_shader, defines)

    inner = offscreen_renderer._renderer
    inner._program_cache.clear()
    inner._program_cache = LambertProgramCache()
