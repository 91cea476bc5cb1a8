"""`FramePair.redetect`: real renderer, depth noise and detection on a fake (SUMO-free) world."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from test_generate_fakes import FakeScenario

from cadsim.dataset import Dataset
from cadsim.generation.pipeline import Stages, generate_dataset

pytestmark = pytest.mark.render

SCENARIO = FakeScenario(
    camera={"width": 320, "height": 240, "hfov_deg": 90.0},
    noise={"noise_rate": 0.002},
    detection={"min_pixels": 20},
)


@pytest.fixture(scope="module")
def dataset(tmp_path_factory) -> Dataset:
    out = tmp_path_factory.mktemp("redetect") / "ds"
    stages = Stages(source="test_generate_fakes:make_source")  # everything else real
    generate_dataset(SCENARIO, out, pairs=2, workers=1, stages=stages, progress=False)
    return Dataset(out, verify=True)


def test_redetect_with_no_run_seed_at_the_dataset_rate_reproduces_the_stored_detections(dataset):
    for pair in dataset:
        again = pair.redetect(SCENARIO.noise["noise_rate"], seed=None)
        assert again.view1.equals(pair.view1) and again.view2.equals(pair.view2)
        np.testing.assert_array_equal(again.gt_pairs, pair.gt_pairs)


def test_redetect_is_deterministic_and_seeded(dataset):
    pair = dataset[0]
    a, b = pair.redetect(0.02, seed=5), pair.redetect(0.02, seed=5)
    assert a.view1.equals(b.view1) and a.view2.equals(b.view2) and a.noise_rate == 0.02
    c = pair.redetect(0.02, seed=6)
    assert c.view1.object_ids == a.view1.object_ids  # noise moves positions, not visibility
    assert not np.array_equal(c.view1.positions, a.view1.positions)


def test_zero_noise_gives_the_clean_depth_detections(dataset):
    from cadsim.render.view import RenderedView
    from cadsim.sensing.depth_noise import NoiseConfig  # noqa: F401  (the real stage is in use)
    from cadsim.sensing.detection import DetectionConfig, detect

    pair = dataset[1]
    clean = pair.redetect(0.0, seed=3)
    assert clean.view1.equals(pair.redetect(0.0, seed=4).view1)  # no randomness left
    cfg = DetectionConfig(**SCENARIO.detection)
    view = RenderedView(pair.color1, pair.depth1, pair.instance1)
    attributes = np.random.default_rng(pair.record["observers"][0]["attribute_seed"])
    direct = detect(view, pair.depth1, pair.objects, pair.cameras[0], cfg, attributes)
    np.testing.assert_array_equal(clean.view1.positions, direct.positions)
    assert clean.view1.object_ids == list(direct.object_ids)
    # The stored detections carry noise; the clean ones are closer to the true object centres.
    cam = pair.cameras[0]
    by_id = {o.id: o for o in pair.objects}
    truth = cam.world_to_camera(np.array([by_id[i].center for i in clean.view1.object_ids]))
    noisy = pair.redetect(0.05, seed=3)
    err_clean = np.linalg.norm(clean.view1.positions - truth, axis=1).mean()
    err_noisy = np.linalg.norm(noisy.view1.positions - truth, axis=1).mean()
    assert err_clean < err_noisy


def test_redetect_rejects_bad_rates(dataset):
    with pytest.raises(ValueError, match="noise_rate: expected a finite value >= 0"):
        dataset[0].redetect(-0.1, seed=1)


def test_redetect_keeps_loaded_images_and_identity(dataset):
    pair = dataset[0]
    _ = pair.color1
    other = pair.redetect(0.01, seed=2)
    assert other.color1 is pair.color1 and other.name == pair.name and other.index == pair.index
    assert Path(other.path) == Path(pair.path)


def test_redetect_reuses_stored_features_instead_of_recomputing(dataset, monkeypatch):
    from cadsim.render.view import RenderedView
    from cadsim.sensing import detection
    from cadsim.sensing.detection import DetectionConfig

    pair = dataset[0]
    cfg = DetectionConfig(**SCENARIO.detection)
    view = RenderedView(pair.color1, pair.depth1, pair.instance1)
    attributes = np.random.default_rng(pair.record["observers"][0]["attribute_seed"])
    recomputed = detection.detect(
        view, pair.depth1, pair.objects, pair.cameras[0], cfg, attribute_rng=attributes
    )
    calls = []
    real = detection.object_features
    monkeypatch.setattr(detection, "object_features", lambda *a: calls.append(a) or real(*a))
    again = pair.redetect(0.03, seed=9)
    assert calls == []  # every detected object already had stored features
    np.testing.assert_array_equal(again.view1.features, recomputed.features)
    np.testing.assert_array_equal(again.view1.features, pair.view1.features)


def test_redetect_rates_gives_the_bits_of_one_redetect_per_rate(dataset):
    rates = [0.0, 0.002, 0.05, 0.0]
    for pair in dataset:
        together = pair.redetect_rates(rates, seed=7)
        for rate, got in zip(rates, together, strict=True):
            alone = dataset[pair.index].redetect(rate, seed=7)  # a fresh pair: nothing shared
            assert got.noise_rate == rate
            assert got.view1.equals(alone.view1) and got.view2.equals(alone.view2)
            for a, b in ((got.view1, alone.view1), (got.view2, alone.view2)):
                np.testing.assert_array_equal(a.positions, b.positions)
        assert not np.array_equal(together[1].view1.positions, together[2].view1.positions)
    with pytest.raises(ValueError, match="noise_rate: expected a finite value >= 0"):
        dataset[0].redetect_rates([0.01, float("nan")], seed=1)


def test_redetection_plan_locates_exactly_as_detect_on_the_full_noisy_image(dataset):
    from cadsim.render.view import RenderedView
    from cadsim.sensing.depth_noise import (
        NoiseConfig,
        apply_depth_noise,
        noisy_depth_values,
        unit_noise,
    )
    from cadsim.sensing.detection import DetectionConfig, detect, plan_detections

    pair = dataset[1]
    cfg, det_cfg = NoiseConfig(noise_rate=0.03), DetectionConfig(**SCENARIO.detection)
    noisy = apply_depth_noise(pair.depth1, cfg, np.random.default_rng(11))
    view = RenderedView(pair.color1, pair.depth1, pair.instance1)
    direct = detect(view, noisy, pair.objects, pair.cameras[0], det_cfg)
    plan = plan_detections(
        pair.instance1, pair.depth1, pair.objects, pair.cameras[0], det_cfg, lambda: pair.color1
    )
    assert len(plan) == len(direct) > 0
    # The noise at the plan's pixels alone is the full image's noise there, bit for bit.
    unit = unit_noise(pair.depth1.shape, cfg, np.random.default_rng(11)).ravel()[plan.pixels]
    clean = pair.depth1.astype(np.float64).ravel()[plan.pixels]
    values = noisy_depth_values(clean, cfg.noise_rate, unit)
    np.testing.assert_array_equal(values, noisy.ravel()[plan.pixels])
    for located in (plan.locate(values), plan.locate(noisy)):
        np.testing.assert_array_equal(located.positions, direct.positions)
        np.testing.assert_array_equal(located.features, direct.features)
        np.testing.assert_array_equal(located.boxes, direct.boxes)
        np.testing.assert_array_equal(located.pixels, direct.pixels)
        assert located.object_ids == direct.object_ids
    with pytest.raises(ValueError, match="plan's pixels"):
        plan.locate(values[:-1])
    with pytest.raises(ValueError, match="clean depth must have the instance map's shape"):
        plan_detections(
            pair.instance1, pair.depth1[:-1], pair.objects, pair.cameras[0], det_cfg, lambda: None
        )
