"""GNSS-like localisation error: a connected vehicle's pose error as satellite positioning makes it.

The i.i.d. model of :mod:`cadsim.sensing.localisation` draws a fresh error for every view. A real
receiver's error is not like that: most of it is a slowly varying bias (satellite geometry,
atmosphere, multipath from the same buildings) that two snapshots a few seconds apart share, plus
a little white noise, a heading error of its own (a heading estimate does not come from the same
measurement as the position), and now and then a jump of several metres (a multipath outlier or a
cycle slip). Per vehicle (observer id) and simulation episode, in the ground plane (x, y metres,
heading radians CCW):

    error(t) = bias + walk(t) + noise + outlier
    bias     ~ N(0, bias_m²) per axis            constant within the episode
    walk(t)  = Σ increments ~ N(0, walk²·1 s)    on a 1 s grid from t = 0, linear between
                                                 grid points (slow drift)
    noise    ~ N(0, noise_m²) per axis           per view (snapshot)
    outlier  = outlier_m in a uniform direction  with probability outlier_rate, per view
    heading  = heading_bias (episode) + N(0, heading_noise²) (view), drawn from their own streams

Episode-level draws (bias, walk, heading bias) come from ``SeedSequence(episode seed, spawn_key=
(5, crc32(vehicle id)))`` — the same for every record of that episode in which the vehicle
observes, whatever order records are read in; per-view draws from the view's localisation seed.

The walk is drawn by random access, in memory and time that do not grow with t (real
timestamps are absolute: V2X-Seq's are seconds since 1970, ~1.6e9): the grid's first
2^:data:`WALK_LEVELS` steps are halved level by level, each interval's increment splitting into
its halves' as a Brownian bridge does (the left half's is half the parent's plus
N(0, walk²·length/4), the right half's the rest; each split's normals by Box–Muller from a
BLAKE2b hash of (episode seed, crc32(vehicle id), level, index) — counter-based), and the walk
at grid point k is the sum of the left halves passed on the way down to step k — exactly a
Gaussian random walk on the grid, with :data:`WALK_LEVELS` + 1 pairs of normals per time. Times beyond
:data:`MAX_TIME_S` (about 35 million years) are refused.

Presets (:data:`PRESETS`; values and their sources: docs/localisation.md): ``exact`` (no error,
the prior given), ``rtk`` (centimetre-level), ``gnss-open-sky``, ``gnss-urban``, ``denied``
(no prior at all: a matcher that needs one declares nothing). ``stated_sigma_m`` is what the
vehicle reports as its 1-σ uncertainty — what a matcher is told — not the error drawn.
``latency_ms`` is the age of the other vehicle's message (:mod:`cadsim.sensing.latency`).

A preset *spec* names a preset with optional modifiers (:func:`parse_spec`): ``gnss-urban*2``
scales every error magnitude and the stated uncertainty by 2 (rates unchanged; ``*0`` is the
exact pose), ``gnss-urban+300ms`` sets the latency to 300 ms; both may be combined
(``gnss-urban*2+300ms``). The sweeps over model scale and latency use them.

Imports numpy only.
"""

from __future__ import annotations

import hashlib
import math
import re
import zlib
from dataclasses import dataclass, replace

import numpy as np

from cadsim.sensing.pose_error import PoseError

_EPISODE_STREAM = 5
WALK_STEP_S = 1.0
WALK_LEVELS = 50
MAX_TIME_S = float(2**WALK_LEVELS) * WALK_STEP_S
"""Largest time (seconds) the walk is drawn at: 2^50 s, far beyond any epoch timestamp."""


MAGNITUDES = (
    "bias_m",
    "walk_m_per_sqrt_s",
    "noise_m",
    "heading_bias_deg",
    "heading_noise_deg",
    "outlier_m",
    "stated_sigma_m",
)
"""The error magnitudes of a model (each >= 0; what a preset spec's ``*SCALE`` multiplies)."""


