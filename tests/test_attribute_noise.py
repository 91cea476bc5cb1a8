"""Attributes as a detector measures them: seeded class confusion within confusion groups at the
configured rate for a 32 × 32-pixel object and more for fewer pixels, sizes measured from the
silhouette and completed from the reported class, and their place in the features."""

from __future__ import annotations

import numpy as np
import pytest

from cadsim.camera import Camera
from cadsim.object_sizes import SIZE_SPREADS
from cadsim.render.view import RenderedView
from cadsim.sensing.attribute_noise import (
    CONFUSION_GROUPS,
    REFERENCE_PIXELS,
    Observation,
    measured_attributes,
)
from cadsim.sensing.detection import DetectionConfig, detect
from cadsim.sensing.features import FEATURE_CLASSES, FEATURE_LAYOUT
from cadsim.world import WorldObject

CLASSES = ("car", "van", "bus", "truck", "bicycle", "person", "traffic_light", "sign", "building")


def objects(n: int) -> list[WorldObject]:
    return [
        WorldObject(f"o{k}", CLASSES[k % len(CLASSES)], "box", (0, 0, 1), 0.0, (4.0, 2.0, 1.5), (1, 1, 1))
        for k in range(n)
    ]  # fmt: skip


def seen(n: int, pixels: float = REFERENCE_PIXELS, completeness: float = 1.0) -> Observation:
    """Every one of n objects seen alike: side-on at 20 m (f = 800 px), ``pixels`` visible."""
    return Observation(
        np.arange(n), np.full(n, pixels), np.tile([[160.0, 60.0]], (n, 1)), np.full(n, 20.0),
        np.full(n, completeness), np.full(n, np.pi / 2), (800.0, 800.0),
    )  # fmt: skip


def classes(objs, rate, rng, pixels=REFERENCE_PIXELS):
    return measured_attributes(objs, seen(len(objs), pixels), rate, 0.1, rng).classes


def test_confusion_is_seeded_and_at_the_configured_rate_at_the_reference_resolution():
    objs = objects(90_000)
    truth = np.array([o.cls for o in objs])
    grouped = np.isin(truth, [c for g in CONFUSION_GROUPS for c in g])
    for rate in (0.0075, 0.05):
        cls = classes(objs, rate, np.random.default_rng(1))
        assert cls == classes(objs, rate, np.random.default_rng(1))
        assert cls != classes(objs, rate, np.random.default_rng(2))
        wrong = np.array(cls) != truth
        assert not wrong[~grouped].any()  # buildings are in no group: never confused
        measured = wrong[grouped].mean()
        assert measured == pytest.approx(rate, abs=4 * np.sqrt(rate / grouped.sum()))


def test_confusion_grows_as_visible_pixels_fall():
    objs = objects(45_000)
    truth = np.array([o.cls for o in objs])
    grouped = np.isin(truth, [c for g in CONFUSION_GROUPS for c in g])
    rates = [
        (np.array(classes(objs, 0.05, np.random.default_rng(5), px)) != truth)[grouped].mean()
        for px in (4 * REFERENCE_PIXELS, REFERENCE_PIXELS, REFERENCE_PIXELS / 4)
    ]
    assert rates[0] == pytest.approx(0.025, abs=0.005)  # sqrt(1/4) of the rate
    assert rates[2] == pytest.approx(0.1, abs=0.01)  # twice the rate
    assert rates[0] < rates[1] < rates[2]


def test_two_views_disagree_about_twice_the_rate_and_only_within_groups():
    objs = objects(90_000)
    cls1 = classes(objs, 0.0075, np.random.default_rng(10))
    cls2 = classes(objs, 0.0075, np.random.default_rng(11))
    group_of = {c: k for k, g in enumerate(CONFUSION_GROUPS) for c in g}
    truth = [o.cls for o in objs]
    grouped = [k for k, c in enumerate(truth) if c in group_of]
    disagree = np.mean([cls1[k] != cls2[k] for k in grouped])
    assert disagree == pytest.approx(0.015, abs=0.002)  # the paper group's CAD data: 1.45 %
    for reported, true in zip(cls1, truth, strict=True):
        if reported != true:
            assert group_of[reported] == group_of[true]


def test_every_other_member_of_a_group_can_be_reported():
    car = objects(1)[0]
    told = {classes([car], 1.0, np.random.default_rng(s))[0] for s in range(60)}
    assert told == {"van", "bus", "truck"}


