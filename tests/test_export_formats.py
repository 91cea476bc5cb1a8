"""``cadsim export opv2v`` / ``cadsim export kitti``: export then import gives the same
association problems (positions, features, reported classes, ground truth, true relative pose,
prior), and KITTI's 15 columns are the views' boxes in camera coordinates."""

from __future__ import annotations

import numpy as np
import pytest
from format_fixtures import write_opv2v, write_v2x_seq
from test_generate_fakes import FAKE_STAGES, FakeScenario

from cadsim.cli import main
from cadsim.dataset import Dataset
from cadsim.exporters.kitti import export_kitti
from cadsim.exporters.opv2v import export_opv2v
from cadsim.generation.pipeline import generate_dataset
from cadsim.importers.opv2v import import_opv2v
from cadsim.importers.v2x_seq import import_v2x_seq


def _same_problems(a: Dataset, b: Dataset, atol: float = 1e-9) -> None:
    assert (len(a), a.n_views, a.is_sequential) == (len(b), b.n_views, b.is_sequential)
    for pa, pb in zip(a, b, strict=True):
        assert (pa.name, pa.episode, pa.slot, pa.sim_seed) == (
            pb.name,
            pb.episode,
            pb.slot,
            pb.sim_seed,
        )
        x, y = pa.problem(), pb.problem()
        np.testing.assert_allclose(x.points1, y.points1, atol=atol)
        np.testing.assert_allclose(x.points2, y.points2, atol=atol)
        assert x.classes1 == y.classes1 and x.classes2 == y.classes2
        assert np.array_equal(pa.gt_pairs, pb.gt_pairs)
        np.testing.assert_allclose(pa.true_relative_pose(), pb.true_relative_pose(), atol=atol)
        assert (x.world1 is None) == (y.world1 is None)
        if x.world1 is not None:
            np.testing.assert_allclose(x.world1, y.world1, atol=1e-6)
            np.testing.assert_allclose(x.world2, y.world2, atol=1e-6)
            assert x.world_sigma == y.world_sigma
        np.testing.assert_array_equal(x.features1, y.features1)  # sizes come back exactly
        np.testing.assert_array_equal(x.features2, y.features2)


def test_box_sequences_round_trip(tmp_path):
    first = import_v2x_seq(write_v2x_seq(tmp_path / "spd"), tmp_path / "a").out
    export_opv2v(first, tmp_path / "opv2v")
    again = import_opv2v(tmp_path / "opv2v", tmp_path / "b").out
    _same_problems(Dataset(first), Dataset(again))


def test_snapshots_with_a_stored_prior_round_trip(tmp_path):
    first = import_opv2v(write_opv2v(tmp_path / "split"), tmp_path / "a").out
    export_opv2v(first, tmp_path / "opv2v")
    again = import_opv2v(tmp_path / "opv2v", tmp_path / "b").out
    a, b = Dataset(first), Dataset(again)
    _same_problems(a, b)
    for k in range(len(a)):
        for i, j in a.snapshot(k).pairs():
            _same_problems_pair(a.snapshot(k).pair(i, j), b.snapshot(k).pair(i, j))


def _same_problems_pair(pa, pb) -> None:
    np.testing.assert_allclose(pa.problem().points2, pb.problem().points2, atol=1e-9)
    assert np.array_equal(pa.gt_pairs, pb.gt_pairs)


@pytest.fixture
def camera_dataset(tmp_path):
    out = tmp_path / "cam"
    generate_dataset(FakeScenario(), out, pairs=2, workers=1, stages=FAKE_STAGES, progress=False)
    return out


def test_camera_records_export_as_the_same_problems_in_boxes(camera_dataset, tmp_path):
    assert main(["export", "opv2v", str(camera_dataset), "--out", str(tmp_path / "o")]) == 0
    assert (
        main(["import", "opv2v", str(tmp_path / "o"), "--out", str(tmp_path / "b"), "--no-prior"])
        == 0
    )
    cam, boxes = Dataset(camera_dataset), Dataset(tmp_path / "b")
    assert len(cam) == len(boxes)
    for pa, pb in zip(cam, boxes, strict=True):
        x, y = pa.problem(), pb.problem()
        np.testing.assert_allclose(x.points1, y.points1, atol=1e-9)
        np.testing.assert_allclose(x.points2, y.points2, atol=1e-9)
        assert np.array_equal(pa.gt_pairs, pb.gt_pairs) and y.pixels1 is None
        assert pa.view2.object_ids == pb.view2.object_ids and pa.observer_ids == pb.observer_ids
        assert (x.classes1 or tuple(pa.view1.true_classes)) == y.classes1
        np.testing.assert_allclose(pa.true_relative_pose(), pb.true_relative_pose(), atol=1e-9)
        # the record identity and the observers' bodies survive: a preset draws the same prior
        wa = pa.localise(1.2, 0.2, seed=3).prior()
        wb = pb.localise(1.2, 0.2, seed=3).prior()
        np.testing.assert_allclose(wa[0], wb[0], atol=1e-6)
        np.testing.assert_allclose(wa[1], wb[1], atol=1e-6)
    first = sorted((tmp_path / "o").iterdir())[0]
    assert (first / "1" / "000000_camera0.png").is_file()


def test_kitti_labels_are_camera_frame_boxes(tmp_path):
    first = import_v2x_seq(write_v2x_seq(tmp_path / "spd"), tmp_path / "a").out
    export_kitti(first, tmp_path / "kitti")
    ds = Dataset(first)
    lines = (tmp_path / "kitti" / "view1" / "label_2" / "000000.txt").read_text().splitlines()
    assert len(lines) == len(ds[0].view1)
    rows = [line.split() for line in lines]
    assert all(len(r) == 15 for r in rows)
    values = np.array([[float(v) for v in r[1:]] for r in rows])
    h = values[:, 7]
    xyz = values[:, 10:13]
    np.testing.assert_allclose(xyz[:, 1] - h / 2, ds[0].view1.positions[:, 1], atol=1e-5)
    np.testing.assert_allclose(xyz[:, [0, 2]], ds[0].view1.positions[:, [0, 2]], atol=1e-5)
    ry = values[:, 13]
    heading = ds[0].view1.headings
    np.testing.assert_allclose(np.cos(ry), np.sin(heading), atol=1e-5)
    assert {r[0] for r in rows} <= {"Car", "Tram"}
    assert (tmp_path / "kitti" / "records.txt").read_text().startswith("000000 e00010_s00")


def test_a_latency_preset_draws_the_same_prior_after_the_round_trip(camera_dataset, tmp_path):
    export_opv2v(camera_dataset, tmp_path / "o")
    boxes = Dataset(import_opv2v(tmp_path / "o", tmp_path / "b", prior=False).out)
    for pa, pb in zip(Dataset(camera_dataset), boxes, strict=True):
        wa = pa.localise_preset("gnss-urban", seed=5).prior()  # 100 ms latency: velocities move
        wb = pb.localise_preset("gnss-urban", seed=5).prior()
        np.testing.assert_allclose(wa[0], wb[0], atol=1e-6)
        np.testing.assert_allclose(wa[1], wb[1], atol=1e-6)
