"""The box-only V2X table (``results/table_v2x_boxes.{md,csv}``): what a method that sees only
3-D boxes (a LiDAR-box pipeline) gets on ``cad-v2x``, beside the full table.

Data. The cad-v2x test and validation splits are exported in the OPV2V layout (``cadsim export
opv2v``) and imported back as box-only records (``cadsim import opv2v --no-prior``) into
``DATA/cad-v2x-boxes`` and ``DATA/cad-v2x-boxes-val``: the same detections (each view's noisy
positions, reported classes, ground truth), the sizes each view's detector reported (with its
size noise; never the objects' true sizes, which would name the pair: docs/dataset.md, "Sizes in
exported boxes") and headings instead of image appearance, no pixels. The record identity and the observers' bodies
survive the round trip, so every localisation preset draws the same prior as for the full
table. A folder is rebuilt when its source split or the export/import code (the result cache's
code version) has changed since it was built, or its manifest is not the one built (a stamp of
kind ``boxes``, :mod:`eval.core.folder_stamps`); otherwise it is reused as it is (its records'
bytes, hence the result cache's keys, would not change).

Protocol. Exactly the full table's (:func:`eval.studies.v2x.table.evaluate_v2x`): every matcher
that runs without pixels (:func:`box_matchers`) under every preset with the same tuning budget,
τ and parameters chosen on the validation split, the oracle and prior rows. ``appearance``-based
matchers compare box sizes here. Files: ``table_v2x_boxes.{md,csv}``,
``table_v2x_boxes_intervals.csv``, ``v2x_boxes/<preset>/``.
"""

from __future__ import annotations

import json
import logging
import shutil
import tempfile
from collections.abc import Sequence
from pathlib import Path

import pandas as pd

from eval.core.folder_stamps import read_stamp, write_stamp
from eval.core.tasks import MatcherSpec
from eval.protocol.claims import Claim, measurement_claim

log = logging.getLogger(__name__)

NAME = "v2x_boxes"
LABEL = "CAD-V2X boxes"
PIXEL_FIELDS = frozenset({"pixels1", "pixels2"})
_SCENARIO = "opv2v"


def box_matchers(specs: Sequence[MatcherSpec]) -> list[MatcherSpec]:
    """The matchers of ``specs`` that can run on box-only data: none that needs pixels or
    image options (``pairwise="image"``)."""
    from matchers.core.registry import requires

    kept = []
    for spec in specs:
        options = dict(getattr(spec, "options", {}) or {})
        if requires(spec.name) & PIXEL_FIELDS or options.get("pairwise") == "image":
            continue
        kept.append(spec)
    return kept


def _ours(folder: Path) -> bool:
    """Whether ``folder`` is a box dataset this stage wrote (safe to replace)."""
    manifest = folder / "manifest.json"
    if not manifest.is_file():
        return not folder.exists() or not any(folder.iterdir())
    try:
        data = json.loads(manifest.read_text())
    except (OSError, ValueError):
        return False
    return data.get("scenario", {}).get("name") == _SCENARIO and (
        data.get("generation", {}).get("cues") == "boxes"
    )


def as_boxes(camera_dir: str | Path, box_dir: str | Path) -> Path:
    """``camera_dir`` exported (OPV2V layout, a temporary folder) and imported as box-only
    records at ``box_dir`` (replaced if this stage wrote it; refused otherwise)."""
    from cadsim.dataset import Dataset
    from cadsim.exporters.opv2v import export_opv2v
    from cadsim.importers.opv2v import import_opv2v
    from eval.core.cache import code_version

    box_dir = Path(box_dir)
    if not _ours(box_dir):
        raise ValueError(f"{box_dir}: exists and is not a box dataset this stage wrote")
    source = {"split": Dataset(camera_dir).checksum, "code": code_version()}
    if _built_from(box_dir) == source:
        return box_dir
    if box_dir.exists():
        shutil.rmtree(box_dir)
    with tempfile.TemporaryDirectory(prefix="cadsim-opv2v-") as tmp:
        exported = Path(tmp) / "opv2v"
        export_opv2v(camera_dir, exported)
        import_opv2v(exported, box_dir, prior=False)
    _remember(box_dir, source)
    return box_dir


def _built_from(box_dir: Path) -> dict | None:
    """The source {split checksum, code version} ``box_dir`` was built from, if it still holds
    the manifest it was built with; None otherwise (rebuild it)."""
    from cadsim.dataset import Dataset

    stamp = read_stamp("boxes", box_dir)
    try:
        built = Dataset(box_dir).checksum
    except (OSError, ValueError):
        return None
    return stamp.get("source") if stamp and stamp.get("checksum") == built else None


