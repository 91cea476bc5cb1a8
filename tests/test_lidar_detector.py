"""The LiDAR box detector: planted objects recovered within a stated error, blind to the
ground-truth tags, defined on empty and tiny clouds."""

from __future__ import annotations

import inspect
import math

import numpy as np
import pytest
from lidar_scenes import box, car, sensor_pose, snapshot

from cadsim.sensing.box_features import BOX_FEATURE_DIM
from cadsim.sensing.lidar.beam_pattern import PRESETS
from cadsim.sensing.lidar.box_detector import detect_boxes
from cadsim.sensing.lidar.box_truth import box_ground_truth
from cadsim.sensing.lidar.raycast import scan
from cadsim.world import WorldObject

HEIGHT = 1.8
# What the detector promises on an unoccluded object within 40 m (docs/lidar.md): centre within
# 0.35 m on the ground plane, axis within 4 degrees, the right class.
CENTRE_TOL_M = 0.35
YAW_TOL_DEG = 4.0


def _detect(objects, seed=0, pattern="hdl-64e"):
    snap = snapshot(*objects)
    s = scan(snap, sensor_pose(HEIGHT), PRESETS[pattern], np.random.default_rng(seed))
    boxes = detect_boxes(s.points, HEIGHT)
    ids, true = box_ground_truth(
        boxes, s.object_index, [o.id for o in snap.objects], [o.cls for o in snap.objects],
        [o.target for o in snap.objects], "v",
    )  # fmt: skip
    return s, boxes, ids, true


def _axis_error_deg(a: float, b: float) -> float:
    d = math.degrees(abs(a - b)) % 180.0
    return min(d, 180.0 - d)


PLANTED = [
    car("c1", 12.0, 0.0, 0.0),
    car("c2", -9.0, 8.0, 0.7),
    car("c3", 25.0, -14.0, 2.1),
    car("c4", -30.0, -12.0, -0.4),
    box("p1", 6.0, -7.0, (0.5, 0.5, 1.75), cls="person", shape="person"),
    box("v1", 3.0, 20.0, (5.0, 2.0, 2.2), yaw=0.3, cls="van", shape="van"),
]


@pytest.mark.parametrize("seed", [0, 1])
def test_planted_objects_are_recovered_within_the_stated_error(seed):
    _, boxes, ids, true = _detect(PLANTED, seed)
    assert sorted(ids) == sorted(o.id for o in PLANTED)
    by_id = {o.id: o for o in PLANTED}
    for k, oid in enumerate(ids):
        obj = by_id[oid]
        centre = np.array(obj.center[:2])
        assert np.hypot(*(boxes.centres[k, :2] - centre)) < CENTRE_TOL_M, oid
        assert abs(boxes.centres[k, 2] - (obj.center[2] - 0.03 - HEIGHT)) < 0.3, oid
        if obj.cls != "person":
            assert _axis_error_deg(boxes.yaws[k], obj.yaw) < YAW_TOL_DEG, oid
        assert boxes.classes[k] == obj.cls, oid
        assert true[k] == obj.cls


def test_the_view_detections_are_boxes_in_the_camera_frame_convention():
    _, boxes, ids, true = _detect(PLANTED[:1])
    det = boxes.to_view_detections(ids, true)
    # 12 m ahead of the sensor: camera z forward = 12, x right = 0, y down = height - 0.75
    assert np.allclose(det.positions[0], [0.0, HEIGHT + 0.03 - 0.75, 12.0], atol=CENTRE_TOL_M)
    assert det.features.shape == (1, BOX_FEATURE_DIM)
    assert abs(det.headings[0]) < math.radians(YAW_TOL_DEG)
    assert det.reported_classes == ["car"] and det.pixels[0] == boxes.point_counts[0] > 50


def test_the_detector_never_reads_the_ground_truth_tags():
    assert list(inspect.signature(detect_boxes).parameters)[0] == "points"
    # the same scene with its objects renamed and listed in another order: the tags of every
    # point change, the points do not, so neither do the boxes; the ids follow the renaming
    s1, b1, ids1, _ = _detect(PLANTED)
    renamed = [WorldObject(f"x{o.id}", o.cls, o.shape, o.center, o.yaw, o.size, o.color) for o in reversed(PLANTED)]  # fmt: skip
    s2, b2, ids2, _ = _detect(renamed)
    assert not np.array_equal(s1.object_index, s2.object_index)
    assert s1.points.tobytes() == s2.points.tobytes()
    for f in ("centres", "sizes", "yaws", "point_counts", "point_box"):
        assert getattr(b1, f).tobytes() == getattr(b2, f).tobytes()
    assert b1.classes == b2.classes
    assert [f"x{i}" for i in ids1] == ids2


def test_a_wall_is_not_an_object_and_a_split_object_gives_one_true_box():
    wall = box("w", 0.0, 15.0, (30.0, 0.5, 8.0), cls="building", shape="building")
    _, boxes, ids, _ = _detect([wall, PLANTED[0]])
    assert ids == ["c1"]
    # a bus behind a pole: whatever boxes come, at most one carries the bus's id
    bus = box("bus", 20.0, 0.0, (12.0, 2.5, 3.2), yaw=math.pi / 2, cls="bus", shape="bus")
    pole = box("pole", 10.0, 0.0, (0.3, 0.3, 3.0), cls="sign", shape="box")
    _, boxes, ids, true = _detect([bus, pole])
    assert ids.count("bus") <= 1 and len(set(ids)) == len(ids)
    assert all(i in ("bus", "pole") or i.startswith("clutter:lidar:v:") for i in ids)


@pytest.mark.parametrize("n", [0, 1, 2, 3, 4, 5, 6, 10, 50])
def test_empty_and_tiny_clouds_give_defined_results(n):
    rng = np.random.default_rng(n)
    for cloud in (
        rng.uniform(-20, 20, (n, 3)),
        np.zeros((n, 3)),
        np.column_stack([np.linspace(1, 5, n), np.zeros(n), np.zeros(n)]),  # collinear
        np.tile([[8.0, 0.0, -HEIGHT + 1.0]], (n, 1)),  # one spot, n times
    ):
        boxes = detect_boxes(cloud, HEIGHT)
        assert len(boxes.point_box) == n and boxes.centres.shape == (len(boxes), 3)
        assert np.isfinite(boxes.centres).all() and (boxes.sizes > 0).all()
        det = boxes.to_view_detections([f"o{k}" for k in range(len(boxes))], boxes.classes)
        assert len(det) == len(boxes)


def test_bad_clouds_are_rejected_naming_the_argument():
    with pytest.raises(ValueError, match="points: non-finite"):
        detect_boxes(np.array([[1.0, np.nan, 0.0]]), HEIGHT)
    with pytest.raises(ValueError, match=r"points: expected \(n, 3\)"):
        detect_boxes(np.zeros((4, 2)), HEIGHT)


def test_an_all_dropout_frame_gives_no_boxes():
    pattern = PRESETS["hdl-32e"]
    from dataclasses import replace

    s = scan(snapshot(*PLANTED), sensor_pose(HEIGHT), replace(pattern, dropout=1.0), np.random.default_rng(0))  # fmt: skip
    boxes = detect_boxes(s.points, HEIGHT)
    assert len(s) == 0 and len(boxes) == 0
    assert box_ground_truth(boxes, s.object_index, [], [], [], "v") == ([], [])