@dataclass(frozen=True)
class GnssErrorModel:
    """One preset's parameters (metres per ground axis, degrees, seconds; module docstring)."""

    bias_m: float = 0.0
    walk_m_per_sqrt_s: float = 0.0
    noise_m: float = 0.0
    heading_bias_deg: float = 0.0
    heading_noise_deg: float = 0.0
    outlier_rate: float = 0.0
    outlier_m: float = 0.0
    stated_sigma_m: float = 0.0
    latency_ms: float = 0.0
    given: bool = True  # False: the vehicle has no pose to share (denied)

    def __post_init__(self) -> None:
        for name in (*MAGNITUDES, "latency_ms"):
            value = getattr(self, name)
            if not (isinstance(value, int | float) and np.isfinite(value) and value >= 0):
                raise ValueError(f"{name}: expected a finite number >= 0, got {value!r}")
        if not 0.0 <= self.outlier_rate <= 1.0:
            raise ValueError(f"outlier_rate: expected a probability, got {self.outlier_rate!r}")

    def scaled(self, factor: float) -> GnssErrorModel:
        """Every error magnitude and the stated uncertainty times ``factor`` (>= 0); the outlier
        rate, the latency and whether a pose is given unchanged."""
        return replace(self, **{name: getattr(self, name) * float(factor) for name in MAGNITUDES})


PRESETS: dict[str, GnssErrorModel] = {
    "exact": GnssErrorModel(),
    "rtk": GnssErrorModel(bias_m=0.02, noise_m=0.01, heading_noise_deg=0.1, stated_sigma_m=0.03),
    "gnss-open-sky": GnssErrorModel(
        bias_m=1.5,
        walk_m_per_sqrt_s=0.05,
        noise_m=0.5,
        heading_bias_deg=0.3,
        heading_noise_deg=0.2,
        outlier_rate=0.01,
        outlier_m=5.0,
        stated_sigma_m=1.6,
    ),
    "gnss-urban": GnssErrorModel(
        bias_m=3.0,
        walk_m_per_sqrt_s=0.2,
        noise_m=1.0,
        heading_bias_deg=1.0,
        heading_noise_deg=0.5,
        outlier_rate=0.05,
        outlier_m=10.0,
        stated_sigma_m=3.2,
        latency_ms=100.0,
    ),
    "denied": GnssErrorModel(latency_ms=100.0, given=False),
}

_SPEC = re.compile(
    r"^(?P<name>[a-z-]+)(\*(?P<scale>[0-9]+(\.[0-9]+)?))?(\+(?P<latency>[0-9]+(\.[0-9]+)?)ms)?$"
)


def preset(name: str) -> GnssErrorModel:
    """The model of preset ``name``; ValueError naming the choices otherwise."""
    if name not in PRESETS:
        raise ValueError(f"preset: expected one of {', '.join(PRESETS)}, got {name!r}")
    return PRESETS[name]


def parse_spec(spec: str) -> tuple[str, float, float | None]:
    """(preset name, error scale, latency in ms or None for the preset's own) of a preset spec
    such as ``gnss-urban``, ``gnss-urban*2``, ``gnss-urban+300ms`` or ``gnss-urban*2+300ms``;
    ValueError naming the accepted forms otherwise."""
    match = _SPEC.match(str(spec))
    if match is None or match["name"] not in PRESETS:
        raise ValueError(
            f"preset: expected one of {', '.join(PRESETS)}, optionally followed by *SCALE and/or "
            f"+LATENCYms (e.g. gnss-urban*2+300ms), got {spec!r}"
        )
    latency = None if match["latency"] is None else float(match["latency"])
    return match["name"], float(match["scale"] or 1.0), latency


def model_of(spec: str) -> GnssErrorModel:
    """The error model a preset spec (:func:`parse_spec`) describes."""
    name, scale, latency = parse_spec(spec)
    model = PRESETS[name] if scale == 1.0 else PRESETS[name].scaled(scale)
    return model if latency is None else replace(model, latency_ms=latency)


def vehicle_key(vehicle: str) -> int:
    """A stable integer for an observer id (the same on every machine and Python)."""
    return zlib.crc32(str(vehicle).encode("utf-8"))


