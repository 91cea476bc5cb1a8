"""Beam patterns of spinning LiDARs: which rays one sweep fires, how far they reach, how noisy
their ranges are — and the ``[lidar]`` table of a scenario file that picks and adjusts one.

A pattern is a fixed set of channels (each a constant elevation angle) fired at ``azimuth_steps``
equally spaced azimuths per revolution, so one sweep is ``channels × azimuth_steps`` rays. Frame:
the LiDAR frame (x forward, y left, z up, metres, origin at the optical centre); elevation is
positive up from the x-y plane, azimuth counter-clockwise from +x, ray ``c · azimuth_steps + k``
is channel c (ascending elevation) at azimuth ``k · 360° / azimuth_steps``.

Presets (values from the manufacturers' manuals, docs/lidar.md lists the sources):

- ``hdl-32e`` (roof): Velodyne HDL-32E — 32 channels evenly spaced from −30.67° to +10.67°
  (1.33°, the manual's firing table), 0.16° horizontally at 10 Hz (2250 azimuths), returns from
  0.05 m to 100 m, range accuracy < 2 cm (σ = 0.02 m).
- ``hdl-64e`` (roof): Velodyne HDL-64E S2/S3 — 64 channels over its 26.8° vertical field of view
  (+2.0° to −24.8°): the upper block of 32 at 1/3° from +2.0°, the lower block of 32 at 1/2°
  down to −24.8°, stretched to meet (the unit's calibration file holds the exact angles);
  2048 azimuths (≈ 0.18°, 10 Hz), usable returns to 120 m, accuracy < 2 cm (σ = 0.02 m).
- ``pandar128`` (roadside): Hesai Pandar128 — 128 channels over −25° to +15° with a dense band of
  0.125° around the horizon (64 channels from −6.0° to +1.875°) and 32 sparser channels above
  and below, 0.1° horizontally at 10 Hz (3600 azimuths), 0.3 m to 200 m, ±2 cm (σ = 0.02 m).

Dropout is the share of rays that return nothing although they hit something (dark or specular
surfaces, rain); the presets use 0.05, the user sets it. Imports only numpy and the config-table
helpers; elevations and azimuths go through :mod:`math` (the C library) so the directions are the
same bits on every CPU.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field, replace

import numpy as np

from cadsim.config_tables import check_number, config_from_table

MAX_CHANNELS = 512
MAX_AZIMUTH_STEPS = 8192
RANGE_STEP_M = 0.004
"""Stored ranges are whole multiples of this (metres): the distance unit of Hesai's packets."""
MAX_RANGE_M = 262.0  # what a uint16 range in 4 mm steps holds (cadsim.dataset.lidar_points)


def _uniform(lo_deg: float, hi_deg: float, n: int) -> tuple[float, ...]:
    """n elevations evenly spaced from lo to hi (degrees, both included), ascending."""
    if n == 1:
        return ((lo_deg + hi_deg) / 2.0,)
    step = (hi_deg - lo_deg) / (n - 1)
    return tuple(round(lo_deg + i * step, 6) for i in range(n))


def _hdl64e() -> tuple[float, ...]:
    upper = [2.0 - i / 3.0 for i in range(32)]  # +2.0 … −8.33
    lower = [-8.83 - i * (24.8 - 8.83) / 31.0 for i in range(32)]  # −8.83 … −24.8
    return tuple(sorted(round(v, 6) for v in upper + lower))


def _pandar128() -> tuple[float, ...]:
    dense = [-6.0 + 0.125 * i for i in range(64)]  # −6.0 … +1.875
    below = list(_uniform(-25.0, -6.5, 32))
    above = list(_uniform(2.375, 15.0, 32))
    return tuple(round(v, 6) for v in below + dense + above)


