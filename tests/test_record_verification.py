"""Issue 40: one verification of records, covering every view, shared by every command.

A small fake N-view dataset (4 views: two vehicles, two roadside units; no SUMO, no OpenGL) is
forged view by view — its checksums resealed, so that only the checks of a record's contents can
refuse it — and ``info``, ``evaluate``, ``train`` and ``show`` must each refuse it with exit
status 2 and the same one line naming the file and the key; the good dataset passes them all.
"""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest
from dataset_forgery import edit_json, edit_npz, manifest_of, record_dirs, reseal, write_manifest
from test_generate_fakes import FAKE_STAGES, FakeScenario

from cadsim.cli import main
from cadsim.dataset import Dataset, DatasetError

VIEWS = 4
OBSERVERS = {"count": 2, "roadside_units": 2}


@pytest.fixture(scope="module")
def pristine(tmp_path_factory) -> Path:
    from cadsim.generation.pipeline import generate_dataset

    out = tmp_path_factory.mktemp("nview") / "ds"
    generate_dataset(
        FakeScenario(observers=OBSERVERS), out, pairs=3, workers=1, stages=FAKE_STAGES,
        progress=False,
    )  # fmt: skip
    return out


@pytest.fixture
def dataset(pristine, tmp_path) -> Path:
    copy = tmp_path / "ds"
    shutil.copytree(pristine, copy)
    return copy


def _argv(command: str, dataset: Path, tmp: Path, pair: int = 0) -> list[str]:
    return {
        "info": ["info", str(dataset)],
        "evaluate": [
            "evaluate", str(dataset), "--no-calibration", "--matchers", "sm", "--runs", "1",
            "--workers", "1", "--no-progress", "--out", str(tmp / "res"),
            "--cache", str(tmp / "cache"),
        ],
        "train": ["train", str(dataset), "--out", str(tmp / "model.json"), "--rounds", "2",
                  "--no-progress"],
        "show": ["show", str(dataset), "--pair", str(pair), "--out", str(tmp / "show.png")],
    }[command]  # fmt: skip


def _refusal(capsys, command: str) -> str:
    """The one line a refused command printed, without its ``cadsim CMD: error:`` prefix."""
    lines = capsys.readouterr().err.strip().splitlines()
    prefix = f"cadsim {command}: error: "
    assert len(lines) == 1 and lines[0].startswith(prefix), lines
    return lines[0][len(prefix) :]


def test_a_good_n_view_dataset_passes_every_command(dataset, tmp_path, capsys):
    ds = Dataset(dataset, verify=True)
    assert ds.n_views == VIEWS and ds.manifest["format_version"] == 6 and len(ds) == 3
    for k in range(len(ds)):
        snap = ds.snapshot(k)
        assert snap.kinds == ["vehicle", "vehicle", "roadside", "roadside"]
        assert all(len(snap.view(v)) >= 3 for v in range(1, VIEWS + 1))
    for command in ("info", "evaluate", "train", "show"):
        assert main(_argv(command, dataset, tmp_path)) == 0, capsys.readouterr().err
    capsys.readouterr()


# Each case: (edit(dataset) -> the index of the first record it breaks, words of the refusal,
# whether SnapshotViews, reading the record unverified, refuses it too with the same line).
def _last(dataset: Path) -> Path:
    return record_dirs(dataset)[-1]


def _in_npz(name: str, edit):
    def apply(dataset: Path) -> int:
        edit_npz(_last(dataset) / name, edit)
        return 2

    return apply


def _in_json(edit):
    def apply(dataset: Path) -> int:
        edit_json(_last(dataset), edit)
        return 2

    return apply


def _nan(arrays):
    arrays["view3_positions"] = arrays["view3_positions"].copy()
    arrays["view3_positions"][0, 0] = np.nan


def _duplicate(arrays):
    ids = arrays["view4_object_ids"].copy()
    ids[1] = ids[0]
    arrays["view4_object_ids"] = ids


def _stray_arrays(arrays):
    for key in [k for k in arrays if k.startswith("view4_")]:
        arrays[key.replace("view4_", "view5_")] = arrays[key]


def _stray_file(dataset: Path) -> int:
    shutil.copy(_last(dataset) / "view4.png", _last(dataset) / "view5.png")
    return 2


def _manifest_format(dataset: Path) -> int:
    manifest = manifest_of(dataset)
    manifest["format_version"] = 5
    write_manifest(dataset, manifest)
    return 0


def _forged_as_format_4(dataset: Path) -> int:
    """Manifest and every record claim format 4: the arrays are still format 6's."""
    manifest = manifest_of(dataset)
    manifest["format_version"] = manifest["generation"]["format_version"] = 4
    write_manifest(dataset, manifest)
    for record_dir in record_dirs(dataset):
        edit_json(record_dir, lambda r: r.update(format_version=4))
    return 0


