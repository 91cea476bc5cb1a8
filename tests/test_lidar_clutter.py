"""Roadside clutter meets the LiDAR detector: trees, poles and parked trailers give boxes, and
every false positive names its source (``box_truth.false_positive_source``); the regime card
splits the false-positive share by source."""

from __future__ import annotations

import numpy as np
from lidar_scenes import car, sensor_pose, snapshot

from cadsim.dataset.lidar_regime import sources_text
from cadsim.sensing.lidar.beam_pattern import PRESETS
from cadsim.sensing.lidar.box_detector import detect_boxes
from cadsim.sensing.lidar.box_truth import box_ground_truth, false_positive_source
from cadsim.world import WorldObject

HEIGHT = 1.8


def _prop(oid: str, cls: str, shape: str, x: float, y: float, size) -> WorldObject:
    """A non-target roadside object standing on the ground at (x, y), world metres."""
    return WorldObject(oid, cls, shape, (x, y, size[2] / 2), 0.0, size, (0.3, 0.5, 0.3), target=False)  # fmt: skip


def test_roadside_clutter_gives_boxes_whose_source_is_attributed():
    from cadsim.sensing.lidar.raycast import scan

    objects = [
        car("c1", 12.0, 0.0),
        _prop("roadside:tree:e:0", "tree", "tree", 8.0, 8.0, (2.4, 2.4, 4.0)),
        _prop("roadside:pole:e:1", "pole", "cylinder", 10.0, -6.0, (0.3, 0.3, 3.6)),
        _prop("roadside:trailer:e:2", "trailer", "box", -12.0, 6.0, (4.0, 2.1, 2.2)),
    ]
    snap = snapshot(*objects)
    s = scan(snap, sensor_pose(HEIGHT), PRESETS["hdl-64e"], np.random.default_rng(0))
    boxes = detect_boxes(s.points, HEIGHT)
    ids, true = box_ground_truth(
        boxes, s.object_index, [o.id for o in objects], [o.cls for o in objects],
        [o.target for o in objects], "v",
    )  # fmt: skip
    assert "c1" in ids
    sources = {false_positive_source(i) for i in ids if i.startswith("clutter:")}
    assert {"tree", "pole", "trailer"} <= sources  # each prop is met and named
    for i, cls, reported in zip(ids, true, boxes.classes, strict=True):
        if i.startswith("clutter:"):
            assert cls == reported  # a false positive's "true" class is what was reported
    assert false_positive_source("c1") is None
    assert false_positive_source("clutter:lidar:v:3") is None  # made before sources were named


def test_sources_are_written_largest_first():
    assert sources_text({"building": 0.12, "tree": 0.04}) == "building 12%; tree 4%"
    assert sources_text({}) == "-"


def test_the_scene_places_clutter_clear_of_roads_and_furniture(tmp_path):
    from cadsim.scenario import load_scenario
    from cadsim.sources.sumo.source import SumoSource

    root = __import__("pathlib").Path(__file__).resolve().parents[1]
    source = SumoSource(load_scenario(root / "scenarios" / "cad-v2x-lidar.toml"), 11, tmp_path)
    try:
        props = [o for o in source.static.objects if o.id.startswith("roadside:")]
        again = SumoSource(load_scenario(root / "scenarios" / "cad-v2x-lidar.toml"), 12, tmp_path)
        assert [o.as_dict() for o in again.static.objects if o.id.startswith("roadside:")] == [
            o.as_dict() for o in props
        ]  # placed from the scenario seed, the same in every episode
        again.close()
    finally:
        source.close()
    kinds = {o.cls for o in props}
    assert kinds == {"tree", "pole", "bin", "trailer"} and all(not o.target for o in props)
    assert len({o.size for o in props}) == len(props)  # each its own size
    furniture = np.array([o.center[:2] for o in source.static.objects if o.cls == "sign"])
    xy = np.array([o.center[:2] for o in props])
    gap = np.linalg.norm(xy[:, None] - furniture[None], axis=2).min()
    assert gap > 1.5
