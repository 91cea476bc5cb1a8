"""``cadsim import v2x-seq`` and ``cadsim import opv2v`` on folders written to the published
layouts: ground truth from the shared track / actor ids, the true relative pose from the
calibration, sequences kept, the stored prior from ``predicted_ego_pos``."""

from __future__ import annotations

import numpy as np
import pytest
from format_fixtures import ACTOR, AGENT_SEES, WORLD, write_opv2v, write_v2x_seq

from cadsim.cli import main
from cadsim.dataset import Dataset
from cadsim.importers.opv2v import import_opv2v
from cadsim.importers.v2x_seq import import_v2x_seq
from cadsim.sensing.box_features import BOX_CUES


def _aligned(pair) -> float:
    """Largest distance (m) between view 1's boxes and view 2's moved by the true pose."""
    t = pair.true_relative_pose()
    gt = pair.gt_pairs
    moved = pair.view2.positions[gt[:, 1]] @ t[:3, :3].T + t[:3, 3]
    return float(np.abs(moved - pair.view1.positions[gt[:, 0]]).max())


def test_v2x_seq_frames_become_a_sequence_of_box_pairs(tmp_path):
    result = import_v2x_seq(write_v2x_seq(tmp_path / "spd"), tmp_path / "out")
    ds = Dataset(result.out, verify=True)
    assert (len(ds), ds.sequences, ds.is_sequential) == (3, 1, True)
    frames = ds.sequence(0)
    assert [p.frame for p in frames] == [0, 1, 2] and frames[0].episode == 10
    for pair, boxes in zip(frames, WORLD, strict=True):
        assert pair.cues == BOX_CUES and pair.problem().pixels1 is None
        assert pair.observer_kinds == ("vehicle", "roadside")
        shared = {"a", "b", "c"}  # seen by both sides; "d" vehicle only, "e" roadside only
        assert len(pair.gt_pairs) == len(shared)
        assert _aligned(pair) < 1e-6  # calibration (with the system error offset) is the truth
        assert pair.record["meta"]["time_offset_s"] == pytest.approx(0.03)
        assert len(pair.view1) == len({"a", "b", "c", "d"} & set(boxes))
    # "d" leaves at frame 1 and returns with the same object id
    assert "v000100" in frames[0].view1.object_ids and "v000100" in frames[2].view1.object_ids
    assert "v000100" not in frames[1].view1.object_ids
    assert frames[0].record["sequence"]["interval_s"] == pytest.approx(0.1)


def test_opv2v_three_agents_become_snapshots_with_shared_actor_ids(tmp_path):
    result = import_opv2v(write_opv2v(tmp_path / "split"), tmp_path / "out")
    ds = Dataset(result.out, verify=True)
    assert (ds.n_views, len(ds)) == (3, 3)
    snap = ds.snapshot(0)
    assert snap.kinds == ["vehicle", "vehicle", "roadside"]
    assert snap.observer_ids == ["3", "7", "-1"]
    for i, j in snap.pairs():
        pair = snap.pair(i, j)
        seen = [AGENT_SEES[int(a)] for a in (snap.observer_ids[i - 1], snap.observer_ids[j - 1])]
        assert len(pair.gt_pairs) == len(seen[0] & seen[1] & set(WORLD[0]))
        assert _aligned(pair) < 1e-6
    assert str(ACTOR["a"]) in snap.view(1).object_ids
    prior = snap.pair(1, 2).prior()  # predicted_ego_pos equals the true pose here: exact
    assert prior is not None and prior[2] == 1.0


def test_opv2v_two_agents_are_kept_as_sequences(tmp_path):
    write_opv2v(tmp_path / "split", agents=(7, -1))
    ds = Dataset(import_opv2v(tmp_path / "split", tmp_path / "out", prior=False).out, verify=True)
    assert (ds.n_views, ds.sequences, len(ds.sequence(0))) == (2, 1, 3)
    pair = ds.sequence(0)[2]
    assert pair.prior() is None and pair.observer_kinds == ("vehicle", "roadside")
    odometry = pair.odometry[0]  # the body moved 0.3 m along world x per frame, heading 0.1 rad
    assert (odometry.x, odometry.y) == pytest.approx((0.6 * np.cos(0.1), -0.6 * np.sin(0.1)))
    assert odometry.distance_m == pytest.approx(0.6)
    assert _aligned(pair) < 1e-6


def test_v2v4real_rotation_translation_poses_read_as_the_same_geometry(tmp_path):
    a = import_opv2v(write_opv2v(tmp_path / "a", agents=(7, 3)), tmp_path / "out-a")
    b = import_opv2v(write_opv2v(tmp_path / "b", v2v4real=True, agents=(7, 3)), tmp_path / "out-b")
    for pa, pb in zip(Dataset(a.out), Dataset(b.out), strict=True):
        np.testing.assert_allclose(pa.view1.positions, pb.view1.positions, atol=1e-9)
        np.testing.assert_allclose(pa.true_relative_pose(), pb.true_relative_pose(), atol=1e-9)


def test_cli_imports_and_reports(tmp_path, capsys):
    src = write_v2x_seq(tmp_path / "spd")
    assert main(["import", "v2x-seq", str(src), "--out", str(tmp_path / "out")]) == 0
    assert "3 frame pairs in 1 episodes, box-only" in capsys.readouterr().out
    assert main(["info", str(tmp_path / "out")]) == 0
    assert "position, class, size, heading" in capsys.readouterr().out


def test_same_input_same_bytes(tmp_path):
    src = write_opv2v(tmp_path / "split")
    a = import_opv2v(src, tmp_path / "a")
    b = import_opv2v(src, tmp_path / "b")
    assert a.checksum == b.checksum
    for rec in sorted((tmp_path / "a" / "pairs").iterdir()):
        for f in rec.iterdir():
            assert f.read_bytes() == (tmp_path / "b" / "pairs" / rec.name / f.name).read_bytes()


def test_an_interrupted_import_leaves_no_dataset(tmp_path, monkeypatch):
    import cadsim.importers.box_dataset as writer

    def interrupted(path, data):
        raise KeyboardInterrupt

    monkeypatch.setattr(writer, "write_file_atomic", interrupted)  # the manifest, written last
    with pytest.raises(KeyboardInterrupt):
        import_v2x_seq(write_v2x_seq(tmp_path / "spd"), tmp_path / "out")
    assert not (tmp_path / "out" / "manifest.json").exists()
    with pytest.raises(ValueError):
        Dataset(tmp_path / "out")