def _pop(key):
    return lambda arrays: arrays.pop(key)


CASES = {
    "nan-positions": (_in_npz("detections.npz", _nan), "view3_positions: non-finite", True),
    "missing-array": (
        _in_npz("detections.npz", _pop("view4_boxes")), "missing arrays ['view4_boxes']", True
    ),
    "flat-positions": (
        _in_npz("detections.npz", lambda a: a.update(view3_positions=a["view3_positions"].ravel())),
        "view3_positions: expected (", True,
    ),
    "feature-width": (
        _in_npz("detections.npz", lambda a: a.update(view4_features=a["view4_features"][:, :-1])),
        "view4_features: ", True,
    ),
    "duplicate-ids": (_in_npz("detections.npz", _duplicate), "detected twice in one view", True),
    "stray-view-arrays": (
        _in_npz("detections.npz", _stray_arrays), "view5_boxes: not an array of this record", True
    ),
    "depth-shape": (
        _in_npz("depth.npz", lambda a: a.update(depth3=a["depth3"].T.copy())),
        "depth.npz: depth3: expected shape (120, 160)", False,
    ),
    "missing-instance": (
        _in_npz("instance.npz", _pop("instance4")), "instance.npz: instance4: missing", False
    ),
    "views-count": (_in_json(lambda r: r.update(views=3)), "views: expected 4", True),
    "observers-count": (
        _in_json(lambda r: r["observers"].pop()), "observers: expected a list of 4 entries", True
    ),
    "observer-kind": (
        _in_json(lambda r: r["observers"][3].update(kind="drone")), "observers[3].kind", True
    ),
    "observer-seed": (
        _in_json(lambda r: r["observers"][2].update(noise_seed="7")),
        "observers[2].noise_seed", True,
    ),
    "record-format": (
        _in_json(lambda r: r.update(format_version=5)),
        "format_version: expected 6 (the manifest's)", True,
    ),
    "manifest-format": (_manifest_format, "format_version: 5 is a frame-pair format", False),
    "forged-format-4": (
        _forged_as_format_4, "view1_reported_classes: not an array of this record", True
    ),
    "stray-view-file": (_stray_file, "view5.png: stray file in the record", False),
}  # fmt: skip


@pytest.mark.parametrize("case", sorted(CASES))
def test_malformed_views_are_refused_alike_by_info_evaluate_train_and_show(
    dataset, tmp_path, capsys, case
):
    edit, words, read_too = CASES[case]
    index = edit(dataset)
    reseal(dataset)  # the checksums vouch for the forged files: only the contents can refuse
    lines = {}
    for command in ("info", "evaluate", "train", "show"):
        assert main(_argv(command, dataset, tmp_path, pair=index)) == 2, command
        lines[command] = _refusal(capsys, command)
    assert len(set(lines.values())) == 1, lines  # one verification: the same line everywhere
    line = lines["info"]
    assert words in line, line
    named = dataset / "manifest.json" if case == "manifest-format" else record_dirs(dataset)[index]
    assert str(named) in line, line
    if read_too:  # reading the snapshot unverified applies the same checks, the same line
        with pytest.raises(DatasetError) as info:
            Dataset(dataset).snapshot(index)
        assert str(info.value) == line


def test_a_file_added_to_a_verified_record_is_caught_in_the_same_process(dataset):
    Dataset(dataset, verify=True)
    Dataset(dataset, verify=True)  # unchanged: skipped
    _stray_file(dataset)
    with pytest.raises(DatasetError, match="view5.png: stray file"):
        Dataset(dataset, verify=True)


def test_an_older_format_stored_as_that_format_still_reads(tmp_path):
    """A frame-pair dataset rewritten as format 3 stored it (``view{k}_classes``) verifies; the
    same records with format 5's arrays under the number 3 do not."""
    from dataset_forgery import as_older_version

    from cadsim.generation.pipeline import generate_dataset

    out = tmp_path / "pairs"
    generate_dataset(FakeScenario(), out, pairs=2, workers=1, stages=FAKE_STAGES, progress=False)
    forged = tmp_path / "forged"
    shutil.copytree(out, forged)
    as_older_version(out, 3)
    ds = Dataset(out, verify=True)
    assert ds[0].view1.reported_classes is None and ds[0].problem().classes1 is None
    manifest = manifest_of(forged)
    manifest["format_version"] = manifest["generation"]["format_version"] = 3
    write_manifest(forged, manifest)
    for record_dir in record_dirs(forged):
        edit_json(record_dir, lambda r: r.update(format_version=3))
    reseal(forged)
    with pytest.raises(DatasetError, match="view1_reported_classes: not an array"):
        Dataset(forged, verify=True)
