"""The stages of the learned matchers' transfer matrix: CAD's training split, then models
trained on each training set and run on each test set. They fill the run record's ``transfer``
section; they need cad-v2x and the external pairs (skipped without either)."""

from __future__ import annotations

import logging

from eval.pipeline.sizes import CAD_TRAIN_SEED_OFFSET, ROOT, SCENARIOS
from eval.pipeline.stage import RunState, shown
from eval.studies.external.evaluation import CALIBRATION_DIR, TEST_DIR
from eval.studies.transfer.evaluation import evaluate_transfer, test_sets, train_models, train_sets

log = logging.getLogger("eval.reproduce")


def transfer_generate(state: RunState) -> None:
    """CAD's training split for the learned matchers (scenario seed + CAD_TRAIN_SEED_OFFSET),
    when cad-v2x and the external pairs are part of this run and the CAD scenario exists."""
    from cadsim.scenario import load_scenario

    path = ROOT / SCENARIOS[0]
    if state.v2x_entry is None or not state.args.external_runs or not path.is_file():
        return
    seed = load_scenario(path).seed + CAD_TRAIN_SEED_OFFSET
    pairs, folder = state.sizes.cad_train, state.data / "cad-train"
    log.info("[transfer generate] CAD train: %d pairs (seed %d)", pairs, seed)
    made = state.generate(path, folder, pairs, seed)
    record = state.record.setdefault("transfer", {})
    record["cad_train"] = {"dir": str(folder), "pairs": pairs, "seed": seed}
    record["cad_train"] |= {"new_records": made.new_records}
    state.cad_train = folder


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
