"""The regime card (``cadsim.dataset.regime``) on hand-built frame pairs with known answers, and
as ``cadsim info --json`` reports it."""

from __future__ import annotations

import json
from dataclasses import dataclass

import numpy as np
import pytest
from test_generate_fakes import FAKE_STAGES, FakeScenario

from cadsim.camera import Camera
from cadsim.cli import main
from cadsim.dataset import Dataset, ViewDetections, ground_truth_pairs
from cadsim.dataset.regime import REGIME_KEYS, dataset_regime, roc_auc
from cadsim.generation.pipeline import generate_dataset
from cadsim.observer_pose import camera_to_world


def view(ids, positions, features) -> ViewDetections:
    k = len(ids)
    return ViewDetections(positions, np.zeros((k, 4)), features, list(ids), ["car"] * k, np.ones(k))


@dataclass
class Pair:
    view1: ViewDetections
    view2: ViewDetections
    camera_to_world: tuple | None = None

    @property
    def gt_pairs(self):
        return ground_truth_pairs(self.view1, self.view2)


def test_counts_and_shares():
    eye = np.eye(4, dtype=np.float32)
    a = Pair(
        view(["a", "b", "c", "x"], np.zeros((4, 3)), eye),
        view(["c", "b", "a"], np.zeros((3, 3)), eye[[2, 1, 0], :]),
    )  # 4 and 3 objects, 3 covisible
    b = Pair(view(["p", "q"], np.zeros((2, 3)), eye[:2]), view(["r"], np.zeros((1, 3)), eye[:1]))
    r = dataset_regime([a, b])
    assert r["pairs"] == 2 and r["objects_per_view"] == pytest.approx((4 + 3 + 2 + 1) / 4)
    assert r["covisible"] == pytest.approx(1.5)
    assert r["noncovisible_share"] == pytest.approx((10 - 6) / 10)
    assert r["covisible_share_of_smaller"] == pytest.approx((3 / 3 + 0 / 1) / 2)
    # True pairs have identical one-hot features (cosine 1), the 11 false ones are orthogonal (0)
    # except b's (p, r), which look alike without being the same object (1, a tie): 10.5 / 11.
    assert r["appearance_auc"] == pytest.approx(10.5 / 11)
    assert r["position_error_median_m"] is None  # no true poses


def test_auc_reads_as_a_probability():
    assert roc_auc([0.9, 0.8], [0.1, 0.2]) == 1.0
    assert roc_auc([0.1], [0.9]) == 0.0
    assert roc_auc([0.5], [0.5]) == 0.5
    assert roc_auc([], [0.3]) is None


def test_position_error_uses_the_true_relative_pose():
    c1 = Camera((0.0, 0.0, 1.5), 0.0)
    c2 = Camera((20.0, 5.0, 1.5), np.radians(150.0))
    world = np.array([[10.0, 1.0, 0.8], [12.0, -3.0, 0.8], [8.0, 4.0, 1.2]])
    offset = np.array([[0.0, 0.0, 0.0], [0.3, 0.0, 0.0], [0.0, 0.4, 0.0]])  # errors 0, .3, .4
    feats = np.ones((3, 2), np.float32)
    pair = Pair(
        view(["a", "b", "c"], c1.world_to_camera(world), feats),
        view(["a", "b", "c"], c2.world_to_camera(world + offset), feats),
        (camera_to_world(c1), camera_to_world(c2)),
    )
    assert dataset_regime([pair])["position_error_median_m"] == pytest.approx(0.3)


def test_empty_dataset_has_no_regime():
    assert dataset_regime([]) == {"pairs": 0} | dict.fromkeys(REGIME_KEYS) | {"cues": None}


def test_info_json_reports_the_regime(tmp_path, capsys):
    out = tmp_path / "fake"
    generate_dataset(FakeScenario(), out, pairs=2, workers=1, stages=FAKE_STAGES, progress=False)
    assert main(["info", str(out), "--json"]) == 0
    reported = json.loads(capsys.readouterr().out)["regime"]
    assert reported == pytest.approx(dataset_regime(Dataset(out)))
    assert set(REGIME_KEYS) <= set(reported) and reported["position_error_median_m"] is not None
    assert main(["info", str(out)]) == 0
    assert "non-covisible share" in capsys.readouterr().out


def test_the_image_auc_leaves_out_the_detectors_class_and_size():
    from cadsim.dataset.regime import image_similarity
    from cadsim.sensing.features import FEATURE_DIM, FEATURE_LAYOUT

    rng = np.random.default_rng(0)
    f1, f2 = rng.random((4, FEATURE_DIM)), rng.random((5, FEATURE_DIM))
    before = image_similarity(f1, f2)
    f2[:, FEATURE_LAYOUT["attributes"]] = rng.random((5, 15))  # other classes and sizes
    np.testing.assert_array_equal(image_similarity(f1, f2), before)
    f2[:, FEATURE_LAYOUT["hog"]] = 0.0
    assert not np.allclose(image_similarity(f1, f2), before)
    # a descriptor of another width (imported data) is an image descriptor as a whole
    g1, g2 = rng.random((3, 900)), rng.random((2, 900))
    from cadsim.dataset.regime import cosine_similarity

    np.testing.assert_array_equal(image_similarity(g1, g2), cosine_similarity(g1, g2))


def test_the_same_class_auc_reads_only_look_alike_false_pairs():
    """Features that tell classes apart but nothing within a class: the pooled AUC is high, the
    AUC against same-class false pairs is at chance."""
    rng = np.random.default_rng(0)
    pairs = []
    for _ in range(20):
        ids = [f"o{k}" for k in range(6)]
        classes = ["car", "car", "car", "sign", "sign", "sign"]
        onehot = np.array([[1.0, 0.0] if c == "car" else [0.0, 1.0] for c in classes])
        f1 = np.hstack([onehot, rng.random((6, 4))]).astype(np.float32)
        f2 = np.hstack([onehot, rng.random((6, 4))]).astype(np.float32)
        v1 = ViewDetections(np.zeros((6, 3)), np.zeros((6, 4)), f1, ids, classes, np.ones(6))
        v2 = ViewDetections(np.zeros((6, 3)), np.zeros((6, 4)), f2, ids, classes, np.ones(6))
        pairs.append(Pair(v1, v2))
    card = dataset_regime(pairs)
    assert card["appearance_auc"] > 0.75
    assert abs(card["same_class_auc"] - 0.5) < 0.1
