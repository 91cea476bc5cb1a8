"""``cadsim import dmgm``: a hand-made ``.pt`` folder converted into our format (what every field
becomes), the shipped subset against its source, image-less records through info/show/problem,
and one-line CLI errors."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from test_import_dmgm_reader import SHARED, view_archive, view_arrays, write

from cadsim.cli import main as cli_main
from cadsim.commands.info import summarise
from cadsim.dataset import Dataset
from cadsim.importers import ImportFormatError
from cadsim.importers.dmgm_dataset import WORLD_SIGMA_M, import_dmgm
from cadsim.importers.dmgm_pt import iter_pairs
from cadsim.pair_drawing import draw_pair_from_record

REPO = Path(__file__).resolve().parents[1]
SHIPPED = REPO / "eval" / "data" / "dmgm-cad"


def _source(tmp_path: Path) -> tuple[Path, dict]:
    """Three pairs: ids 100, 101 (sequence 069) and 200 (sequence 071); two objects shared per
    pair. Returns the folder and {(pair id, side): arrays}."""
    src = tmp_path / "src"
    arrays = {}
    for pair_id, seq, frame in (("100", "069", "0001"), ("101", "069", "0002"), ("200", "071", "0007")):  # fmt: skip
        a = view_arrays(5, seed=int(pair_id))
        b = view_arrays(4, seed=int(pair_id) + 1)
        b["y"][:2] = a["y"][[3, 0]]  # b[0] is a[3], b[1] is a[0]
        for side, arr in (("proc_s", a), ("proc_t", b)):
            name = f"data/{side}/{pair_id}/{seq}_{frame}"
            write(src / side / pair_id / "data.pt", view_archive(arr, name))
            arrays[(pair_id, side)] = arr
    return src, arrays


def test_hand_made_folder_imports_field_by_field(tmp_path):
    src, arrays = _source(tmp_path)
    result = import_dmgm(src, tmp_path / "out", progress=False)
    assert result.sequences == {"069": 2, "071": 1} and result.pairs == 3
    ds = Dataset(tmp_path / "out", verify=True)
    assert ds.scenario_name == "dmgm-cad" and ds.record_files == ("detections.npz", "record.json")
    assert sorted(p.name for p in (tmp_path / "out" / "pairs" / "e00069_s00").iterdir()) == [
        "detections.npz",
        "record.json",
    ]
    assert [(p.episode, p.slot, p.sim_seed) for p in ds] == [(69, 0, 69), (69, 1, 69), (71, 0, 71)]
    pair = ds[2]
    a, b = arrays[("200", "proc_s")], arrays[("200", "proc_t")]
    np.testing.assert_array_equal(pair.view1.positions, a["pos"].astype(float))
    np.testing.assert_array_equal(pair.view2.features, b["x"])
    assert pair.view1.object_ids == [str(int(v)) for v in a["y"]]
    assert pair.view1.true_classes == [f"label{k}" for k in a["label"]]
    np.testing.assert_array_equal(pair.gt_pairs, [[0, 1], [3, 0]])
    # The prior: DMGM's left-handed world made right-handed by negating y; its stated sigma.
    world1, world2, sigma = pair.prior()
    np.testing.assert_array_equal(world1, a["pos_world"].astype(float) * [1, -1, 1])
    np.testing.assert_array_equal(world2[:, 1], -b["pos_world"][:, 1].astype(float))
    assert sigma == WORLD_SIGMA_M
    # `norm` is the box centre the matchers get; no images, no cameras, no re-detection.
    problem = pair.problem()
    np.testing.assert_array_equal(problem.pixels1, a["norm"].astype(float))
    np.testing.assert_array_equal(problem.world2, world2)
    assert problem.world_sigma == WORLD_SIGMA_M
    assert not pair.has_images and pair.cameras is None and np.isnan(pair.time)
    with pytest.raises(ValueError, match="no depth images"):
        pair.redetect(0.01, seed=0)
    with pytest.raises(ValueError, match="stored with this"):
        pair.localise(1.0, 0.1, seed=0)
    manifest = ds.manifest
    assert manifest["source"]["commit"] == "5729d0e9" and manifest["source"]["licence"] == "MIT"
    assert manifest["source"]["sequences"] == {"069": 2, "071": 1}
    record = json.loads((pair.path / "record.json").read_text())
    assert record["meta"]["pair_id"] == "200" and record["meta"]["frame"] == "0007"


def test_import_is_deterministic_and_compact_features_stay_close(tmp_path):
    src, arrays = _source(tmp_path)
    first = import_dmgm(src, tmp_path / "a", progress=False)
    again = import_dmgm(src, tmp_path / "b", progress=False)
    assert first.checksum == again.checksum  # same input, same records
    compact = import_dmgm(src, tmp_path / "c", ["071"], compact=True, progress=False)
    assert compact.sequences == {"071": 1}
    pair = Dataset(tmp_path / "c")[0]
    x = arrays[("200", "proc_s")]["x"]
    scale = x.max() / 255
    assert pair.view1.features.dtype == np.float32
    assert np.abs(pair.view1.features - x).max() <= scale / 2 + 1e-6


def test_image_less_records_work_with_info_and_show(tmp_path):
    src, _ = _source(tmp_path)
    import_dmgm(src, tmp_path / "out", progress=False)
    ds = Dataset(tmp_path / "out")
    summary = summarise(ds)
    assert summary["n_pairs"] == 3 and summary["covisible"]["mean"] == 2
    assert summary["source"]["repository"].endswith("gaopeng5/DMGM")
    fig = draw_pair_from_record(ds[0])
    assert len(fig.axes) == 3  # view 1, view 2 from above, and the prior in the world frame
    png = tmp_path / "show.png"
    assert cli_main(["show", str(tmp_path / "out"), "--pair", "1", "--out", str(png)]) == 0
    assert png.stat().st_size > 0


def _cli(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "cadsim", *args], capture_output=True, text=True, cwd=REPO
    )


def test_import_cli_errors_are_one_line(tmp_path):
    src, _ = _source(tmp_path)
    bad = tmp_path / "bad"
    for side in ("proc_s", "proc_t"):
        write(bad / side / "7" / "data.pt", b"PK\x03\x04 not really a zip")
    cases = {
        "corrupt": (["import", "dmgm", str(bad), "--out", str(tmp_path / "o1")], "bad/proc_s/7"),
        "missing": (["import", "dmgm", str(tmp_path / "nope"), "--out", str(tmp_path / "o2")],
                    "missing folder"),
        "sequence": (["import", "dmgm", str(src), "--out", str(tmp_path / "o3"),
                      "--sequences", "070"], "no pairs of sequences"),
        "not empty": (["import", "dmgm", str(src), "--out", str(src)], "not an empty folder"),
    }  # fmt: skip
    for name, (args, expected) in cases.items():
        done = _cli(*args)
        assert done.returncode == 2, name
        lines = done.stderr.strip().splitlines()
        assert len(lines) == 1 and lines[0].startswith("cadsim import: error:"), (name, lines)
        assert expected in lines[0], (name, lines)
    assert not (tmp_path / "o1" / "manifest.json").exists()  # nothing half-written is a dataset
    done = _cli("import", "dmgm", str(src), "--out", str(tmp_path / "ok"), "--no-progress")
    assert done.returncode == 0 and "3 pairs (069: 2, 071: 1)" in done.stdout


def test_import_refuses_a_folder_without_pairs(tmp_path):
    (tmp_path / "src" / "proc_s").mkdir(parents=True)
    (tmp_path / "src" / "proc_t").mkdir()
    with pytest.raises(ImportFormatError, match="no pairs to import"):
        import_dmgm(tmp_path / "src", tmp_path / "out", progress=False)


def test_shipped_subset_splits_and_checksums():
    val = Dataset(SHIPPED / "val-070", verify=True)
    test = Dataset(SHIPPED / "test-069-071", verify=True)
    assert len(val) == 201 and len(test) == 109
    assert {p.episode for p in val} == {70} and {p.episode for p in test} == {69, 71}
    for ds in (val, test):
        assert ds.manifest["source"]["commit"] == "5729d0e9"
        assert ds.manifest["generation"]["compact_features"] is True
    assert (SHIPPED / "LICENSE").read_text().startswith("MIT License")


@pytest.mark.skipif(not SHARED.is_dir(), reason=f"{SHARED} not present")
def test_one_shipped_pair_equals_its_source():
    test = Dataset(SHIPPED / "test-069-071")
    pair = test[60]  # the last pair of sequence 069
    source = next(p for p in iter_pairs(SHARED) if p.pair_id == pair.record["meta"]["pair_id"])
    assert source.sequence == "069" and pair.episode == 69 and pair.slot == 60
    s, t = source.view_s, source.view_t
    np.testing.assert_array_equal(pair.view1.positions, s.pos.astype(float))
    np.testing.assert_array_equal(pair.view2.world, t.pos_world.astype(float) * [1, -1, 1])
    assert pair.view2.object_ids == [str(v) for v in t.y]
    # uint8 features: each value within half a quantisation step of the source's float32.
    step = s.x.max() / 255
    assert np.abs(pair.view1.features - s.x).max() <= step / 2 + 1e-6
    shared = {str(v) for v in s.y} & {str(v) for v in t.y}
    assert len(pair.gt_pairs) == len(shared)
