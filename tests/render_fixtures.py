"""Shared small-scene helpers for the rendering and detection tests (320×240 images); the
`renderer` fixture is in conftest.py."""

from cadsim.camera import Camera

W, H = 320, 240


def cam(**kw) -> Camera:
    """A W×H camera at 1.6 m looking east unless overridden."""
    kw.setdefault("position", (0.0, 0.0, 1.6))
    kw.setdefault("yaw", 0.0)
    return Camera(width=W, height=H, **kw)
