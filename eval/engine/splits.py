"""Loading a study's splits: a test dataset paired with its validation dataset (and the prior
preset and sensor it is read under), with the table's name for it. Imports ``eval/core/``."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from eval.core import tasks
from eval.core.tasks import MatcherSpec

# Scenario name -> table name where the first-word rule (below) does not give the right one.
DATASET_LABELS = {"cad-dense": "CAD-dense", "dmgm-cad": "DMGM"}

# A table row (the requested matcher's label) -> the spec that runs for it on one dataset (tuned
# parameters and protocol options make the two differ).
Named = dict[str, MatcherSpec]


@dataclass(frozen=True)
class DatasetEntry:
    """A test dataset and its validation dataset. label: the table's dataset name (``CAD``);
    localisation: the name of a GNSS-like preset (:mod:`cadsim.sensing.gnss_error`) that
    re-draws every record's localisation prior in every run (None: the records' own); sensor:
    the sensor a two-sensor dataset is read as ("camera", "lidar"; None: as stored,
    :mod:`cadsim.dataset.sensor_view`)."""

    label: str
    scenario: str
    test_dir: str
    test_checksum: str
    test_pairs: int
    val_dir: str | None = None
    val_checksum: str | None = None
    val_pairs: int = 0
    localisation: str | None = None  # a GNSS-like preset re-drawing every record's prior
    sensor: str | None = None


PAPER_FAMILIES = ("cad", "mrc")  # scenario-name prefixes titled like the paper's datasets


def dataset_label(scenario_name: str) -> str:
    """Table name of a scenario: :data:`DATASET_LABELS`; a scenario of the paper's families by
    its family in upper case (cad-intersection -> CAD, mrc-arena -> MRC, cad-dense ->
    CAD-dense); any other by its own name (my-busy-3lane stays my-busy-3lane)."""
    if scenario_name in DATASET_LABELS:
        return DATASET_LABELS[scenario_name]
    family = scenario_name.split("-", 1)[0]
    return family.upper() if family.lower() in PAPER_FAMILIES else scenario_name


def open_entry(
    test_dir: str | Path,
    val_dir: str | Path | None,
    label: str | None = None,
    localisation: str | None = None,
    sensor: str | None = None,
) -> DatasetEntry:
    """Open the test (and validation) dataset and describe them, titled `label` (default:
    :func:`dataset_label` of its scenario), read as ``sensor`` (a two-sensor dataset's
    "camera" or "lidar"; None: as stored). Each is verified against its
    manifest's checksums (once per process for unchanged files): the result cache is keyed by
    the manifest's checksum, so a record modified after generation would otherwise go unseen."""
    read = (lambda d: tasks.open_dataset(d)) if sensor is None else (lambda d: tasks.open_dataset(d, sensor))  # fmt: skip
    test = read(str(test_dir))
    val = read(str(val_dir)) if val_dir is not None else None
    for dataset in (test, val):
        if dataset is not None:
            dataset.verify_once()
    if val is not None and val.scenario_name != test.scenario_name:
        raise ValueError(
            f"{val_dir}: validation scenario {val.scenario_name!r} differs from "
            f"{test_dir}'s {test.scenario_name!r}"
        )
    if localisation is not None:
        from cadsim.sensing.gnss_error import model_of
        from cadsim.sensing.latency import MIN_VELOCITY_FORMAT

        latency = model_of(localisation).latency_ms  # ValueError naming the presets
        for dataset, where in ((test, test_dir), (val, val_dir)):
            version = None if dataset is None else dataset.manifest["format_version"]
            if latency and version is not None and version < MIN_VELOCITY_FORMAT:
                raise ValueError(
                    f"{where}: localisation {localisation!r} has a message latency of "
                    f"{latency:g} ms, which needs object velocities (dataset format version "
                    f"{MIN_VELOCITY_FORMAT}); this dataset is version {version} — regenerate it"
                )
    return DatasetEntry(
        label=label or dataset_label(test.scenario_name),
        scenario=test.scenario_name,
        test_dir=str(test_dir),
        test_checksum=test.checksum,
        test_pairs=len(test),
        val_dir=None if val is None else str(val_dir),
        val_checksum=None if val is None else val.checksum,
        val_pairs=0 if val is None else len(val),
        localisation=localisation,
        sensor=getattr(test, "sensor", None),
    )


def val_dirs(datasets: Sequence[str], given: Sequence[str] | None) -> list[str | None]:
    """Validation dataset per test dataset: `given` in order, else ``DIR-val`` if it exists."""
    if given:
        if len(given) != len(datasets):
            raise ValueError(f"--val: {len(given)} directories for {len(datasets)} datasets")
        return list(given)
    candidates = [str(Path(d).with_name(Path(d).name + "-val")) for d in datasets]
    return [c if (Path(c) / "manifest.json").is_file() else None for c in candidates]
