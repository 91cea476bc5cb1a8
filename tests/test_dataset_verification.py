"""Issue 15 #2: a record changed after generation is caught when the dataset is opened for
evaluation, even when the result cache already holds the runs of the original (its key is the
manifest's checksum, which a tampered record does not change)."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from test_generate_fakes import FAKE_STAGES, FakeScenario

from cadsim.cli import main
from cadsim.dataset import Dataset, DatasetError
from cadsim.dataset.encoding import load_npz, npz_bytes
from cadsim.generation.pipeline import generate_dataset


@pytest.fixture(scope="module")
def pristine(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("verify") / "ds"
    generate_dataset(FakeScenario(), out, pairs=3, workers=1, stages=FAKE_STAGES, progress=False)
    return out


@pytest.fixture
def dataset(pristine, tmp_path) -> Path:
    copy = tmp_path / "ds"
    shutil.copytree(pristine, copy)
    return copy


def _evaluate(dataset: Path, tmp_path: Path) -> int:
    return main(
        ["evaluate", str(dataset), "--no-calibration", "--matchers", "sm", "--runs", "1"]
        + ["--workers", "1", "--out", str(tmp_path / "res"), "--cache", str(tmp_path / "cache")]
    )


def _tamper(record: Path) -> None:
    """Rewrite detections.npz with valid, different detections (manifest untouched)."""
    path = record / "detections.npz"
    arrays = load_npz(str(path), str(path))
    arrays["view1_positions"] = arrays["view1_positions"] + 0.5
    path.write_bytes(npz_bytes(arrays))


def test_rewritten_detections_are_refused_even_with_a_warm_cache(dataset, tmp_path, capsys):
    assert _evaluate(dataset, tmp_path) == 0  # verifies, computes, caches
    assert any((tmp_path / "cache").rglob("*.npz"))
    capsys.readouterr()
    _tamper(dataset / "pairs" / "e00000_s01")
    assert _evaluate(dataset, tmp_path) == 2  # same process, same cache: still caught
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1
    assert "e00000_s01" in err[0] and "checksum mismatch" in err[0]


def test_truncated_record_is_one_line_in_evaluate_and_sweep_noise(dataset, tmp_path, capsys):
    path = dataset / "pairs" / "e00001_s00" / "detections.npz"
    path.write_bytes(path.read_bytes()[:100])
    assert _evaluate(dataset, tmp_path) == 2
    sweep = ["sweep-noise", str(dataset), "--rates", "0,0.01", "--matchers", "sm", "--runs", "1"]
    sweep += ["--workers", "1", "--out", str(tmp_path / "sw"), "--cache", str(tmp_path / "c")]
    assert main(sweep) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 2 and all("e00001_s00" in line for line in lines)
    assert lines[1].startswith("cadsim sweep-noise: error: ")


def test_verification_is_skipped_for_unchanged_files_and_redone_after_a_change(dataset):
    ds = Dataset(dataset, verify=True)
    calls = []
    original = Dataset.verify

    def counting(self):
        calls.append(self.path)
        original(self)

    Dataset.verify = counting
    try:
        Dataset(dataset, verify=True)  # unchanged: no re-hash in this process
        assert calls == []
        _tamper(dataset / "pairs" / "e00000_s00")
        with pytest.raises(DatasetError, match="e00000_s00: checksum mismatch"):
            Dataset(dataset, verify=True)
        assert len(calls) == 1
    finally:
        Dataset.verify = original
    assert len(ds) == 3


def test_truncated_cache_entry_is_recomputed(dataset, tmp_path, capsys):
    assert _evaluate(dataset, tmp_path) == 0
    entries = list((tmp_path / "cache").rglob("*.npz"))
    assert entries
    for entry in entries:
        entry.write_bytes(entry.read_bytes()[: entry.stat().st_size // 2])
    metrics = tmp_path / "res" / "metrics_per_pair.csv"
    before = pd.read_csv(metrics).drop(columns="time_s")
    assert _evaluate(dataset, tmp_path) == 0  # recomputed (timings differ), not an error
    pd.testing.assert_frame_equal(pd.read_csv(metrics).drop(columns="time_s"), before)
    for entry in entries:
        with np.load(entry) as data:  # complete again
            assert "meta" in data.files
