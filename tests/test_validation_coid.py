"""The synthetic CoID benchmark end to end on a handful of frame pairs."""

from __future__ import annotations

import numpy as np

from eval.validation.coid_synthetic import ALL_MATCHERS, SceneConfig, format_summary, run_benchmark
from matchers import available, required_options, requires


def test_every_matcher_without_a_prior_is_benchmarked():
    # (the learned matchers need a model trained on data: they are the transfer study's)
    assert set(ALL_MATCHERS) == {
        m for m in available() if not requires(m) and not required_options(m)
    }


def test_small_benchmark_calibrates_and_scores():
    summary, per_frame = run_benchmark(
        ["appearance", "sm", "maximin"],
        seed=1,
        validation_frames=4,
        test_frames=3,
        runs=2,
        progress=False,
    )
    assert list(summary["matcher"]) == ["appearance", "sm", "maximin"]
    assert len(per_frame) == 3 * 3 * 2
    for col in ("f1_mean", "precision_mean", "recall_mean", "accuracy_mean", "ap"):
        assert summary[col].between(0.0, 1.0).all(), col
    # deterministic matchers give the same answer in every run
    assert summary.set_index("matcher").loc["sm", "f1_std"] == 0.0
    # matcher scores lie in [0, 1], so a calibrated tau that keeps something does too
    assert summary["tau"].between(0.0, 1.0).all()
    text = format_summary(summary)
    assert len(text.splitlines()) == 2 + 3 and "maximin" in text


def test_spatial_structure_beats_look_alike_appearance():
    # noise-free geometry, look-alike features: spectral matching on distances must beat
    # matching by appearance alone (the reason the suite exists)
    cfg = SceneConfig(position_noise_m=0.0)
    summary, _ = run_benchmark(
        ["appearance", "sm"],
        seed=2,
        validation_frames=4,
        test_frames=6,
        runs=1,
        cfg=cfg,
        progress=False,
    )
    f1 = summary.set_index("matcher")["f1_mean"]
    assert f1["sm"] > f1["appearance"] + 0.2
    assert np.isfinite(f1).all()
