"""Equal tuning budget: each matcher's configuration is chosen on validation pairs only (seed 0),
by mean per-pair F1 at the configuration's own τ; the untuned table stays beside the tuned one."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest
from frame_pair_fakes import make_dataset

from eval.core import tasks
from eval.core.cache import ResultCache
from eval.core.executor import SerialExecutor
from eval.core.runner import Runner
from eval.core.tasks import MatcherSpec
from eval.engine.protocol_run import evaluate
from eval.engine.splits import open_entry
from eval.engine.validation_choice import chosen_specs
from eval.protocol import calibration, tuning
from matchers.core.discretise import discretise
from matchers.core.matching import Matching
from matchers.core.problem import Problem


def noisy_matcher(problem: Problem, seed: int = 0, threshold=None, blur: float = 1.0) -> Matching:
    """Appearance similarity drowned in `blur` × uniform noise: less blur, better matching."""
    f1 = problem.features1 / np.linalg.norm(problem.features1, axis=1, keepdims=True)
    f2 = problem.features2 / np.linalg.norm(problem.features2, axis=1, keepdims=True)
    rng = np.random.default_rng([seed, problem.n1, problem.n2])
    scores = (f1 @ f2.T + 1) / 2 + blur * rng.uniform(size=(problem.n1, problem.n2))
    scores = scores / scores.max()
    return Matching(discretise(scores, threshold), scores, "noisy", time_s=1e-3)


GRIDS = {
    "noisy": [{}, {"blur": 0.0}, {"blur": 3.0}],
    "flat": [{}],
}


@pytest.fixture
def world(monkeypatch):
    datasets = {
        "data/cad": make_dataset(100, 6),
        "data/cad-val": make_dataset(900, 4),
    }
    monkeypatch.setattr(tasks, "open_dataset", lambda path: datasets[path])
    monkeypatch.setattr(tasks, "matcher_function", lambda name: noisy_matcher)
    monkeypatch.setattr(tuning, "grid", lambda name: GRIDS[name])
    return datasets


def _runner(tmp_path) -> Runner:
    return Runner(ResultCache(tmp_path / "cache"), SerialExecutor(), version="v", progress=False)


def test_tuning_never_sees_test_pairs_and_uses_seed_zero(world, tmp_path, monkeypatch):
    runner = _runner(tmp_path)
    requested, calibrated = [], []
    real_run, real_calibrate = runner.run, calibration.calibrate

    def run_spy(requests, desc="runs"):
        requested.extend(requests)
        return real_run(requests, desc)

    def calibrate_spy(runs):
        calibrated.extend(runs)
        return real_calibrate(runs)

    monkeypatch.setattr(runner, "run", run_spy)
    monkeypatch.setattr(calibration, "calibrate", calibrate_spy)
    entry = open_entry("data/cad", "data/cad-val")
    choices = tuning.tune_entry(entry, [MatcherSpec("noisy"), MatcherSpec("flat")], runner)

    assert {r.dataset_dir for r in requested} == {"data/cad-val"}
    assert {r.seed for r in requested} == {tuning.TUNING_SEED}
    seen = {o.sim_seed for run in calibrated for o in run.outcomes}
    assert seen == {p.sim_seed for p in world["data/cad-val"]}
    assert not seen & {p.sim_seed for p in world["data/cad"]}
    # One configuration per grid entry, the clean one wins; a one-entry grid keeps its defaults.
    noisy = choices["noisy"]
    assert [c.config for c in noisy.candidates] == GRIDS["noisy"]
    assert noisy.params == {"blur": 0.0} and noisy.spec == MatcherSpec.of("noisy", blur=0.0)
    f1 = [c.val_f1 for c in noisy.candidates]
    assert f1[1] == max(f1) and f1[1] > f1[0]
    assert choices["flat"].params == {} and len(choices["flat"].candidates) == 1


@pytest.mark.parametrize("order", [[{}, {"blur": 1.0}], [{"blur": 1.0}, {}]])
def test_ties_do_not_favour_the_defaults_or_the_grid_order(world, tmp_path, monkeypatch, order):
    monkeypatch.setattr(tuning, "grid", lambda name: order)  # blur 1.0 is the default: a tie
    choices = tuning.tune_entry(
        open_entry("data/cad", "data/cad-val"), [MatcherSpec("noisy")], _runner(tmp_path)
    )
    a, b = choices["noisy"].candidates
    assert a.val_f1 == b.val_f1 and choices["noisy"].params == {"blur": 1.0}


def test_untunable_matchers_are_left_out_of_the_tuning_table(world, tmp_path):
    entry = open_entry("data/cad", "data/cad-val")
    choices = tuning.tune_entry(
        entry, [MatcherSpec("noisy"), MatcherSpec("flat")], _runner(tmp_path)
    )
    rows = pd.DataFrame(tuning.tuning_rows(choices.values()))
    assert set(rows["matcher"]) == {"noisy"} and len(rows) == len(GRIDS["noisy"])


def test_every_tunable_builtin_matcher_gets_the_same_budget():
    from matchers import available, search_space
    from matchers.core.search_spaces import TUNING_BUDGET

    sizes = {name: len(search_space(name)) for name in available()}
    assert {size for size in sizes.values() if size > 1} == {TUNING_BUDGET}, sizes
    # the learned matchers' classifier is their tuning (trained on training data, not searched)
    assert sorted(n for n, size in sizes.items() if size == 1) == [
        "appearance",
        "learned",
        "learned_pose",
        "none",
    ]


def test_tuned_evaluation_writes_tuning_the_untuned_table_and_the_chosen_parameters(
    world, tmp_path, monkeypatch
):
    calibrated = []
    real = calibration.calibrate

    def spy(runs):
        calibrated.extend(runs)
        return real(runs)

    monkeypatch.setattr(calibration, "calibrate", spy)
    out = tmp_path / "out"
    runner = _runner(tmp_path)
    entry = open_entry("data/cad", "data/cad-val")
    taus = evaluate([entry], [MatcherSpec("noisy")], [0, 1], runner, out, tune=True)
    assert {o.sim_seed for r in calibrated for o in r.outcomes} <= {
        p.sim_seed for p in world["data/cad-val"]
    }

    table = pd.read_csv(out / "tuning.csv")
    assert list(table.columns) == ["dataset", "matcher", "config", "params", "val_f1", "tau"] + [
        "chosen"
    ]
    assert table["chosen"].sum() == 1
    assert json.loads(table.loc[table["chosen"], "params"].item()) == {"blur": 0.0}

    tuned = pd.read_csv(out / "metrics_per_pair.csv")
    untuned = pd.read_csv(out / "metrics_per_pair_untuned.csv")
    assert set(tuned["params"]) == {'{"blur":0.0}'} and set(untuned["params"]) == {"{}"}
    assert tuned["matcher"].unique().tolist() == ["noisy"]  # the row keeps the matcher's name
    assert tuned["f1"].mean() > untuned["f1"].mean()
    # The sweeps read the choice back, with the τ calibrated for it on every validation seed.
    named, chosen_taus = chosen_specs(out, "CAD", [MatcherSpec("noisy")])
    assert named["noisy"] == MatcherSpec.of("noisy", blur=0.0)
    assert chosen_taus["noisy"] == pytest.approx(taus["CAD"]["noisy"])
    thresholds = pd.read_csv(out / "thresholds.csv")
    assert thresholds["val_runs"].tolist() == [2]

    # Tuned, untuned and search share runs through the cache: a second evaluation computes nothing.
    computed = runner.totals.computed
    evaluate([entry], [MatcherSpec("noisy")], [0, 1], runner, out, tune=True)
    assert runner.totals.computed == computed


def test_tuning_needs_a_validation_set(world, tmp_path):
    with pytest.raises(ValueError, match="validation"):
        tuning.tune_entry(open_entry("data/cad", None), [MatcherSpec("noisy")], _runner(tmp_path))