def episode_draws(
    model: GnssErrorModel, episode_seed: int, vehicle: str, time_s: float
) -> tuple[np.ndarray, float]:
    """(bias + walk at ``time_s`` (2,) metres, heading bias radians) of ``vehicle`` in the episode
    seeded ``episode_seed``: the same for every view of that vehicle in that episode."""
    ss = np.random.SeedSequence(
        int(episode_seed), spawn_key=(_EPISODE_STREAM, vehicle_key(vehicle))
    )
    rng = np.random.default_rng(ss)
    bias = rng.standard_normal(2) * model.bias_m
    heading = float(rng.standard_normal()) * np.radians(model.heading_bias_deg)
    if not (np.isfinite(time_s) and float(time_s) <= MAX_TIME_S):
        raise ValueError(f"time: expected finite seconds up to {MAX_TIME_S:.4g}, got {time_s!r}")
    t = max(0.0, float(time_s))
    walk = np.zeros(2)
    if model.walk_m_per_sqrt_s > 0:
        walk = _walk(episode_seed, vehicle, t / WALK_STEP_S) * (
            model.walk_m_per_sqrt_s * np.sqrt(WALK_STEP_S)
        )
    return bias + walk, heading


def _walk(episode_seed: int, vehicle: str, steps: float) -> np.ndarray:
    """A unit Gaussian random walk (increments N(0, 1) per axis) at ``steps`` grid steps, linear
    between grid points, drawn by halving (module docstring): (2,)."""
    k = int(np.floor(steps))
    prefix = f"{int(episode_seed)}/{vehicle_key(vehicle)}"
    # the whole grid's increment, then the halves that hold step k, level by level
    zx, zy = _normals(prefix, 0, 0)
    scale = 2.0 ** (WALK_LEVELS / 2)
    ix, iy = zx * scale, zy * scale  # the current interval's increment
    wx = wy = 0.0  # the walk at the current interval's start
    start = 0
    for level in range(1, WALK_LEVELS + 1):
        half = 1 << (WALK_LEVELS - level)
        zx, zy = _normals(prefix, level, start)
        spread = math.sqrt(half / 2)
        lx, ly = 0.5 * ix + zx * spread, 0.5 * iy + zy * spread  # the left half's increment
        if k < start + half:
            ix, iy = lx, ly
        else:
            wx, wy, ix, iy, start = wx + lx, wy + ly, ix - lx, iy - ly, start + half
    frac = steps - start  # start == k, except at the grid's very end (k = 2^WALK_LEVELS)
    return np.array([wx + frac * ix, wy + frac * iy])


def _normals(prefix: str, level: int, start: int) -> tuple[float, float]:
    """Two independent standard normals for the split of the interval at (``level``, ``start``):
    Box–Muller on a BLAKE2b hash of (episode seed, vehicle, level, start) — counter-based, so
    any interval's normals are drawn without the others, and through the C library's ``math``
    (the same bits on every numpy dispatch level, :mod:`cadsim.portable_math`)."""
    digest = hashlib.blake2b(
        f"{prefix}/{level}/{start}".encode(), digest_size=16, person=b"cadsim-gnss-walk"
    ).digest()
    u1 = ((int.from_bytes(digest[:8], "little") >> 11) + 1) * 2.0**-53  # (0, 1]
    u2 = (int.from_bytes(digest[8:], "little") >> 11) * 2.0**-53  # [0, 1)
    radius = math.sqrt(-2.0 * math.log(u1))
    return radius * math.cos(2 * math.pi * u2), radius * math.sin(2 * math.pi * u2)


def draw_error(
    model: GnssErrorModel, episode_seed: int, vehicle: str, time_s: float, view_seed: int
) -> PoseError:
    """The pose error of one view: the episode's bias, walk and heading bias of ``vehicle`` at
    ``time_s`` plus this view's noise, heading noise and outlier (seeded by ``view_seed``)."""
    shared, heading = episode_draws(model, episode_seed, vehicle, time_s)
    rng = np.random.default_rng(int(view_seed))
    noise = rng.standard_normal(2) * model.noise_m
    heading += float(rng.standard_normal()) * np.radians(model.heading_noise_deg)
    jump, direction = rng.random(), rng.random() * 2 * np.pi
    offset = shared + noise
    if jump < model.outlier_rate:
        offset = offset + model.outlier_m * np.array([np.cos(direction), np.sin(direction)])
    return PoseError(float(offset[0]), float(offset[1]), heading)
