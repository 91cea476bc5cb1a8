"""The stages on the shipped DMGM CAD pairs (``eval/data/dmgm-cad``, not generated, so not
scaled): the external benchmark with the ranking agreement, and the prior matchers' grid
sensitivity. They fill the run record's ``external`` section."""

from __future__ import annotations

import logging

from eval.engine.matcher_list import with_prior
from eval.pipeline.stage import RunState, shown
from eval.studies.external.agreement import write_agreement
from eval.studies.external.evaluation import (
    CALIBRATION_DIR,
    TEST_DIR,
    evaluate_external,
)
from eval.studies.external.prior_defaults import write_sensitivity

log = logging.getLogger("eval.reproduce")


def external_seeds(state: RunState) -> list[int]:
    return list(range(state.args.external_runs))


def external(state: RunState) -> None:
    """Every matcher on the DMGM CAD pairs, tuned and τ calibrated on sequence 070."""
    args, seeds = state.args, external_seeds(state)
    if seeds:
        matchers = with_prior(args.matchers)
        log.info(
            "[external] DMGM CAD: %d matchers × %d runs; τ and tuning on sequence 070",
            len(matchers), len(seeds),
        )  # fmt: skip
        evaluate_external(
            state.runner, state.out, matchers, seeds,
            tune=args.tune, tune_pairs=args.external_tune_pairs or None,
        )  # fmt: skip
        write_agreement(state.out)
    state.record["external"] = {
        "test_dir": shown(TEST_DIR),
        "calibration_dir": shown(CALIBRATION_DIR),
        "seeds": seeds,
        "tune_pairs": args.external_tune_pairs or None,
    }


def prior_sensitivity(state: RunState) -> None:
    """Every grid point of the prior matchers on sequences 069 + 071 (tuned runs only)."""
    if external_seeds(state) and state.args.tune:
        log.info("[prior sensitivity] every grid point of the prior matchers on 069 + 071")
        write_sensitivity(state.out, state.runner)
