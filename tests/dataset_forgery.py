"""Helpers for tests that forge a dataset (no tests here): edit a record's files, then reseal the
manifest's checksums so that only the checks of a record's contents can refuse it."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from cadsim.dataset import layout
from cadsim.dataset.checksum import dataset_checksum, record_dir_checksum
from cadsim.dataset.encoding import json_bytes, load_npz, npz_bytes


def manifest_of(dataset: Path) -> dict:
    return json.loads((Path(dataset) / layout.MANIFEST).read_text())


def write_manifest(dataset: Path, manifest: dict) -> None:
    (Path(dataset) / layout.MANIFEST).write_bytes(json_bytes(manifest))


def record_dirs(dataset: Path) -> list[Path]:
    """The records' folders in dataset order."""
    pairs = Path(dataset) / layout.PAIRS_DIR
    return [pairs / entry["name"] for entry in manifest_of(dataset)["records"]]


def edit_json(record_dir: Path, edit) -> None:
    """``edit(record)`` on the parsed ``record.json``, written back canonically."""
    path = Path(record_dir) / layout.RECORD_JSON
    record = json.loads(path.read_text())
    edit(record)
    path.write_bytes(json_bytes(record))


def edit_npz(path: Path, edit) -> None:
    """``edit(arrays)`` on an ``.npz``'s arrays (a dict to change in place), written back."""
    arrays = load_npz(str(path), str(path))
    edit(arrays)
    Path(path).write_bytes(npz_bytes({k: np.asarray(v) for k, v in arrays.items()}))


def reseal(dataset: Path) -> None:
    """Recompute every record's checksum and the dataset's in the manifest: the records' files
    as they are now pass the checksum check."""
    manifest = manifest_of(dataset)
    files = manifest.get("record_files") or layout.RECORD_FILES
    for entry in manifest["records"]:
        entry["checksum"] = record_dir_checksum(
            Path(dataset) / layout.PAIRS_DIR / entry["name"], files
        )
    manifest["checksum"] = dataset_checksum(e["checksum"] for e in manifest["records"])
    write_manifest(dataset, manifest)


def as_older_version(dataset: Path, version: int) -> None:
    """Rewrite a format-5 (frame pairs) dataset as the older ``version`` (2-4) would have stored
    it: the format number in the manifest and every record, ``view{k}_classes`` (the true class)
    instead of true and reported classes, and before 3 no object velocities; resealed."""
    assert version in (2, 3, 4)
    manifest = manifest_of(dataset)
    manifest["format_version"] = manifest["generation"]["format_version"] = version
    write_manifest(dataset, manifest)

    def older(record: dict) -> None:
        record["format_version"] = version
        for obj in record["objects"] if version < 3 else ():
            obj.pop("velocity", None)

    def classes(arrays: dict) -> None:
        for key in [k for k in arrays if k.endswith(("_true_classes", "_reported_classes"))]:
            value = arrays.pop(key)
            if key.endswith("_true_classes"):
                arrays[key.replace("_true_classes", "_classes")] = value

    for record_dir in record_dirs(dataset):
        edit_json(record_dir, older)
        edit_npz(record_dir / layout.DETECTIONS_NPZ, classes)
    reseal(dataset)
