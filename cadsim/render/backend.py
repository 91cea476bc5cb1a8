"""Choice of the off-screen OpenGL backend (OSMesa or EGL) and loading pyrender configured for it.

PyOpenGL binds its platform once per process, at the first ``import OpenGL``, from the environment
variable ``PYOPENGL_PLATFORM``. ``select_backend`` therefore only probes the system libraries with
ctypes (which does not import OpenGL), then sets the variable; ``load_pyrender`` does both and applies
the pyrender fixes from ``cadsim.render.shims`` before pyrender is imported.

Preference: OSMesa (exact depth, faster on CPU), then EGL. ``CADSIM_GL_BACKEND=osmesa|egl`` forces one.
Both draw the same bytes with Mesa's llvmpipe (EGL is made to rasterise as OSMesa does,
``cadsim.render.shims``); a vendor GPU's EGL driver rasterises its own way, and the manifest says
which driver drew a dataset (:func:`gl_identity`).
"""

from __future__ import annotations

import ctypes
import logging
import os
import sys
from dataclasses import dataclass
from types import ModuleType

log = logging.getLogger(__name__)

ENV_VAR = "CADSIM_GL_BACKEND"


@dataclass(frozen=True)
class BackendSpec:
    """What one backend needs: shared libraries (each a tuple of alternative sonames) and the
    Debian/Ubuntu packages that provide them."""

    name: str
    libraries: tuple[tuple[str, ...], ...]
    apt_packages: tuple[str, ...]


# Order = preference. Sonames as PyOpenGL looks them up (lib<name>.so[.N]).
BACKENDS: dict[str, BackendSpec] = {
    "osmesa": BackendSpec(
        "osmesa",
        libraries=(("libOSMesa.so.8", "libOSMesa.so.6", "libOSMesa.so"),),
        apt_packages=("libosmesa6",),
    ),
    "egl": BackendSpec(
        "egl",
        libraries=(
            ("libEGL.so.1", "libEGL.so"),
            ("libGL.so.1", "libGL.so", "libOpenGL.so.0"),
        ),
        apt_packages=("libegl1", "libegl-mesa0", "libgl1-mesa-dri"),
    ),
}


ROWS_REVERSED = frozenset({"egl"})
"""Backends drawn as OSMesa draws (:func:`cadsim.render.shims.match_osmesa_rasterisation`),
whose images pyrender returns with their rows reversed."""


def _missing_libraries(spec: BackendSpec) -> list[str]:
    """Sonames (first alternative of each group) that cannot be loaded with ctypes."""
    missing = []
    for alternatives in spec.libraries:
        for soname in alternatives:
            try:
                ctypes.CDLL(soname)
                break
            except OSError:
                continue
        else:
            missing.append(alternatives[0])
    return missing


def install_hint(spec: BackendSpec) -> str:
    return f"sudo apt-get update && sudo apt-get install -y {' '.join(spec.apt_packages)}"


def select_backend() -> str:
    """Pick the off-screen GL backend, set ``PYOPENGL_PLATFORM`` and return "osmesa" or "egl".

    Honours ``CADSIM_GL_BACKEND``. If OpenGL is already imported in this process its platform is
    fixed; that platform is returned (or an error raised if a different one is requested). Raises
    RuntimeError naming the missing library and the apt-get command that installs it.
    """
    requested = os.environ.get(ENV_VAR, "").strip().lower()
    if requested and requested not in BACKENDS:
        raise RuntimeError(
            f"{ENV_VAR}={os.environ[ENV_VAR]!r} is not a known GL backend; "
            f"expected one of {', '.join(BACKENDS)} (or leave it unset to choose automatically)"
        )
    current = os.environ.get("PYOPENGL_PLATFORM", "").strip().lower()
    if "OpenGL" in sys.modules:
        if current not in BACKENDS:
            raise RuntimeError(
                f"OpenGL was imported before cadsim chose a backend (PYOPENGL_PLATFORM={current!r}); "
                "import cadsim.render before anything that imports OpenGL or pyrender"
            )
        if requested and requested != current:
            raise RuntimeError(
                f"{ENV_VAR}={requested!r} but OpenGL is already bound to {current!r} in this "
                "process; the GL platform cannot change after OpenGL is imported"
            )
        return current
    if requested:
        candidates = [requested]
    elif current in BACKENDS:
        candidates = [current]  # the user chose one via PyOpenGL's own variable
    else:
        candidates = list(BACKENDS)
    problems = []
    for name in candidates:
        spec = BACKENDS[name]
        missing = _missing_libraries(spec)
        if not missing:
            os.environ["PYOPENGL_PLATFORM"] = name
            log.debug("GL backend: %s", name)
            return name
        problems.append(
            f"{name}: cannot load {', '.join(missing)} (install with: {install_hint(spec)})"
        )
    raise RuntimeError(
        "no off-screen OpenGL backend is usable for rendering. " + "; ".join(problems)
    )


def load_pyrender() -> tuple[ModuleType, str]:
    """Select the backend, apply the pyrender/PyOpenGL fixes and import pyrender.

    Returns (pyrender module, backend name)."""
    backend = select_backend()
    from cadsim.render.shims import apply_shims, match_osmesa_rasterisation

    apply_shims()
    import pyrender
    import pyrender.renderer

    if backend in ROWS_REVERSED:  # one rasterisation on every backend: OSMesa's
        match_osmesa_rasterisation(pyrender.renderer)
    return pyrender, backend


SOFTWARE_RENDERERS = ("llvmpipe", "softpipe", "swrast", "lavapipe")
"""Mesa's CPU rasterisers (``GL_RENDERER`` starts with one of these): the ones that give the
reference bytes."""


def gl_identity(backend: str) -> dict:
    """The current GL context's backend, ``GL_VENDOR``, ``GL_RENDERER`` and ``GL_VERSION``, and
    whether it is a vendor GPU driver (not one of Mesa's CPU rasterisers) — for the manifest."""
    from OpenGL.GL import GL_RENDERER, GL_VENDOR, GL_VERSION, glGetString

    def text(name) -> str:
        value = glGetString(name)
        return value.decode("utf-8", "replace") if isinstance(value, bytes) else str(value)

    renderer = text(GL_RENDERER)
    return {
        "backend": backend,
        "vendor": text(GL_VENDOR),
        "renderer": renderer,
        "version": text(GL_VERSION),
        "gpu_driver": not renderer.lower().startswith(SOFTWARE_RENDERERS),
    }
