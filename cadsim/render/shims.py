"""Run-time fixes for pyrender on CPU, applied before pyrender is imported (see docs/rendering.md).

1. PyOpenGL >= 3.1.5 on OSMesa: ``OpenGL.contextdata.getContext()`` returns a fresh ctypes pointer
   object on every call, and these compare unequal. pyrender keys its shader-program cache on that
   value, so every primitive's shader is recompiled on every draw (~4 fps, and the cache grows by
   gigabytes). The fix makes getContext return the pointer's integer address, which is stable.
2. numpy 2 removed ``np.infty``; pyrender 0.1.45 still uses it (pyrender-maintained does not). The
   alias is restored only if missing, so either pyrender works.
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
