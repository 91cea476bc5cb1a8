"""Record format: byte-exact encoders, checksums, atomic writes, ViewDetections, the reader's errors."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from test_generate_fakes import FAKE_STAGES, FakeScenario

from cadsim.dataset import Dataset, DatasetError, ViewDetections, ground_truth_pairs, layout
from cadsim.dataset.atomic_writer import remove_stale_temp, write_file_atomic, write_record
from cadsim.dataset.checksum import dataset_checksum, record_checksum
from cadsim.dataset.detections import is_acceptable_pair
from cadsim.dataset.encoding import decode_png, json_bytes, load_npz, npz_bytes, png_bytes
from cadsim.dataset.seeds import noise_seed, simulation_seed
from cadsim.generation.pipeline import generate_dataset

REPO = Path(__file__).resolve().parents[1]


def _view(ids, seed=0, d=5):
    rng = np.random.default_rng(seed)
    k = len(ids)
    return ViewDetections(
        positions=rng.normal(size=(k, 3)),
        boxes=rng.uniform(0, 100, size=(k, 4)),
        features=rng.uniform(size=(k, d)).astype(np.float32),
        object_ids=list(ids),
        true_classes=["car"] * k,
        pixels=rng.integers(1, 500, size=k),
    )


def test_npz_bytes_are_reproducible_and_round_trip(tmp_path):
    arrays = {"a": np.arange(12, dtype=np.float32).reshape(3, 4), "ids": np.array(["x", "yy"])}
    first = npz_bytes(arrays)
    assert npz_bytes(arrays) == first  # no timestamps: same content, same bytes
    back = load_npz(first, "test.npz")
    assert list(back) == ["a", "ids"]
    np.testing.assert_array_equal(back["a"], arrays["a"])
    assert back["ids"].tolist() == ["x", "yy"]
    with pytest.raises(TypeError, match="object arrays"):
        npz_bytes({"bad": np.array([{}, None], dtype=object)})
    with pytest.raises(ValueError, match="broken.npz: not a readable"):
        load_npz(b"not a zip", "broken.npz")


def test_json_and_png_encoding():
    assert json_bytes({"b": 1, "a": [1.5]}) == json_bytes({"a": [1.5], "b": 1})
    img = np.random.default_rng(0).integers(0, 256, size=(7, 9, 3), dtype=np.uint8)
    data = png_bytes(img)
    assert data == png_bytes(img)
    np.testing.assert_array_equal(decode_png(data, "x.png"), img)  # RGB order preserved
    with pytest.raises(ValueError, match="expected \\(H, W, 3\\) uint8"):
        png_bytes(img.astype(np.float32))


def test_checksums_depend_on_names_contents_and_order():
    a = record_checksum({"x": b"1", "y": b"2"})
    assert a == record_checksum({"y": b"2", "x": b"1"})
    assert a != record_checksum({"x": b"1", "y": b"3"})
    assert a != record_checksum({"x": b"1", "z": b"2"})
    b = record_checksum({"x": b"9"})
    assert dataset_checksum([a, b]) != dataset_checksum([b, a])


def test_seeds_are_distinct_and_stable():
    assert simulation_seed(5, 0) == simulation_seed(5, 0)
    sims = {simulation_seed(5, e) for e in range(50)}
    assert len(sims) == 50 and all(0 <= s < 2**31 for s in sims)
    assert simulation_seed(5, 1) != simulation_seed(6, 1)
    noises = {noise_seed(5, e, s, v) for e in range(5) for s in range(5) for v in (1, 2)}
    assert len(noises) == 50
    with pytest.raises(ValueError, match="seed: expected a non-negative integer"):
        simulation_seed(-1, 0)


def test_write_record_is_all_or_nothing(tmp_path, monkeypatch):
    files = {"a.bin": b"a" * 100, "b.bin": b"b" * 100}
    assert write_record(tmp_path, "e00000_s00", files)
    assert not write_record(tmp_path, "e00000_s00", {"other": b""})  # existing record kept
    assert sorted(p.name for p in (tmp_path / "pairs" / "e00000_s00").iterdir()) == [
        "a.bin",
        "b.bin",
    ]

    # A crash while writing the second file leaves no record and no temp dir.
    import cadsim.dataset.atomic_writer as aw

    real = aw._write_synced
    calls = []

    def failing(path, data, shown=None):
        calls.append(path.name)
        if len(calls) == 2:
            raise OSError("disk full")
        real(path, data, shown)

    monkeypatch.setattr(aw, "_write_synced", failing)
    with pytest.raises(OSError, match="disk full"):
        write_record(tmp_path, "e00000_s01", files)
    assert not (tmp_path / "pairs" / "e00000_s01").exists()
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(layout.TEMP_PREFIX)]


def test_remove_stale_temp_and_atomic_file(tmp_path):
    (tmp_path / ".tmp-e00001_s00-123-abc").mkdir()
    (tmp_path / ".tmp-e00001_s00-123-abc" / "view1.png").write_bytes(b"half")
    (tmp_path / "episodes").mkdir()
    (tmp_path / "episodes" / ".tmp-e00001.json-1-x").write_bytes(b"{")
    assert remove_stale_temp(tmp_path) == [".tmp-e00001.json-1-x", ".tmp-e00001_s00-123-abc"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["episodes"]
    write_file_atomic(tmp_path / "m.json", b"1")
    write_file_atomic(tmp_path / "m.json", b"2")
    assert (tmp_path / "m.json").read_bytes() == b"2"


def test_layout_names_round_trip():
    assert layout.record_name(3, 1) == "e00003_s01"
    assert layout.parse_record_name("e00003_s01") == (3, 1)
    assert layout.parse_record_name(".tmp-e00003_s01-1") is None
    with pytest.raises(ValueError):
        layout.record_name(-1, 0)


@settings(max_examples=40, deadline=None)
@given(
    ids1=st.lists(st.sampled_from("abcdefgh"), unique=True, max_size=8),
    ids2=st.lists(st.sampled_from("abcdefgh"), unique=True, max_size=8),
)
def test_ground_truth_pairs_match_object_ids(ids1, ids2):
    v1, v2 = _view(ids1, 1), _view(ids2, 2)
    gt = ground_truth_pairs(v1, v2)
    assert gt.shape == (len(set(ids1) & set(ids2)), 2) and gt.dtype == np.int64
    assert all(ids1[i] == ids2[j] for i, j in gt)
    assert list(gt[:, 0]) == sorted(gt[:, 0])
    cov = len(gt)
    assert is_acceptable_pair(v1, v2) == (cov >= 3 and len(ids1) > cov and len(ids2) > cov)
    arrays = v1.to_arrays("view1")
    assert ViewDetections.from_arrays(load_npz(npz_bytes(arrays), "x"), "view1", "x").equals(v1)


def test_view_detections_validate_shapes():
    with pytest.raises(ValueError, match="detections.boxes: 1 rows for 2 object ids"):
        ViewDetections(
            np.zeros((2, 3)), np.zeros((1, 4)), np.zeros((2, 4)), ["a", "b"], ["c"] * 2, [1, 2]
        )
    with pytest.raises(ValueError, match="detected twice"):
        ViewDetections(
            np.zeros((2, 3)), np.zeros((2, 4)), np.zeros((2, 4)), ["a", "a"], ["c"] * 2, [1, 2]
        )
    empty = ViewDetections(np.zeros((0, 3)), np.zeros((0, 4)), np.zeros((0, 0)), [], [], [])
    assert len(empty) == 0 and empty.positions.shape == (0, 3)


@pytest.fixture(scope="module")
def small_dataset(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("ds") / "fake"
    generate_dataset(FakeScenario(), out, pairs=3, workers=1, stages=FAKE_STAGES, progress=False)
    return out


def test_reader_exposes_records(small_dataset):
    ds = Dataset(small_dataset, verify=True)
    assert len(ds) == 3 and len(list(ds)) == 3
    manifest = json.loads((small_dataset / "manifest.json").read_text())
    assert (
        ds.checksum
        == manifest["checksum"]
        == dataset_checksum(r["checksum"] for r in manifest["records"])
    )
    pair = ds[-1]
    assert pair.index == 2 and (pair.episode, pair.slot) == (1, 0)
    record = json.loads((small_dataset / "pairs" / pair.name / "record.json").read_text())
    gt_ids = [g["object_id"] for g in record["ground_truth"]]
    assert [pair.view1.object_ids[i] for i, _ in pair.gt_pairs] == gt_ids
    assert [pair.view2.object_ids[j] for _, j in pair.gt_pairs] == gt_ids
    assert pair.sim_seed == simulation_seed(11, 1)
    assert pair.color1.shape == (120, 160, 3) and pair.depth2.dtype == np.float32
    # Instance images index the stored objects; the observer's own vehicle is not visible.
    seen = {pair.objects[i].id for i in np.unique(pair.instance1[pair.instance1 >= 0])}
    assert "obs1" not in seen and set(pair.view1.object_ids) <= seen
    problem = pair.problem()
    np.testing.assert_array_equal(problem.points1, pair.view1.positions)
    np.testing.assert_array_equal(problem.features2, pair.view2.features)
    assert pair.cameras[0].width == 160 and pair.observer_ids == ("obs1", "obs2")
    with pytest.raises(IndexError, match="pair 3 out of range"):
        ds[3]


def test_reader_errors_name_the_problem(small_dataset, tmp_path):
    with pytest.raises(DatasetError, match="no manifest"):
        Dataset(tmp_path)
    import shutil

    copy = tmp_path / "copy"
    shutil.copytree(small_dataset, copy)
    manifest = json.loads((copy / "manifest.json").read_text())
    (copy / "pairs" / manifest["records"][1]["name"] / "view2.png").write_bytes(b"tampered")
    Dataset(copy)  # opening does not hash
    with pytest.raises(DatasetError, match="e00000_s01: checksum mismatch"):
        Dataset(copy, verify=True)
    with pytest.raises(ValueError, match="view2.png: not a readable PNG"):
        _ = Dataset(copy)[1].color2
    manifest["complete"] = False
    (copy / "manifest.json").write_text(json.dumps(manifest))
    with pytest.raises(DatasetError, match="generation did not finish"):
        Dataset(copy)


def test_a_verified_dataset_is_not_read_again_by_the_next_process_unless_a_file_changed(
    small_dataset, tmp_path, monkeypatch
):
    """The verification stamp (cadsim.dataset.verified_stamps) stands in for a full verify in a
    later process only while every file is as it was; a rewritten record is checked again."""
    import shutil

    from cadsim.dataset import reader

    monkeypatch.setenv("CADSIM_CACHE_DIR", str(tmp_path / "cache"))
    copy = tmp_path / "copy"
    shutil.copytree(small_dataset, copy)
    calls = []
    real = reader.Dataset.verify
    monkeypatch.setattr(reader.Dataset, "verify", lambda self: calls.append(1) or real(self))
    Dataset(copy, verify=True)
    assert len(calls) == 1 and list((tmp_path / "cache" / "verified").glob("*.json"))
    reader._VERIFIED.clear()  # a new process: only the stamp remembers
    Dataset(copy, verify=True)
    assert len(calls) == 1
    manifest = json.loads((copy / "manifest.json").read_text())
    (copy / "pairs" / manifest["records"][2]["name"] / "view1.png").write_bytes(b"tampered")
    reader._VERIFIED.clear()
    with pytest.raises(DatasetError, match="checksum mismatch"):
        Dataset(copy, verify=True)
    assert len(calls) == 2


def test_a_fresh_generation_counts_as_verified(tmp_path, monkeypatch):
    from cadsim.dataset import reader

    monkeypatch.setenv("CADSIM_CACHE_DIR", str(tmp_path / "cache"))
    out = tmp_path / "fresh"
    generate_dataset(FakeScenario(), out, pairs=2, workers=1, stages=FAKE_STAGES, progress=False)
    monkeypatch.setattr(reader.Dataset, "verify", lambda self: pytest.fail("read again"))
    reader._VERIFIED.clear()
    Dataset(out, verify=True)  # the generator's stamp: its records were checksummed as written


_BLOCKER = """
import importlib.abc, sys
BLOCKED = {"libsumo", "traci", "sumolib", "sumo", "pyrender", "OpenGL"}
class Block(importlib.abc.MetaPathFinder):
    def find_spec(self, name, path=None, target=None):
        if name.split(".")[0] in BLOCKED:
            raise ImportError(f"blocked: {name}")
sys.meta_path.insert(0, Block())
for name in list(sys.modules):
    if name.split(".")[0] in BLOCKED:
        del sys.modules[name]
"""


def test_reader_needs_neither_sumo_nor_pyrender(small_dataset, tmp_path):
    script = _BLOCKER + textwrap.dedent(
        f"""
        try:
            import pyrender
        except ImportError:
            pass
        else:
            raise SystemExit("blocker failed")
        from cadsim.dataset import Dataset
        from cadsim.commands.info import summarise
        from cadsim.pair_drawing import draw_pair_from_record, save_figure
        ds = Dataset({str(small_dataset)!r}, verify=True)
        pair = ds[0]
        pair.problem(); pair.color1; pair.depth1; pair.instance2; pair.objects
        pair.redetect(0.05, seed=1)  # noise + detection modules: no SUMO/pyrender either
        assert summarise(ds)["n_pairs"] == 3
        save_figure(draw_pair_from_record(pair), {str(tmp_path / "p.png")!r})
        bad = [m for m in sys.modules if m.split(".")[0] in BLOCKED]
        assert not bad, bad
        print("ok")
        """
    )
    env = {**os.environ, "MPLBACKEND": "Agg"}
    out = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, cwd=REPO, env=env
    )
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "ok"
