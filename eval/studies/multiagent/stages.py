"""The stages of the multi-agent study on cad-multi: its test and validation snapshots, then
two-view matchers on every pair of views fused per subset of N views. They fill the run
record's ``multiagent`` section."""

from __future__ import annotations

import logging

from eval.engine.matcher_list import parse_matchers
from eval.engine.validation_choice import chosen_specs
from eval.pipeline.stage import RunState, generate_splits
from eval.studies.multiagent.evaluation import LABEL as MA_LABEL
from eval.studies.multiagent.evaluation import MATCHERS as MA_MATCHERS
from eval.studies.multiagent.evaluation import PRESETS as MA_PRESETS
from eval.studies.multiagent.evaluation import SCENARIO as MA_SCENARIO
from eval.studies.multiagent.evaluation import SUBSETS as MA_SUBSETS
from eval.studies.multiagent.evaluation import evaluate_multiagent
from eval.studies.multiagent.fused_cache import FOLDER as FUSED_FOLDER
from matchers.fusion import usable_fusions

log = logging.getLogger("eval.reproduce")


def multiagent_seeds(state: RunState) -> list[int]:
    return list(range(state.args.multiagent_runs))


def multiagent_generate(state: RunState) -> None:
    """cad-multi's test and validation snapshots on disjoint scenario seeds."""
    if not multiagent_seeds(state):
        return
    record = state.record.setdefault("multiagent", {})
    state.multi_dirs = generate_splits(
        state, MA_SCENARIO, (MA_LABEL, "cad-multi"), state.sizes.multiagent, "snapshots", record
    )


def multiagent(state: RunState) -> None:
    """The multi-agent table: CAD's tuned matchers, every fusion, every N, every preset."""
    seeds = multiagent_seeds(state)
    if state.multi_dirs is None:
        return
    named, _ = chosen_specs(state.out, "CAD", parse_matchers(",".join(MA_MATCHERS)))
    log.info(
        "[multiagent] %s: %d matchers × %d fusions × N in %s × %d presets × %d runs",
        MA_LABEL, len(named), len(usable_fusions()), sorted(MA_SUBSETS), len(MA_PRESETS),
        len(seeds),
    )  # fmt: skip
    evaluate_multiagent(
        *state.multi_dirs, named, seeds, state.runner, state.out,
        cache=state.runner.cache.root / FUSED_FOLDER,
    )  # fmt: skip
    record = state.record.setdefault("multiagent", {})
    record |= {"seeds": seeds, "matchers": list(named)}
    record |= {"presets": list(MA_PRESETS), "fusions": usable_fusions()}
    record |= {"subsets": {str(n): list(v) for n, v in MA_SUBSETS.items()}}