@dataclass(frozen=True)
class BeamPattern:
    """One sweep's rays and their measurement model.

    elevations_deg: per-channel elevation, degrees, ascending. azimuth_steps: azimuths per
    revolution. min_range_m / max_range_m: returns closer / farther are dropped (metres).
    range_sigma_m: standard deviation of the Gaussian range noise (metres). dropout: probability
    that a ray which hits returns nothing, in [0, 1]. mount: "roof" or "roadside", the kind of
    unit the preset is (``cadsim.sensing.lidar.observe`` mounts the table's pattern on vehicles
    and ``roadside_preset`` on observers on no vehicle).
    """

    name: str
    elevations_deg: tuple[float, ...]
    azimuth_steps: int
    min_range_m: float
    max_range_m: float
    range_sigma_m: float
    dropout: float
    mount: str = "roof"
    _directions: np.ndarray | None = field(default=None, repr=False, compare=False)

    def __post_init__(self) -> None:
        where = f"[lidar] ({self.name})"
        if not 1 <= len(self.elevations_deg) <= MAX_CHANNELS:
            raise ValueError(
                f"{where} channels must be in [1, {MAX_CHANNELS}], got {len(self.elevations_deg)}"
            )
        for e in self.elevations_deg:
            check_number(where, "elevation", e, minimum=-90.0, maximum=90.0)
        if list(self.elevations_deg) != sorted(self.elevations_deg):
            raise ValueError(f"{where} elevations_deg must be ascending")
        check_number(where, "azimuth_steps", self.azimuth_steps, minimum=1, maximum=MAX_AZIMUTH_STEPS, integer=True)  # fmt: skip
        check_number(where, "min_range_m", self.min_range_m, minimum=0.0, maximum=MAX_RANGE_M)
        check_number(where, "max_range_m", self.max_range_m, minimum=0.1, maximum=MAX_RANGE_M)
        if self.min_range_m >= self.max_range_m:
            raise ValueError(f"{where} min_range_m must be below max_range_m")
        check_number(where, "range_noise_m", self.range_sigma_m, minimum=0.0, maximum=1.0)
        check_number(where, "dropout", self.dropout, minimum=0.0, maximum=1.0)
        if self.mount not in ("roof", "roadside"):
            raise ValueError(f"{where} mount must be 'roof' or 'roadside', got {self.mount!r}")

    @property
    def channels(self) -> int:
        return len(self.elevations_deg)

    @property
    def ray_count(self) -> int:
        """Rays per sweep: channels × azimuth_steps."""
        return self.channels * self.azimuth_steps

    def directions(self) -> np.ndarray:
        """(ray_count, 3) float64 unit ray directions in the LiDAR frame, ray order as in the module
        docstring. Cached; the same bits on every CPU (sines and cosines from :mod:`math`)."""
        if self._directions is None:
            el = np.radians(np.asarray(self.elevations_deg, dtype=np.float64))
            az = np.arange(self.azimuth_steps, dtype=np.float64) * (
                2.0 * math.pi / self.azimuth_steps
            )
            cos_el = np.array([math.cos(v) for v in el])
            sin_el = np.array([math.sin(v) for v in el])
            cos_az = np.array([math.cos(v) for v in az])
            sin_az = np.array([math.sin(v) for v in az])
            d = np.empty((self.channels, self.azimuth_steps, 3))
            d[..., 0] = cos_el[:, None] * cos_az[None, :]
            d[..., 1] = cos_el[:, None] * sin_az[None, :]
            d[..., 2] = sin_el[:, None]
            d = d.reshape(-1, 3)
            d.setflags(write=False)
            object.__setattr__(self, "_directions", d)
        return self._directions


PRESETS: dict[str, BeamPattern] = {
    "hdl-32e": BeamPattern("hdl-32e", _uniform(-30.67, 10.67, 32), 2250, 0.05, 100.0, 0.02, 0.05),
    "hdl-64e": BeamPattern("hdl-64e", _hdl64e(), 2048, 0.9, 120.0, 0.02, 0.05),
    "pandar128": BeamPattern("pandar128", _pandar128(), 3600, 0.3, 200.0, 0.02, 0.05, "roadside"),
}
"""The named beam patterns a ``[lidar]`` table's ``preset`` picks (module docstring)."""


