"""The stages of the learned matchers' transfer matrix: CAD's and CAD-V2X's training splits,
then models trained on each training set and run on each test set. They fill the run record's ``transfer``
section; they need cad-v2x and the external pairs (skipped without either)."""

from __future__ import annotations

import logging

from eval.pipeline.sizes import (
    CAD_TRAIN_SEED_OFFSET,
    ROOT,
    SCENARIOS,
    V2X_SCENARIO,
    V2X_TRAIN_SEED_OFFSET,
)
from eval.pipeline.stage import RunState, shown
from eval.studies.external.evaluation import CALIBRATION_DIR, TEST_DIR
from eval.studies.transfer.evaluation import evaluate_transfer, test_sets, train_models, train_sets
from eval.studies.transfer.sets import CAD_TRAIN_DIR, V2X_TRAIN_DIR

log = logging.getLogger("eval.reproduce")


def transfer_generate(state: RunState) -> None:
    """The learned matchers' training splits, each on its scenario's own seed: CAD's (seed +
    CAD_TRAIN_SEED_OFFSET) and CAD-V2X's (seed + V2X_TRAIN_SEED_OFFSET, beside the test split
    the V2X study made), when cad-v2x and the external pairs are part of this run and the CAD
    scenario exists. No other study reads them."""
    from cadsim.scenario import load_scenario

    path = ROOT / SCENARIOS[0]
    if state.v2x_entry is None or not state.args.external_runs or not path.is_file():
        return
    record = state.record.setdefault("transfer", {})
    v2x_path = ROOT / V2X_SCENARIO
    splits = (
        ("cad_train", "CAD", path, CAD_TRAIN_SEED_OFFSET, state.sizes.cad_train, CAD_TRAIN_DIR),
        ("v2x_train", "CAD-V2X", v2x_path, V2X_TRAIN_SEED_OFFSET, state.sizes.v2x["train"],
         V2X_TRAIN_DIR),
    )  # fmt: skip
    for key, label, scenario, offset, pairs, name in splits:
        folder = state.data / name
        seed = load_scenario(scenario).seed + offset
        log.info("[transfer generate] %s train: %d pairs (seed %d)", label, pairs, seed)
        made = state.generate(scenario, folder, pairs, seed)
        record[key] = {"dir": str(folder), "pairs": pairs, "seed": seed}
        record[key] |= {"new_records": made.new_records}
    state.cad_train = state.data / CAD_TRAIN_DIR


def transfer(state: RunState) -> None:
    """Models trained on each training set, run on every test set."""
    if state.cad_train is None:
        return
    sets = train_sets(state.data, state.cad_train, CALIBRATION_DIR)
    tests = test_sets(state.data, state.out, TEST_DIR, CALIBRATION_DIR)
    log.info("[transfer] %d models × %d test sets × 4 learned matchers", len(sets), len(tests))
    models = train_models(sets, state.data / "models", state.progress)
    evaluate_transfer(models, tests, state.runner, state.out)
    state.record.setdefault("transfer", {}).update(
        {
            "train": {k: [shown(d) for d in v] for k, v in sets.items()},
            "test": [t.label for t in tests],
            "train_s": {k: round(v[1], 2) for k, v in models.items()},
        }
    )
