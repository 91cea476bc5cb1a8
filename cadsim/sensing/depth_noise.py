"""Depth-sensor noise (DESIGN §4): standard deviation ``noise_rate · d²`` at depth d, metres.

The noise of a pixel is ``σ(d) · (√(1-f) · w + √f · c)`` with ``w`` independent standard-normal
per pixel, ``c`` a spatially correlated standard-normal field and ``f = correlated_fraction``, so the
total standard deviation is exactly σ(d). ``c`` is white noise smoothed by a Gaussian of standard
deviation ``correlation_length_px`` (its autocorrelation at a lag of r pixels is exp(-r²/(4 L²))),
re-normalised to unit variance; for L > 4 px it is generated on a grid L/2 px coarser and upsampled
bilinearly (the same field statistics at a fraction of the cost). Pixels without a hit (depth 0)
stay 0; noisy hits are kept ≥ ``MIN_NOISY_DEPTH_M`` so that 0 keeps meaning "no hit". Applied to
the depth image only, never to ground truth. Deterministic for a given ``rng`` state.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import cv2
import numpy as np
from scipy.ndimage import gaussian_filter

from cadsim.config_tables import check_number, config_from_table
from cadsim.limits import MAX_IMAGE_SIDE, MAX_NOISE_RATE

MIN_NOISY_DEPTH_M = 0.01


@dataclass(frozen=True)
class NoiseConfig:
    """The ``[noise]`` table of a scenario file.

    noise_rate: σ(d) = noise_rate · d², 1/m (0.01 → 1 m at 10 m; the paper's "1 m at 10 m for 0.1"
    does not fit its own formula, see docs/detection.md). correlation_length_px: standard deviation
    (pixels) of the Gaussian that correlates the smooth part of the noise; 0 = all noise white.
    correlated_fraction: share of the noise variance in the correlated part, in [0, 1].
    """

    noise_rate: float = 0.001
    correlation_length_px: float = 12.0
    correlated_fraction: float = 0.5

    def __post_init__(self) -> None:
        check_number("[noise]", "noise_rate", self.noise_rate, minimum=0.0, maximum=MAX_NOISE_RATE)
        # The correlated field's filter costs time in proportion to its length.
        check_number(
            "[noise]",
            "correlation_length_px",
            self.correlation_length_px,
            minimum=0.0,
            maximum=MAX_IMAGE_SIDE,
        )
        check_number(
            "[noise]", "correlated_fraction", self.correlated_fraction, minimum=0.0, maximum=1.0
        )

    @classmethod
    def from_table(cls, table: Mapping, where: str = "[noise]") -> NoiseConfig:
        """Build from a scenario-file table; unknown keys/bad values raise naming ``where``."""
        return config_from_table(cls, table, where, "[noise]")


def correlated_field(
    shape: tuple[int, int], correlation_length_px: float, rng: np.random.Generator
) -> np.ndarray:
    """(H, W) float64 zero-mean, unit-variance Gaussian random field with Gaussian autocorrelation
    of length ``correlation_length_px`` (white noise if it is 0)."""
    h, w = shape
    L = float(correlation_length_px)
    if L <= 0:
        return rng.standard_normal(shape)
    step = max(1, int(L // 2)) if L > 4 else 1
    lo_h, lo_w = -(-h // step) + 1, -(-w // step) + 1
    field = gaussian_filter(rng.standard_normal((lo_h, lo_w)), sigma=L / step, mode="wrap")
    if step > 1:
        field = cv2.resize(field, (lo_w * step, lo_h * step), interpolation=cv2.INTER_LINEAR)
    field = field[:h, :w]
    field = field - field.mean()
    std = field.std()
    return field / std if std > 0 else field


def check_depth(depth: np.ndarray) -> np.ndarray:
    """``depth`` ((H, W) metres along the optical axis, 0 = no hit) as float64; raises
    ValueError unless it is 2-D, finite and >= 0."""
    d = np.asarray(depth)
    if d.ndim != 2:
        raise ValueError(f"depth must be a 2-D (H, W) image, got shape {d.shape}")
    d = d.astype(np.float64)
    if not np.all(np.isfinite(d)) or np.any(d < 0):
        raise ValueError("depth must be finite and >= 0 (0 = no hit)")
    return d


def unit_noise(shape: tuple[int, int], config: NoiseConfig, rng: np.random.Generator) -> np.ndarray:
    """(H, W) float64 unit-variance noise ``√(1-f) · w + √f · c`` (module docstring), drawn from
    ``rng`` in a fixed order (white noise, then the correlated field). It does not depend on
    the noise rate: every rate scales the same field (common random numbers)."""
    f = config.correlated_fraction
    unit = np.sqrt(1.0 - f) * rng.standard_normal(shape)
    if f > 0:
        unit += np.sqrt(f) * correlated_field(shape, config.correlation_length_px, rng)
    return unit


def noisy_depth_values(depth: np.ndarray, noise_rate: float, unit: np.ndarray | None) -> np.ndarray:
    """Noisy depth as float32, elementwise: ``depth`` (float64 metres, 0 = no hit, any shape) plus
    ``noise_rate · d² · unit`` (``unit``: :func:`unit_noise`, or its values at the same pixels;
    unused and may be None when the rate is 0). Hits stay ≥ ``MIN_NOISY_DEPTH_M``, misses 0."""
    if noise_rate == 0:
        return depth.astype(np.float32)
    noisy = depth + noise_rate * depth * depth * unit
    return np.where(depth > 0, np.maximum(noisy, MIN_NOISY_DEPTH_M), 0.0).astype(np.float32)


def apply_depth_noise(
    depth: np.ndarray, config: NoiseConfig, rng: np.random.Generator
) -> np.ndarray:
    """Noisy copy of ``depth`` ((H, W) metres along the optical axis, 0 = no hit) as float32.

    Draws from ``rng`` in a fixed order (white noise, then the correlated field), so the same
    generator state gives the same image."""
    d = check_depth(depth)
    if config.noise_rate == 0:
        return noisy_depth_values(d, 0.0, None)
    return noisy_depth_values(d, config.noise_rate, unit_noise(d.shape, config, rng))
