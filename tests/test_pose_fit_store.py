"""The pose fits kept beside the result cache (eval.core.pose_fit_store): what a run fitted is
served to the next process for exactly the same inputs, and a file that is not this code's, or
not its digest, is ignored."""

from __future__ import annotations

import numpy as np
import pytest

from eval.core import pose_fit_store, pose_metrics


@pytest.fixture
def fresh_memo(monkeypatch):
    monkeypatch.setattr(pose_metrics, "_PLANAR_MEMO", {})
    monkeypatch.setattr(pose_fit_store, "_saved", 0)


def _fit_inputs(seed: int):
    rng = np.random.default_rng(seed)
    p1 = rng.uniform(-20, 20, (8, 3))
    p2 = p1 + rng.normal(0, 0.2, p1.shape)
    pairs = np.stack([np.arange(8), np.arange(8)], axis=1)
    extrinsics = np.stack([np.eye(4), np.eye(4)])
    return p1, p2, pairs, extrinsics, np.eye(4)


def test_the_next_process_reads_the_fits_instead_of_fitting(tmp_path, fresh_memo, monkeypatch):
    p1, p2, pairs, extrinsics, truth = _fit_inputs(0)
    planar = pose_metrics.matched_planar_error(p1, p2, pairs, extrinsics, truth)
    six = pose_metrics.matched_pose_error(p1, p2, pairs, truth)
    assert pose_fit_store.save(tmp_path) == 2
    monkeypatch.setattr(pose_metrics, "_PLANAR_MEMO", {})  # a new process
    assert pose_fit_store.load(tmp_path) == 2
    monkeypatch.setattr(pose_metrics, "planar_fit", lambda *a: pytest.fail("fitted again"))
    monkeypatch.setattr(pose_metrics, "rigid_fit", lambda *a: pytest.fail("fitted again"))
    assert pose_metrics.matched_planar_error(p1, p2, pairs, extrinsics, truth) == planar
    assert pose_metrics.matched_pose_error(p1, p2, pairs, truth) == six
    # other inputs are not served a stored fit
    with pytest.raises(pytest.fail.Exception, match="fitted again"):
        pose_metrics.matched_planar_error(p1, p2 + 1.0, pairs, extrinsics, truth)


def test_a_tampered_or_foreign_file_is_ignored(tmp_path, fresh_memo, monkeypatch):
    p1, p2, pairs, extrinsics, truth = _fit_inputs(1)
    pose_metrics.matched_planar_error(p1, p2, pairs, extrinsics, truth)
    pose_fit_store.save(tmp_path)
    path = tmp_path / pose_fit_store.FILE
    with np.load(path) as data:
        stored = {k: data[k] for k in data.files}
    stored["values"] = stored["values"] + 1.0  # a changed fit under the old digest
    np.savez(path, **stored)
    monkeypatch.setattr(pose_metrics, "_PLANAR_MEMO", {})
    assert pose_fit_store.load(tmp_path) == 0 and not pose_metrics._PLANAR_MEMO
    monkeypatch.setattr("eval.core.cache.code_version", lambda: "another version")
    pose_metrics.matched_planar_error(p1, p2, pairs, extrinsics, truth)
    pose_fit_store.save(tmp_path)
    monkeypatch.undo()
    monkeypatch.setattr(pose_metrics, "_PLANAR_MEMO", {})
    assert pose_fit_store.load(tmp_path) == 0  # fitted under other code: not served
    path.write_bytes(b"not a file of fits")
    assert pose_fit_store.load(tmp_path) == 0
