"""Appearance realism (the scenario's ``[appearance]`` table): what makes one object look
different in two vehicles' cameras, as it does on real data.

With the table absent every view is rendered as before: one fixed sun, one ambient level, and
each camera's colours as the renderer produces them. With it:

- **illumination per episode**: the sun's azimuth uniform in [0°, 360°), its elevation uniform in
  ``sun_elevation_deg`` and its intensity in ``sun_intensity``, the ambient level uniform in
  ``ambient`` — drawn from the episode's simulation seed, so both views of a record share them
  (one world, one sky), but two vehicles see an object's lit and shaded sides differently;
- **per-camera exposure and white balance**: each view's linear colour times a gain
  exp(N(0, ``exposure_sigma``²)) (``exposure_sigma`` in natural-log units; 0.35 ≈ ½ stop) and,
  per channel, exp(N(0, ``white_balance_sigma``²)), then clipped — drawn per view from a child of
  its attribute stream.

Colour variety between instances of a class comes from the scenario's palette (the SUMO vehicle
types file, e.g. ``cad-v2x-vtypes.add.xml``: market shares of car colours, mostly white, grey,
black and silver). Imports numpy only.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from cadsim import portable_math as pm
from cadsim.config_tables import check_number, config_from_table

_LIGHT_STREAM = 11  # spawn key of the episode's illumination under its simulation seed
_CAMERA_CHILD = 10  # spawn-key suffix of a view's exposure stream under its attribute stream


@dataclass(frozen=True)
class Lighting:
    """One episode's light: sun azimuth and elevation (degrees; azimuth CCW from +x, the world's
    east), sun intensity and ambient level (the renderer's units)."""

    sun_azimuth_deg: float
    sun_elevation_deg: float
    sun_intensity: float
    ambient: float


@dataclass(frozen=True)
class AppearanceConfig:
    """The ``[appearance]`` table (module docstring). Ranges are [low, high]."""

    sun_elevation_deg: tuple[float, float] = (20.0, 70.0)
    sun_intensity: tuple[float, float] = (0.5, 0.9)
    ambient: tuple[float, float] = (0.3, 0.55)
    exposure_sigma: float = 0.0
    white_balance_sigma: float = 0.0

    def __post_init__(self) -> None:
        for key, (low, high) in (
            ("sun_elevation_deg", (1.0, 90.0)),
            ("sun_intensity", (0.0, 5.0)),
            ("ambient", (0.0, 2.0)),
        ):
            value = getattr(self, key)
            if not (isinstance(value, list | tuple) and len(value) == 2):
                raise ValueError(f"[appearance] {key}: expected [low, high], got {value!r}")
            for v in value:
                check_number("[appearance]", key, v, minimum=low, maximum=high)
            if value[0] > value[1]:
                raise ValueError(f"[appearance] {key}: expected low <= high, got {list(value)}")
        check_number(
            "[appearance]", "exposure_sigma", self.exposure_sigma, minimum=0.0, maximum=2.0
        )
        check_number(
            "[appearance]",
            "white_balance_sigma",
            self.white_balance_sigma,
            minimum=0.0,
            maximum=1.0,
        )

    @classmethod
    def from_table(cls, table: Mapping, where: str = "[appearance]") -> AppearanceConfig:
        """Build from a scenario-file table; unknown keys/bad values raise naming ``where``."""
        return config_from_table(cls, table, where, "[appearance]")

    def lighting(self, simulation_seed: int) -> Lighting:
        """The illumination of the episode simulated with ``simulation_seed``."""
        ss = np.random.SeedSequence(int(simulation_seed), spawn_key=(_LIGHT_STREAM,))
        u = np.random.default_rng(ss).random(4)
        (e0, e1), (i0, i1), (a0, a1) = self.sun_elevation_deg, self.sun_intensity, self.ambient
        return Lighting(
            sun_azimuth_deg=360.0 * float(u[0]),
            sun_elevation_deg=e0 + (e1 - e0) * float(u[1]),
            sun_intensity=i0 + (i1 - i0) * float(u[2]),
            ambient=a0 + (a1 - a0) * float(u[3]),
        )

    def camera_gains(self, attribute_rng: np.random.Generator) -> np.ndarray:
        """(3,) per-channel gain of one view (exposure times white balance), from a child of the
        view's attribute stream (the attribute stream itself is not advanced)."""
        seq = attribute_rng.bit_generator.seed_seq
        child = np.random.SeedSequence(seq.entropy, spawn_key=(*seq.spawn_key, _CAMERA_CHILD))
        z = np.random.default_rng(child).standard_normal(4)
        return pm.exp(z[0] * self.exposure_sigma + z[1:] * self.white_balance_sigma)


def _srgb_to_linear(c: np.ndarray) -> np.ndarray:
    return np.where(c <= 0.04045, c / 12.92, pm.power((c + 0.055) / 1.055, 2.4))


def _linear_to_srgb(c: np.ndarray) -> np.ndarray:
    return np.where(c <= 0.0031308, 12.92 * c, 1.055 * pm.power(c, 1 / 2.4) - 0.055)


def exposed(color: np.ndarray, gains: np.ndarray) -> np.ndarray:
    """(H, W, 3) uint8 sRGB image with its linear intensities scaled per channel by ``gains``
    and clipped (a camera's exposure and white balance). The 256-level tables are computed with
    :mod:`cadsim.portable_math`, so the image is the same on every CPU."""
    lut = np.arange(256, dtype=float) / 255.0
    linear = _srgb_to_linear(lut)
    out = np.empty_like(np.asarray(color, dtype=np.uint8))
    for c in range(3):  # one 256-entry table per channel: no per-pixel float work
        table = np.round(255.0 * _linear_to_srgb(np.clip(linear * gains[c], 0.0, 1.0)))
        out[..., c] = table.astype(np.uint8)[color[..., c]]
    return out
