"""Run-time fixes for pyrender on CPU, applied before pyrender is imported (see docs/rendering.md).

1. PyOpenGL >= 3.1.5 on OSMesa: ``OpenGL.contextdata.getContext()`` returns a fresh ctypes pointer
   object on every call, and these compare unequal. pyrender keys its shader-program cache on that
   value, so every primitive's shader is recompiled on every draw (~4 fps, and the cache grows by
   gigabytes). The fix makes getContext return the pointer's integer address, which is stable.
2. numpy 2 removed ``np.infty``; pyrender 0.1.45 still uses it (pyrender-maintained does not). The
   alias is restored only if missing, so either pyrender works.
3. On a framebuffer platform (EGL) pyrender draws into 4x multisampled off-screen buffers, with
   ``GL_MULTISAMPLE`` on for every pass but segmentation; OSMesa draws single-sampled into a
   window buffer, which Mesa fills top row first (a flipped viewport, the fill rule and winding
   to match). Either difference alone changes pixels: the colour pass's edges (multisampling),
   and one unit in the last place of 24-bit depth, hence a few edge pixels of every pass (the
   orientation). :func:`match_osmesa_rasterisation` (applied after pyrender is imported, on
   EGL only) removes both, so one scenario and seed give one dataset on either backend.
"""

from __future__ import annotations

import ctypes
import os

import numpy as np

_applied = False


def _stable_context_key(get_context):
    def get_context_stable(context=None):
        ctx = get_context(context)
        try:
            address = ctypes.cast(ctx, ctypes.c_void_p).value
        except (TypeError, ctypes.ArgumentError):
            return ctx
        return address if address else ctx

    get_context_stable.__wrapped__ = get_context
    return get_context_stable


def apply_shims() -> None:
    """Apply the fixes once per process. Requires ``PYOPENGL_PLATFORM`` to be set already."""
    global _applied
    if _applied:
        return
    if not hasattr(np, "infty"):
        np.infty = np.inf  # noqa: NPY201 - restores the alias old pyrender uses
    if os.environ.get("PYOPENGL_PLATFORM") == "osmesa":
        import OpenGL.contextdata as contextdata

        contextdata.getContext = _stable_context_key(contextdata.getContext)
    _applied = True


def match_osmesa_rasterisation(renderer_module) -> None:
    """Make pyrender's renderer module (``pyrender.renderer``) rasterise on a framebuffer
    platform (EGL) exactly as OSMesa does: its off-screen buffers allocated with 0 samples (an
    ordinary buffer, so its "resolve" blit is a copy), ``GL_MULTISAMPLE`` never enabled, and
    every pass drawn with the clip origin at the upper left (``glClipControl``), as Mesa draws
    into OSMesa's window buffer: the same window coordinates, depth plane equations, fill rule
    and winding. The image then comes out with its rows reversed; :class:`~cadsim.render.Renderer`
    puts them back. The names replaced are module globals bound by ``from OpenGL.GL import *``.
    Call it only on such a platform (on OSMesa the clip origin would turn its image over).
    Idempotent."""
    if getattr(renderer_module, "_cadsim_matches_osmesa", False):
        return
    from OpenGL.GL import GL_MULTISAMPLE, GL_NEGATIVE_ONE_TO_ONE, GL_UPPER_LEFT, glClipControl

    enable = renderer_module.glEnable
    storage = renderer_module.glRenderbufferStorageMultisample
    viewport = renderer_module.glViewport

    def gl_enable(capability):
        return None if capability == GL_MULTISAMPLE else enable(capability)

    def gl_renderbuffer_storage_single_sample(target, samples, internal_format, width, height):
        return storage(target, 0, internal_format, width, height)

    def gl_viewport_upper_left(*args):
        glClipControl(GL_UPPER_LEFT, GL_NEGATIVE_ONE_TO_ONE)
        return viewport(*args)

    renderer_module.glEnable = gl_enable
    renderer_module.glRenderbufferStorageMultisample = gl_renderbuffer_storage_single_sample
    renderer_module.glViewport = gl_viewport_upper_left
    renderer_module._cadsim_matches_osmesa = True
