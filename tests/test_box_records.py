"""Box-only records: the detections are 3-D boxes (positions, class, size, heading) and nothing
else; the record says so (``cues``), the problem has no pixels, and the pose metrics' inputs
(true relative pose, camera extrinsics) say that the sensor is the LiDAR."""

from __future__ import annotations

import json

import numpy as np
import pytest
from box_fakes import BOXES, two_view_record

from cadsim.dataset import Dataset
from cadsim.dataset.manifest import DatasetError
from cadsim.dataset.regime import dataset_regime
from cadsim.importers.box_dataset import write_box_dataset
from cadsim.sensing.box_features import BOX_CUES, box_feature_vector


@pytest.fixture
def box_dataset(tmp_path):
    write_box_dataset(tmp_path / "ds", [two_view_record(0, 0), two_view_record(1, 0)], "t", {})
    return Dataset(tmp_path / "ds", verify=True)


def test_problem_has_boxes_and_no_pixels(box_dataset):
    pair = box_dataset[0]
    assert pair.cues == BOX_CUES
    problem = pair.problem()
    assert problem.pixels1 is None and problem.pixels2 is None
    assert problem.classes1 == ("car", "bus", "person", "car")
    sizes = np.array([BOXES[i][4:7] for i in ("a", "b", "c", "d")])
    np.testing.assert_array_equal(problem.features1, box_feature_vector(sizes))
    assert pair.gt_pairs.tolist() == [[0, 2], [1, 0], [2, 1]]
    assert pair.view1.headings is not None and pair.view1.headings.shape == (4,)


def test_true_relative_pose_maps_one_sensor_onto_the_other(box_dataset):
    pair = box_dataset[0]
    t = pair.true_relative_pose()
    gt = pair.gt_pairs
    moved = pair.view2.positions[gt[:, 1]] @ t[:3, :3].T + t[:3, 3]
    np.testing.assert_allclose(moved, pair.view1.positions[gt[:, 0]], atol=1e-9)
    # the sensor's mount on its body: 0.75 m body origin below a LiDAR at 1.8 m
    mount = pair.camera_extrinsics[0]
    np.testing.assert_allclose(mount[:3, 3], [0.0, 0.0, 1.05], atol=1e-12)
    np.testing.assert_allclose(mount[:3, :3] @ [0, 0, 1], [1, 0, 0], atol=1e-12)  # z → forward


def test_regime_card_states_the_cues(box_dataset):
    card = dataset_regime(box_dataset)
    assert card["cues"] == "position, class, size, heading"
    assert card["position_error_median_m"] == pytest.approx(0.0, abs=1e-9)


def test_presets_draw_a_prior_on_box_records(box_dataset):
    pair = box_dataset[0].localise_preset("gnss-urban", seed=0)
    world1, world2, sigma = pair.prior()
    assert world1.shape == (4, 3) and sigma > 0
    assert pair.problem().world1 is not None


def test_bad_cues_and_headings_are_refused(tmp_path):
    write_box_dataset(tmp_path / "ds", [two_view_record()], "t", {})
    record = tmp_path / "ds" / "pairs" / "e00000_s00" / "record.json"
    data = json.loads(record.read_text())
    data["cues"] = ["position", "smell"]
    from cadsim.dataset.verification import RecordLayout, check_record_json

    with pytest.raises(DatasetError, match="cues: unknown cues"):
        check_record_json(data, record, RecordLayout(5, 2, ("detections.npz", "record.json")))