@dataclass(frozen=True)
class LidarConfig:
    """The ``[lidar]`` table of a scenario file: a preset and any of its values replaced.

    preset: a name of :data:`PRESETS` (default "hdl-64e"). channels + vertical_fov_deg
    ([lowest, highest] degrees): evenly spaced channels instead of the preset's; elevations_deg:
    explicit per-channel angles instead (ascending). horizontal_resolution_deg: azimuth step
    (degrees; 360 / it azimuths, rounded). min_range_m, max_range_m, range_noise_m (σ, metres),
    dropout (probability). roadside_preset: the pattern of roadside units (observers on no
    vehicle; default "pandar128"), which takes only range_noise_m and dropout from the table.
    """

    preset: str = "hdl-64e"
    channels: int | None = None
    vertical_fov_deg: tuple[float, float] | list[float] | None = None
    elevations_deg: tuple[float, ...] | list[float] | None = None
    horizontal_resolution_deg: float | None = None
    min_range_m: float | None = None
    max_range_m: float | None = None
    range_noise_m: float | None = None
    dropout: float | None = None
    roadside_preset: str = "pandar128"

    def __post_init__(self) -> None:
        for key in ("preset", "roadside_preset"):
            name = getattr(self, key)
            if name not in PRESETS:
                raise ValueError(
                    f"[lidar] {key} must be one of {', '.join(sorted(PRESETS))}, got {name!r}"
                )
        if self.elevations_deg is not None and (self.channels is not None or self.vertical_fov_deg is not None):  # fmt: skip
            raise ValueError(
                "[lidar] give either elevations_deg or channels + vertical_fov_deg, not both"
            )
        if (self.channels is None) != (self.vertical_fov_deg is None):
            raise ValueError("[lidar] channels and vertical_fov_deg go together")
        if self.channels is not None:
            check_number("[lidar]", "channels", self.channels, minimum=1, maximum=MAX_CHANNELS, integer=True)  # fmt: skip
            fov = self.vertical_fov_deg
            if not isinstance(fov, (list, tuple)) or len(fov) != 2:
                raise ValueError(
                    f"[lidar] vertical_fov_deg must be [lowest, highest] degrees, got {fov!r}"
                )
            for v in fov:
                check_number("[lidar]", "vertical_fov_deg", v, minimum=-90.0, maximum=90.0)
            if not fov[0] < fov[1]:
                raise ValueError(
                    "[lidar] vertical_fov_deg must be [lowest, highest] with lowest < highest"
                )
        if self.dropout == 1.0:  # no ray would return: generation would search for ever
            raise ValueError("[lidar] dropout must be below 1 (at 1 no ray returns), got 1.0")
        if self.elevations_deg is not None and not isinstance(self.elevations_deg, (list, tuple)):
            raise ValueError("[lidar] elevations_deg must be a list of degrees")
        if self.horizontal_resolution_deg is not None:
            check_number("[lidar]", "horizontal_resolution_deg", self.horizontal_resolution_deg, minimum=360.0 / MAX_AZIMUTH_STEPS, maximum=360.0)  # fmt: skip
        self.pattern()  # the remaining checks are the pattern's

    @classmethod
    def from_table(cls, table: Mapping, where: str = "[lidar]") -> LidarConfig:
        """Build from a scenario-file table; unknown keys/bad values raise naming ``where``."""
        return config_from_table(cls, table, where, "[lidar]")

    def pattern(self, roadside: bool = False) -> BeamPattern:
        """The resolved beam pattern (the roadside one's preset values for ``roadside``; the
        table's overrides apply to the roof unit only, except dropout and range noise)."""
        if roadside:
            base = PRESETS[self.roadside_preset]
            shared = {"range_sigma_m": self.range_noise_m, "dropout": self.dropout}
            return replace(base, **{k: v for k, v in shared.items() if v is not None})
        base = PRESETS[self.preset]
        changes: dict = {}
        if self.channels is not None:
            lo, hi = (float(v) for v in self.vertical_fov_deg)
            changes["elevations_deg"] = _uniform(lo, hi, int(self.channels))
        if self.elevations_deg is not None:
            changes["elevations_deg"] = tuple(float(v) for v in self.elevations_deg)
        if self.horizontal_resolution_deg is not None:
            changes["azimuth_steps"] = max(1, round(360.0 / float(self.horizontal_resolution_deg)))
        for key, attr in (("min_range_m", "min_range_m"), ("max_range_m", "max_range_m"),
                          ("range_noise_m", "range_sigma_m"), ("dropout", "dropout")):  # fmt: skip
            value = getattr(self, key)
            if value is not None:
                changes[attr] = value
        changes = {k: v for k, v in changes.items() if v != getattr(base, k)}
        if not changes:  # the table repeats the preset's values
            return base
        return replace(base, **changes, name=f"{base.name}+custom", _directions=None)
