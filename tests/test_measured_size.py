"""Sizes the camera detector measures from what it sees (planted objects, rendered): a truncated,
occluded or distant object's reported size is further from its true size than a near, fully
visible one's, and the surface-to-centre shift reads the detector's estimate, never the true
size or heading."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from render_fixtures import cam

from cadsim.sensing.detection import DetectionConfig, detect, plan_detections
from cadsim.sensing.features import reported_sizes
from cadsim.world import Snapshot, WorldObject

pytestmark = pytest.mark.render

CONFIG = DetectionConfig(
    class_confusion=0.0,
    size_noise=0.1,
    min_pixels=10,
    max_truncation=0.8,
    min_visible_fraction=0.05,
)
DRAWS = 40


def car(oid: str, x: float, y: float, yaw: float = np.pi / 2) -> WorldObject:
    return WorldObject(oid, "car", "car", (x, y, 0.76), yaw, (4.6, 1.85, 1.52), (0.8, 0.1, 0.1))


def wall(x: float, y: float) -> WorldObject:
    return WorldObject("w", "building", "building", (x, y, 2.0), 0.0, (0.5, 3.0, 4.0), (0.6, 0.55, 0.5), target=False)  # fmt: skip


def size_error(renderer, objects, target: str, camera=None) -> float:
    """Mean over DRAWS attribute streams of Σ |log(reported / true)| over the three dimensions."""
    camera = camera or cam()
    view = renderer.render(Snapshot(0.0, objects), camera)
    true = np.log(next(o for o in objects if o.id == target).size)
    errors = []
    for seed in range(DRAWS):
        dets = detect(view, view.depth, objects, camera, CONFIG, np.random.default_rng(seed))
        assert target in dets.object_ids, "the planted object must be detected"
        k = dets.object_ids.index(target)
        errors.append(np.abs(np.log(reported_sizes(dets.features)[k]) - true).sum())
    return float(np.mean(errors))


def test_far_truncated_and_occluded_objects_get_worse_sizes(renderer):
    near = size_error(renderer, [car("c", 12.0, 0.0)], "c")
    far = size_error(renderer, [car("c", 60.0, 0.0)], "c")
    # at the left border of the image (a 90° field of view: 45° to the side), about half out
    truncated = size_error(renderer, [car("c", 12.0, 12.5)], "c")
    occluded = size_error(renderer, [car("c", 16.0, 0.0), wall(10.0, 1.2)], "c")
    assert near < 0.5  # a near, fully seen car: within ≈ 15 % per dimension
    assert far > near + 0.1 and truncated > near + 0.1 and occluded > near + 0.1


def test_the_centre_shift_reads_the_estimate_not_the_true_size(renderer):
    camera = cam()
    objects = [car("c", 15.0, 2.0, yaw=0.4), car("d", 25.0, -3.0)]
    view = renderer.render(Snapshot(0.0, objects), camera)
    plan = plan_detections(
        view.instance, view.depth, objects, camera, CONFIG, lambda: view.color,
        np.random.default_rng(7),
    )  # fmt: skip
    assert len(plan) == 2
    before = plan.locate(view.depth).positions
    # The same plan with every object's true size and heading replaced: nothing moves.
    plan.objects = [dataclasses.replace(o, size=(9.0, 4.0, 3.0), yaw=o.yaw + 1.0) for o in plan.objects]  # fmt: skip
    np.testing.assert_array_equal(plan.locate(view.depth).positions, before)
    # The shift follows the estimate: a larger estimated box puts the centre further back.
    plan.estimates = plan.estimates * [2.0, 2.0, 1.0, 1.0]
    after = plan.locate(view.depth).positions
    assert (np.linalg.norm(after, axis=1) > np.linalg.norm(before, axis=1) + 0.3).all()
