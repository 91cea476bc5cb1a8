"""The transfer study's data: the training sets (never a test split), the test sets with the
split each one's τ comes from, and DMGM's sequence 070 split by frame order into a training part
and a τ part (:func:`split_external`). See :mod:`eval.studies.transfer.evaluation` for the protocol."""

from __future__ import annotations

import logging
import re
import shutil
from dataclasses import dataclass
from pathlib import Path

from eval.studies.external.agreement import EXTERNAL_BLOCK

log = logging.getLogger("eval.studies.transfer.evaluation")

SIM_ONLY = "cadsim CAD + CAD-V2X train"  # the "trained on cadsim only" model of the goals
# DMGM's sequence 070 split by frame order: the first EXTERNAL_TRAIN_PAIRS train the DMGM model
# (as many pairs as SIM_ONLY's two 50-pair splits), EXTERNAL_GAP are dropped, the rest are the
# τ split of the learned rows on DMGM (split_external).
EXTERNAL_TRAIN_PAIRS = 100
EXTERNAL_GAP = EXTERNAL_BLOCK
EXTERNAL_SPLIT = ("dmgm-070-train", "dmgm-070-calibration")  # folders under the data folder
CAD_TRAIN_DIR, V2X_TRAIN_DIR = "cad-train", "cad-v2x-train"  # the simulated training splits
EXTERNAL_TRAIN = "DMGM 070 (pairs 1–100)"
EXTERNAL_TEST = "DMGM 069 + 071"


@dataclass(frozen=True)
class TestSet:
    """A test split, the split the learned matchers' τ is calibrated on (``val_dir``), the prior
    preset it is scored under (None: the records' own), where the main tables evaluated the
    hand-crafted matchers on it, and the cluster of its intervals (``block`` None: the
    simulation episode; N: blocks of N consecutive pairs of one sequence)."""

    label: str
    test_dir: Path
    val_dir: Path
    localisation: str | None
    reference_dir: Path
    reference_label: str
    block: int | None = None

    @property
    def cluster_unit(self) -> str:
        return "episode" if self.block is None else f"block of {self.block} pairs"


def split_external(source: Path, data: Path) -> tuple[Path, Path]:
    """(training part, τ part) of the external calibration dataset at ``source``, written once
    into ``data/``:data:`EXTERNAL_SPLIT` (copies of its records, a manifest naming the source):
    the first :data:`EXTERNAL_TRAIN_PAIRS` records in dataset (frame) order, then — after
    :data:`EXTERNAL_GAP` dropped records — the rest. Disjoint by construction; rewritten only
    when missing or not what ``source`` gives now."""
    from cadsim.dataset.reader import Dataset

    source = Path(source)
    records = Dataset(source, verify=True).manifest["records"]
    start = EXTERNAL_TRAIN_PAIRS + EXTERNAL_GAP
    if len(records) <= start:
        raise ValueError(
            f"{source}: {len(records)} frame pairs; the transfer split needs more than {start} "
            f"({EXTERNAL_TRAIN_PAIRS} to train on, {EXTERNAL_GAP} dropped, the rest for τ)"
        )
    parts = (records[:EXTERNAL_TRAIN_PAIRS], records[start:])
    roles = ("training", "tau calibration")
    out = []
    for name, part, role in zip(EXTERNAL_SPLIT, parts, roles, strict=True):
        out.append(_write_subset(source, Path(data) / name, part, role))
    return out[0], out[1]


def _write_subset(source: Path, target: Path, records: list[dict], role: str) -> Path:
    """``target``: the dataset of ``records`` of ``source`` (unchanged when already so)."""
    from cadsim.dataset import layout
    from cadsim.dataset.checksum import dataset_checksum
    from cadsim.dataset.manifest import read_manifest, write_manifest
    from cadsim.dataset.reader import Dataset

    manifest = read_manifest(source)
    checksum = dataset_checksum(r["checksum"] for r in records)
    if (target / layout.MANIFEST).is_file():
        try:
            if Dataset(target, verify=True).checksum == checksum:
                return target
        except Exception as exc:  # a stale or broken copy: rewritten below
            log.info("[transfer] rewriting %s (%s)", target, exc)
    names = [r["name"] for r in records]
    manifest |= {
        "records": records,
        "pairs": len(records),
        "checksum": checksum,
        "subset": {
            "of": source.name,
            "of_checksum": manifest["checksum"],
            "role": role,
            "first": names[0],
            "last": names[-1],
            "rule": (
                f"frame order: the first {EXTERNAL_TRAIN_PAIRS} pairs train, {EXTERNAL_GAP} "
                "dropped, the rest calibrate τ (eval.studies.transfer.evaluation.split_external)"
            ),
        },
    }
    staging = target.with_name(target.name + ".tmp")
    shutil.rmtree(staging, ignore_errors=True)
    (staging / layout.PAIRS_DIR).mkdir(parents=True)
    for name in names:
        shutil.copytree(source / layout.PAIRS_DIR / name, staging / layout.PAIRS_DIR / name)
    write_manifest(staging, manifest)
    shutil.rmtree(target, ignore_errors=True)
    staging.rename(target)
    Dataset(target, verify=True)
    return target


def train_sets(data: Path, cad_train: Path, external_train: Path) -> dict[str, list[Path]]:
    """{training-set label: dataset folders}: labels start with ``cadsim`` (simulated) or
    ``DMGM`` (external); the DMGM model trains on the training part of ``external_train``
    (:func:`split_external`, written into ``data``)."""
    v2x_train = Path(data) / V2X_TRAIN_DIR
    external, _ = split_external(external_train, data)
    return {
        "cadsim CAD train": [cad_train],
        "cadsim CAD-V2X train": [v2x_train],
        SIM_ONLY: [cad_train, v2x_train],
        EXTERNAL_TRAIN: [external],
    }


def test_sets(data: Path, out: Path, external_test: Path, external_val: Path) -> list[TestSet]:
    """The three test sets, with the folders of the main tables' evaluations of them; on DMGM
    the learned matchers' τ comes from the τ part of ``external_val`` (:func:`split_external`),
    its intervals cluster blocks of :data:`EXTERNAL_BLOCK` consecutive pairs."""
    data, out = Path(data), Path(out)
    _, external_tau = split_external(external_val, data)
    return [
        TestSet("cadsim CAD test", data / "cad", data / "cad-val", None, out, "CAD"),
        TestSet(
            "cadsim CAD-V2X test",
            data / "cad-v2x",
            data / "cad-v2x-val",
            "gnss-urban",
            out / "v2x" / "gnss-urban",
            "CAD-V2X",
        ),
        TestSet(
            EXTERNAL_TEST,
            Path(external_test),
            external_tau,
            None,
            out / "external",
            "DMGM",
            EXTERNAL_BLOCK,
        ),
    ]


def slug(label: str) -> str:
    """A folder name for a label: ``cadsim CAD + CAD-V2X train`` -> ``cadsim-cad-cad-v2x-train``."""
    return re.sub(r"[^a-z0-9]+", "-", label.lower()).strip("-")


__all__ = [
    "EXTERNAL_TEST",
    "EXTERNAL_TRAIN",
    "EXTERNAL_TRAIN_PAIRS",
    "SIM_ONLY",
    "TestSet",
    "slug",
    "split_external",
    "test_sets",
    "train_sets",
]