def test_size_is_the_silhouette_measured_then_scattered_as_the_rate_says():
    # A car seen side-on: its silhouette 160 x 60 px at 20 m is 4.0 x 1.5 m; its width comes from
    # the car class's aspect ratio (4.5 / 1.8). Scatter at the reference resolution: size_noise.
    car = [WorldObject(f"c{k}", "car", "car", (0, 20, 0.75), 0.0, (4.5, 1.8, 1.5), (1, 1, 1)) for k in range(20_000)]  # fmt: skip
    out = measured_attributes(car, seen(len(car), 1e9), 0.0, 0.0, np.random.default_rng(3))
    np.testing.assert_allclose(np.median(out.sizes, axis=0), [4.0, 1.6, 1.5], rtol=0.01)
    noisy = measured_attributes(car, seen(len(car)), 0.0, 0.1, np.random.default_rng(3)).sizes
    log_ratio = np.log(noisy / np.median(out.sizes, axis=0))
    assert (noisy > 0).all() and abs(np.median(log_ratio[:, 2])) < 0.01
    assert log_ratio[:, 2].std() == pytest.approx(np.hypot(0.1, 0.05), rel=0.05)  # + depth


def test_unseen_parts_come_from_the_reported_class_not_the_object():
    # Nothing visible (completeness 0): the size is the class's mean whatever the object's.
    big = [WorldObject("c", "car", "car", (0, 20, 0.75), 0.0, (5.2, 2.0, 1.8), (1, 1, 1))]
    out = measured_attributes(
        big, seen(1, 1e9, completeness=0.0), 0.0, 0.0, np.random.default_rng(0)
    )
    np.testing.assert_allclose(out.sizes[0], SIZE_SPREADS["car"].mean, rtol=1e-9)


def test_draws_do_not_depend_on_the_rates():
    # The same stream, different rates: whoever is confused at a low rate is confused at a high one.
    objs = objects(5000)
    low = classes(objs, 0.01, np.random.default_rng(4))
    high = classes(objs, 0.2, np.random.default_rng(4))
    truth = [o.cls for o in objs]
    assert all(h != t for lo, h, t in zip(low, high, truth, strict=True) if lo != t)


def test_detection_config_validates_the_new_keys():
    assert DetectionConfig().class_confusion == 0.0075 and DetectionConfig().size_noise == 0.1
    with pytest.raises(ValueError, match="class_confusion must be <= 1"):
        DetectionConfig(class_confusion=1.5)
    with pytest.raises(ValueError, match="size_noise must be >= 0"):
        DetectionConfig(size_noise=-0.1)


def hand_made_view() -> tuple[RenderedView, list[WorldObject], Camera]:
    """Three vehicles 15 m ahead of a 160×120 camera, painted as rectangles into the instance map
    (no renderer needed)."""
    camera = Camera((0.0, 0.0, 1.0), 0.0, width=160, height=120)
    objs = [
        WorldObject(f"v{k}", cls, cls, (15.0, y, 1.0), 0.0, (4.5, 1.8, 1.5), (0.8, 0.1, 0.1))
        for k, (cls, y) in enumerate((("car", 3.0), ("van", 0.0), ("truck", -3.0)))
    ]
    instance = np.full((120, 160), -1, np.int32)
    uv = camera.project(camera.world_to_camera(np.array([o.center for o in objs])))
    for k, (u, v) in enumerate(uv.astype(int)):
        instance[v - 4 : v + 4, u - 6 : u + 6] = k
    color = np.random.default_rng(0).integers(0, 255, (120, 160, 3), dtype=np.uint8)
    depth = np.where(instance >= 0, 15.0, 0.0).astype(np.float32)
    return RenderedView(color, depth, instance), objs, camera


def test_features_carry_the_reported_class():
    """With an attribute stream that confuses everything, a vehicle's attribute one-hot is another
    vehicle class; without a stream it is the true class. Nothing else changes."""
    view, objs, camera = hand_made_view()
    config = DetectionConfig(
        class_confusion=1.0, size_noise=0.0, min_visible_fraction=0.0, max_truncation=1.0
    )
    truthful = detect(view, view.depth, objs, camera, config)
    confused = detect(
        view, view.depth, objs, camera, config, attribute_rng=np.random.default_rng(0)
    )
    assert truthful.object_ids == ["v0", "v1", "v2"]
    onehot = slice(FEATURE_LAYOUT["attributes"].start, FEATURE_LAYOUT["attributes"].start + len(FEATURE_CLASSES))  # fmt: skip
    assert (
        truthful.object_ids == confused.object_ids
        and truthful.true_classes == confused.true_classes
    )
    for k, true_cls in enumerate(truthful.true_classes):
        told = FEATURE_CLASSES[int(np.argmax(truthful.features[k, onehot]))]
        seen = FEATURE_CLASSES[int(np.argmax(confused.features[k, onehot]))]
        assert told == true_cls and seen != true_cls
        assert truthful.reported_classes[k] == told and confused.reported_classes[k] == seen
    # HOG and colour blocks are untouched.
    rest = slice(0, FEATURE_LAYOUT["attributes"].start)
    np.testing.assert_array_equal(truthful.features[:, rest], confused.features[:, rest])
