"""The LiDAR V2X table (``results/table_v2x_lidar.{md,csv}``): what the matchers get on boxes
that cadsim's own LiDAR detector found, beside the camera table and the label-quality box table.

Data. ``scenarios/cad-v2x-lidar.toml`` — cad-v2x's junction, traffic, observers, seeds and
localisation preset, each observer sensing with an HDL-64E on its roof instead of a camera — is
generated into ``DATA/cad-v2x-lidar`` (test, seed 11) and ``DATA/cad-v2x-lidar-val`` (validation,
seed 1011), as many pairs as the camera table's splits. Each view's detections are the LiDAR
box detector's (``cadsim.sensing.lidar.box_detector``): its misses, splits, merges, wall slivers
and centre bias (its regime card: ``cadsim info``), reported classes from box size, the box
feature vector of the *fitted* sizes, headings; no pixels.

Protocol. The camera table's (:func:`eval.studies.v2x_table.evaluate_v2x`): every matcher that
runs without pixels (:func:`eval.studies.v2x_boxes.box_matchers`), every preset, the same tuning
budget, τ and parameters on the validation split, oracle and prior rows. Files:
``table_v2x_lidar.{md,csv}``, ``table_v2x_lidar_intervals.csv``, ``v2x_lidar/<preset>/``.
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Sequence
from pathlib import Path

import pandas as pd

from eval.core.tasks import MatcherSpec

log = logging.getLogger(__name__)

NAME = "v2x_lidar"
LABEL = "CAD-V2X LiDAR"
SCENARIO = "scenarios/cad-v2x-lidar.toml"


def generate_lidar_splits(
    root: Path, data: Path, pairs: int, val_seed_offset: int, generate: Callable
) -> tuple[Path, Path, dict]:
    """The test and validation splits of :data:`SCENARIO` under ``data`` (``generate(path,
    folder, pairs, seed)`` makes or resumes one); (test dir, val dir, what the run record keeps)."""
    from cadsim.scenario import load_scenario

    path = root / SCENARIO
    seed = load_scenario(path).seed
    test, val = data / "cad-v2x-lidar", data / "cad-v2x-lidar-val"
    record = {}
    for split, folder, split_seed in (("test", test, None), ("val", val, seed + val_seed_offset)):
        log.info("[v2x lidar generate] %s %s: %d pairs", LABEL, split, pairs)
        made = generate(path, folder, pairs, split_seed)
        record[split] = {"dir": str(folder), "pairs": pairs, "seed": split_seed or seed}
        record[split] |= {"new_records": made.new_records}
    return test, val, record


def evaluate_lidar(
    test_dir: str | Path,
    val_dir: str | Path,
    matchers: Sequence[MatcherSpec],
    seeds: Sequence[int],
    runner,
    out_dir: str | Path,
    tune: bool = True,
) -> tuple[pd.DataFrame, dict]:
    """The full table's protocol on the LiDAR splits (module docstring); (table, record)."""
    from eval.studies.v2x_boxes import box_matchers
    from eval.studies.v2x_table import evaluate_v2x

    chosen = box_matchers(matchers)
    log.info("[v2x lidar] %s: %d matchers on %s, %s", LABEL, len(chosen), test_dir, val_dir)
    table = evaluate_v2x(test_dir, val_dir, LABEL, chosen, seeds, runner, out_dir, tune=tune, name=NAME)  # fmt: skip
    return table, {"matchers": [m.name for m in chosen]}
