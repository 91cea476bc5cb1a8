"""Format 2: the observers' true poses and camera extrinsics round-trip through a dataset, the
detector's attribute errors are the record's own, an older dataset is refused in one clear line,
and ``distinct_observers`` never repeats a pair of observers within an episode."""

from __future__ import annotations

import json
import shutil
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from test_generate_fakes import FAKE_STAGES, FakeScenario

from cadsim.dataset import Dataset, DatasetError
from cadsim.dataset.record_format import FORMAT_VERSION
from cadsim.dataset.seeds import attribute_seed
from cadsim.generation.pipeline import Stages, generate_dataset
from cadsim.observer_pose import ObserverPose
from cadsim.sensing.features import FEATURE_CLASSES, FEATURE_LAYOUT


@pytest.fixture(scope="module")
def fake_dataset(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("poses") / "fake"
    generate_dataset(FakeScenario(), out, pairs=3, workers=1, stages=FAKE_STAGES, progress=False)
    return out


def test_observer_poses_and_extrinsics_round_trip(fake_dataset):
    for pair in Dataset(fake_dataset):
        objects = {o.id: o for o in pair.objects}
        for k, (oid, cam) in enumerate(zip(pair.observer_ids, pair.cameras, strict=True)):
            carrier = objects[oid]
            pose = pair.observer_poses[k]
            assert pose == ObserverPose.of_carrier(carrier)
            assert pose.position == carrier.center and pose.yaw == carrier.yaw
            np.testing.assert_allclose(pose.body_to_world(), carrier.pose(), atol=1e-12)
            # camera -> body -> world equals camera -> world; the rotation stays a rotation.
            T = pair.camera_extrinsics[k]
            np.testing.assert_allclose(pose.body_to_world() @ T, pair.camera_to_world[k], atol=1e-9)
            np.testing.assert_allclose(T[:3, :3] @ T[:3, :3].T, np.eye(3), atol=1e-12)
            # The camera to world transform agrees with the Camera's own mapping.
            p = np.array([[1.0, -2.0, 7.0]])
            world = pair.camera_to_world[k] @ np.append(p[0], 1.0)
            np.testing.assert_allclose(world[:3], cam.camera_to_world(p)[0], atol=1e-9)
            stored = pair.record["observers"][k]
            assert stored["pose"] == {"position": list(carrier.center), "yaw": carrier.yaw}


def test_the_record_keeps_the_attribute_seed_and_redetect_reuses_it(fake_dataset, tmp_path):
    ds = Dataset(fake_dataset)
    pair = ds[0]
    for v in (1, 2):
        stored = pair.record["observers"][v - 1]["attribute_seed"]
        assert stored == attribute_seed(11, pair.episode, pair.slot, v)
    assert ds.manifest["format_version"] == FORMAT_VERSION == 5


def test_redetect_keeps_the_records_attribute_errors_whatever_the_seed(tmp_path):
    """Real noise and detection on fake scenes: features do not depend on redetect's seed at
    rate 0, and attribute errors do appear (a vehicle reported as another class)."""
    scenario = replace(
        FakeScenario(),
        camera={"width": 160, "height": 120, "hfov_deg": 90.0},
        noise={"noise_rate": 0.0},
        detection={"min_pixels": 6, "class_confusion": 0.5, "size_noise": 0.2},
    )
    stages = Stages(source="test_generate_fakes:make_source")  # everything else real
    out = tmp_path / "real"
    generate_dataset(scenario, out, pairs=2, workers=1, stages=stages, progress=False)
    pair = Dataset(out)[0]
    a, b = pair.redetect(0.0, seed=3), pair.redetect(0.0, seed=4)
    assert a.view1.equals(b.view1) and a.view2.equals(b.view2)
    assert a.view1.equals(pair.view1)  # the stored detections (noise rate 0 in this scenario)
    onehot = slice(FEATURE_LAYOUT["attributes"].start, FEATURE_LAYOUT["attributes"].start + len(FEATURE_CLASSES))  # fmt: skip
    reported = [
        FEATURE_CLASSES[int(np.argmax(f[onehot]))]
        for view in (pair.view1, pair.view2)
        for f in view.features
    ]
    truth = pair.view1.true_classes + pair.view2.true_classes
    wrong = sum(r != t for r, t in zip(reported, truth, strict=True))
    assert 0 < wrong < len(truth)  # at rate 0.5 some, not all, are misreported
    # The record keeps what the detector reported beside the truth, and a matcher sees only the
    # reported class: the planted confusion reaches the Problem, the true class does not.
    assert pair.view1.reported_classes + pair.view2.reported_classes == reported
    problem = pair.problem()
    assert list(problem.classes1) + list(problem.classes2) == reported != truth
    assert problem.classes1 == tuple(pair.select(range(len(pair.view1)), []).view1.reported_classes)


def test_an_older_dataset_is_refused_in_one_line_naming_both_versions(fake_dataset, tmp_path):
    old = tmp_path / "old"
    shutil.copytree(fake_dataset, old)
    manifest = json.loads((old / "manifest.json").read_text())
    manifest["format_version"] = 1
    (old / "manifest.json").write_text(json.dumps(manifest))
    with pytest.raises(DatasetError) as info:
        Dataset(old)
    message = str(info.value)
    assert "\n" not in message and str(old) in message
    assert "format version 1 is older than the versions 2, 3, 4, 5, 6 or 7" in message
    assert "regenerate" in message
    manifest["format_version"] = 8
    (old / "manifest.json").write_text(json.dumps(manifest))
    with pytest.raises(DatasetError, match="version 8 is not the versions 2, 3, 4, 5, 6 or 7"):
        Dataset(old)


def test_distinct_observers_never_repeat_a_pair_of_vehicles(tmp_path):
    # The fake source offers the same two vehicles (obs1, obs2) in every snapshot.
    repeated = tmp_path / "repeated"
    sampling = {"pairs_per_episode": 3, "pairs_per_snapshot": 2}
    generate_dataset(
        replace(FakeScenario(), sampling=sampling), repeated, pairs=3, workers=1,
        stages=FAKE_STAGES, progress=False,
    )  # fmt: skip
    names = [{*p.observer_ids} for p in Dataset(repeated)]
    assert names.count({"obs1", "obs2"}) == 3
    distinct = tmp_path / "distinct"
    generate_dataset(
        replace(FakeScenario(), sampling=sampling | {"distinct_observers": True}), distinct,
        pairs=3, workers=1, stages=FAKE_STAGES, progress=False,
    )  # fmt: skip
    ds = Dataset(distinct)
    by_episode: dict[int, list] = {}
    for pair in ds:
        by_episode.setdefault(pair.episode, []).append(frozenset(pair.observer_ids))
    assert len(ds) == 3 and len(by_episode) == 3  # one record per episode, the rest repeats
    for keys in by_episode.values():
        assert len(keys) == len(set(keys))


def test_generating_into_an_older_dataset_says_to_use_a_new_folder(fake_dataset, tmp_path):
    from cadsim.generation.pipeline import GenerationError

    old = tmp_path / "old"
    shutil.copytree(fake_dataset, old)
    manifest = json.loads((old / "manifest.json").read_text())
    manifest["format_version"] = 1
    (old / "manifest.json").write_text(json.dumps(manifest))
    with pytest.raises(GenerationError, match="version 1 is older.*use a new --out"):
        generate_dataset(
            FakeScenario(), old, pairs=3, workers=1, stages=FAKE_STAGES, progress=False
        )
