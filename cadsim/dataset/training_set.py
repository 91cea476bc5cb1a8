"""Training examples for the learned matchers from frame-pair datasets: every record's matching
problem with its ground truth, and the record of what they are (dataset names, checksums and the
checksum of every record) that a model file keeps, so that an evaluation can refuse a model
trained on the data it is asked to score (:func:`overlapping_records`)."""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from pathlib import Path

import numpy as np

from cadsim.dataset.reader import Dataset


def training_examples(
    dirs: Sequence[str | Path], progress: bool = False
) -> tuple[list[tuple[object, np.ndarray]], dict]:
    """([(matchers.Problem, (g, 2) ground-truth pairs)] of every record of every dataset in
    ``dirs``, {"datasets": [{name, checksum, pairs, records}]}): the records' own detections and
    localisation prior. Two datasets with a record in common are refused (ValueError)."""
    from tqdm import tqdm

    examples, datasets, seen = [], [], {}
    for folder in dirs:
        ds = Dataset(folder, verify=True)
        records = []
        pairs = tqdm(ds, desc=f"features of {Path(folder).name}", disable=not progress, leave=False)
        for pair in pairs:
            if pair.checksum in seen:
                raise ValueError(
                    f"{folder}: record {pair.name} is also in {seen[pair.checksum]}; "
                    "give each training record once"
                )
            seen[pair.checksum] = str(folder)
            records.append(pair.checksum)
            examples.append((pair.problem(), pair.gt_pairs))
        datasets.append(
            {
                "name": Path(folder).resolve().name,
                "checksum": ds.checksum,
                "pairs": len(records),
                "records": records,
            }
        )
    return examples, {"datasets": datasets}


def dataset_records(folder: str | Path) -> set[str]:
    """Checksums of every record of the dataset at ``folder`` (verified first)."""
    return {pair.checksum for pair in Dataset(folder, verify=True)}


def overlapping_records(trained_on: set[str], dirs: Iterable[str | Path]) -> dict[str, int]:
    """{dataset folder: how many of its records are among ``trained_on``} for the folders that
    share at least one record with a model's training data."""
    shared = {}
    for folder in dirs:
        common = len(dataset_records(folder) & trained_on)
        if common:
            shared[str(folder)] = common
    return shared
