"""Attributes as a detector sees them: seeded class confusion at the configured rate, within
confusion groups, log-normal size noise, and its place in the features."""

from __future__ import annotations

import numpy as np
import pytest

from cadsim.camera import Camera
from cadsim.render.view import RenderedView
from cadsim.sensing.attribute_noise import CONFUSION_GROUPS, perceived_attributes
from cadsim.sensing.detection import DetectionConfig, detect
from cadsim.sensing.features import FEATURE_CLASSES, FEATURE_LAYOUT
from cadsim.world import WorldObject

CLASSES = ("car", "van", "bus", "truck", "bicycle", "person", "traffic_light", "sign", "building")


def objects(n: int) -> list[WorldObject]:
    return [
        WorldObject(f"o{k}", CLASSES[k % len(CLASSES)], "box", (0, 0, 1), 0.0, (4.0, 2.0, 1.5), (1, 1, 1))
        for k in range(n)
    ]  # fmt: skip


def test_confusion_is_seeded_and_at_the_configured_rate():
    objs = objects(90_000)
    truth = np.array([o.cls for o in objs])
    grouped = np.isin(truth, [c for g in CONFUSION_GROUPS for c in g])
    for rate in (0.0075, 0.05):
        cls, _ = perceived_attributes(objs, rate, 0.1, np.random.default_rng(1))
        again, _ = perceived_attributes(objs, rate, 0.1, np.random.default_rng(1))
        other, _ = perceived_attributes(objs, rate, 0.1, np.random.default_rng(2))
        assert cls == again and cls != other
        wrong = np.array(cls) != truth
        assert not wrong[~grouped].any()  # buildings are in no group: never confused
        measured = wrong[grouped].mean()
        assert measured == pytest.approx(rate, abs=4 * np.sqrt(rate / grouped.sum()))


def test_two_views_disagree_about_twice_the_rate_and_only_within_groups():
    objs = objects(90_000)
    cls1, _ = perceived_attributes(objs, 0.0075, 0.0, np.random.default_rng(10))
    cls2, _ = perceived_attributes(objs, 0.0075, 0.0, np.random.default_rng(11))
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
    seen = {
        perceived_attributes([car], 1.0, 0.0, np.random.default_rng(s))[0][0] for s in range(60)
    }
    assert seen == {"van", "bus", "truck"}


def test_size_noise_is_log_normal_with_the_configured_spread():
    objs = objects(20_000)
    _, size = perceived_attributes(objs, 0.0, 0.1, np.random.default_rng(3))
    log_ratio = np.log(size / np.array([o.size for o in objs]))
    assert (size > 0).all()
    assert log_ratio.std() == pytest.approx(0.1, rel=0.03)
    assert abs(log_ratio.mean()) < 0.005
    _, exact = perceived_attributes(objs, 0.0, 0.0, np.random.default_rng(3))
    np.testing.assert_array_equal(exact, [o.size for o in objs])


def test_draws_do_not_depend_on_the_rates():
    # The same stream, different rates: whoever is confused at a low rate is confused at a high one.
    objs = objects(5000)
    low, _ = perceived_attributes(objs, 0.01, 0.1, np.random.default_rng(4))
    high, _ = perceived_attributes(objs, 0.2, 0.1, np.random.default_rng(4))
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
