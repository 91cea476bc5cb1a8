"""Depth noise: σ = noise_rate · d², seeded, holes kept, correlated part with a set length."""

import numpy as np
import pytest

from cadsim.sensing.depth_noise import (
    MIN_NOISY_DEPTH_M,
    NoiseConfig,
    apply_depth_noise,
    correlated_field,
)


def flat(d: float, shape=(240, 320)) -> np.ndarray:
    return np.full(shape, d, dtype=np.float32)


def lag_corr(x: np.ndarray, lag: int) -> float:
    x = (x - x.mean()) / x.std()
    return float(0.5 * ((x[:, :-lag] * x[:, lag:]).mean() + (x[:-lag] * x[lag:]).mean()))


def test_same_seed_same_noise_and_different_seed_different_noise():
    depth = flat(12.0)
    cfg = NoiseConfig(noise_rate=0.01)
    a = apply_depth_noise(depth, cfg, np.random.default_rng(7))
    b = apply_depth_noise(depth, cfg, np.random.default_rng(7))
    c = apply_depth_noise(depth, cfg, np.random.default_rng(8))
    assert a.dtype == np.float32 and a.shape == depth.shape
    np.testing.assert_array_equal(a, b)
    assert not np.allclose(a, c)


def test_no_hit_pixels_stay_zero_and_the_input_is_untouched():
    depth = flat(30.0)
    depth[:50] = 0.0
    before = depth.copy()
    noisy = apply_depth_noise(depth, NoiseConfig(noise_rate=0.05), np.random.default_rng(0))
    np.testing.assert_array_equal(depth, before)
    assert np.all(noisy[:50] == 0.0)
    assert np.all(noisy[50:] >= MIN_NOISY_DEPTH_M)  # hits remain hits even with huge noise


def test_zero_rate_is_identity():
    depth = np.random.default_rng(1).uniform(0, 50, (60, 80)).astype(np.float32)
    np.testing.assert_array_equal(
        apply_depth_noise(depth, NoiseConfig(noise_rate=0.0), np.random.default_rng(0)), depth
    )


@pytest.mark.parametrize("fraction", [0.0, 0.5, 1.0])
def test_standard_deviation_is_rate_times_depth_squared(fraction):
    rate = 0.002
    cfg = NoiseConfig(noise_rate=rate, correlation_length_px=4.0, correlated_fraction=fraction)
    for d in (5.0, 10.0, 20.0):
        errs = np.concatenate(
            [
                (apply_depth_noise(flat(d), cfg, np.random.default_rng(s)) - d).ravel()
                for s in range(4)
            ]
        )
        assert abs(errs.mean()) < 0.05 * rate * d * d
        assert errs.std() == pytest.approx(rate * d * d, rel=0.05)


@pytest.mark.parametrize("length", [3.0, 8.0, 20.0])
def test_correlated_field_has_the_requested_correlation_length(length):
    rng = np.random.default_rng(3)
    fields = [correlated_field((240, 320), length, rng) for _ in range(3)]
    for lag in (1, int(length)):
        measured = np.mean([lag_corr(f, lag) for f in fields])
        assert measured == pytest.approx(np.exp(-(lag**2) / (4 * length**2)), abs=0.08)
    for f in fields:
        assert f.std() == pytest.approx(1.0, abs=1e-6)


def test_correlation_length_really_correlates_neighbouring_pixels_of_the_noise():
    depth = flat(10.0)
    smooth = NoiseConfig(noise_rate=0.01, correlation_length_px=10.0, correlated_fraction=1.0)
    white = NoiseConfig(noise_rate=0.01, correlation_length_px=0.0, correlated_fraction=1.0)
    half = NoiseConfig(noise_rate=0.01, correlation_length_px=10.0, correlated_fraction=0.5)
    noise = {
        name: apply_depth_noise(depth, cfg, np.random.default_rng(5)) - 10.0
        for name, cfg in (("smooth", smooth), ("white", white), ("half", half))
    }
    assert lag_corr(noise["smooth"], 1) > 0.98
    assert lag_corr(noise["smooth"], 10) == pytest.approx(np.exp(-0.25), abs=0.1)
    assert abs(lag_corr(noise["white"], 1)) < 0.03
    # Half of the variance correlated: neighbours correlate at about half the smooth value.
    assert lag_corr(noise["half"], 1) == pytest.approx(0.5, abs=0.06)


def test_config_validation_names_the_table_and_key():
    with pytest.raises(ValueError, match=r"s\.toml \[noise\].*unknown key\(s\) noise_rat"):
        NoiseConfig.from_table({"noise_rat": 0.1}, "s.toml [noise]")
    with pytest.raises(TypeError, match=r"s\.toml \[noise\] noise_rate must be a number"):
        NoiseConfig.from_table({"noise_rate": "0.1"}, "s.toml [noise]")
    with pytest.raises(ValueError, match="correlated_fraction must be <= 1"):
        NoiseConfig(correlated_fraction=1.5)
    with pytest.raises(ValueError, match="noise_rate must be >= 0"):
        NoiseConfig(noise_rate=-0.1)
    cfg = NoiseConfig.from_table({"noise_rate": 0.02, "correlation_length_px": 5})
    assert cfg == NoiseConfig(noise_rate=0.02, correlation_length_px=5)


def test_bad_depth_images_are_rejected():
    with pytest.raises(ValueError, match="2-D"):
        apply_depth_noise(np.zeros(5), NoiseConfig(), np.random.default_rng(0))
    bad = flat(3.0)
    bad[0, 0] = np.nan
    with pytest.raises(ValueError, match="finite"):
        apply_depth_noise(bad, NoiseConfig(), np.random.default_rng(0))