def _remember(box_dir: Path, source: dict) -> None:
    """Stamp ``box_dir`` as built from ``source`` (:mod:`eval.core.folder_stamps`)."""
    from cadsim.dataset import Dataset

    write_stamp("boxes", box_dir, {"source": source, "checksum": Dataset(box_dir).checksum})


def evaluate_boxes(
    test_dir: str | Path,
    val_dir: str | Path,
    data: str | Path,
    matchers: Sequence[MatcherSpec],
    seeds: Sequence[int],
    runner,
    out_dir: str | Path,
    tune: bool = True,
) -> tuple[pd.DataFrame, dict]:
    """Build the box splits from cad-v2x's ``test_dir`` / ``val_dir`` under ``data`` and run
    the full table's protocol on them (module docstring); (table, what the run record keeps)."""
    from eval.studies.v2x.table import evaluate_v2x

    data = Path(data)
    test = as_boxes(test_dir, data / f"{Path(test_dir).name}-boxes")
    val = as_boxes(val_dir, data / f"{Path(test_dir).name}-boxes-val")
    chosen = box_matchers(matchers)
    log.info("[v2x boxes] %s: %d matchers, box-only splits %s, %s", LABEL, len(chosen), test, val)
    table = evaluate_v2x(test, val, LABEL, chosen, seeds, runner, out_dir, tune=tune, name=NAME)
    record = {"test_dir": str(test), "val_dir": str(val), "matchers": [m.name for m in chosen]}
    return table, record


def _delta_line(results: Path) -> list[str]:
    """Per preset: the validation-chosen matcher's test F1 with boxes against with cameras."""
    from eval.engine.cells import ranged
    from eval.engine.result_table import read_result
    from eval.engine.validation_choice import recorded_validation
    from eval.studies.v2x.report import chosen_by_preset, chosen_row

    out = []
    boxes = pd.read_csv(results / f"table_{NAME}.csv", keep_default_na=False, na_values=[""])
    full = read_result(results, "table_v2x.csv", allow_empty=True)
    val_boxes, val_full = recorded_validation(results, NAME), recorded_validation(results, "v2x")
    presets = dict.fromkeys(boxes["preset"])
    for preset, (name, row) in chosen_by_preset(boxes, presets, val_boxes).items():
        text = (
            f"`{preset}`: with boxes only, `{name}` (chosen on validation) "
            f"{ranged(row.f1_mean, row.f1_low, row.f1_high)} F1, success@(1 m, 2°) "
            f"{ranged(row.success_1m_2deg, row.success_low, row.success_high)}"
        )
        other = chosen_row(full, preset, val_full) if full is not None else None
        if other is not None:
            text += f"; with cameras `{other[0]}` {ranged(other[1].f1_mean, other[1].f1_low, other[1].f1_high)} F1"
        out.append(text)
    return out


def timing_claims(seconds: float | None) -> list[Claim]:
    """The stage's time in the last cold run against its 120 s goal (a point measurement;
    none without a cold run)."""
    if seconds is None:
        return []
    return [
        measurement_claim(
            NAME, "stage time (export, import, evaluation)", seconds, 120.0, "last cold run"
        )
    ]


def readme_part(results: Path, rel: str, seconds: float | None = None) -> list[str]:
    """Report lines for the box-only table (none without ``table_v2x_boxes.md``); ``seconds``:
    the stage's time in the last cold run (export, import and evaluation)."""
    from eval.engine.power import power_line
    from eval.engine.result_table import bullets
    from eval.studies.v2x.report import compact_markdown

    results = Path(results)
    markdown = compact_markdown(results, NAME, LABEL)
    power = [line for line in (power_line(results, NAME),) if line]
    return (
        []
        if markdown is None
        else [
            "### The V2X task with boxes only",
            "",
            "`cad-v2x` exported in the OPV2V layout and imported back as 3-D boxes — what a "
            "LiDAR-box method sees: the same detections (positions as the cameras measured them), "
            "ground truth and priors, each view's reported size (the detector's noisy estimate) "
            "and heading instead of image appearance, no pixels (docs/external-data.md). "
            "Every matcher that runs without pixels, under the full table's protocol (equal tuning "
            "budget, τ and parameters on validation, oracle and prior rows). Per preset the best "
            f"by validation F1, the best without a prior and the reference rows; every matcher: "
            f"[{rel}/table_{NAME}.md]({rel}/table_{NAME}.md).",
            "",
            markdown,
            "",
            *bullets(_delta_line(results) + power),
            *(f"- {c.statement}." for c in timing_claims(seconds)),
            "",
            f"(`{rel}/table_{NAME}.csv`, `{rel}/table_{NAME}_intervals.csv`, `{rel}/{NAME}/`.)",
            "",
        ]
    )


__all__ = [
    "LABEL",
    "NAME",
    "as_boxes",
    "box_matchers",
    "evaluate_boxes",
    "readme_part",
    "timing_claims",
]
