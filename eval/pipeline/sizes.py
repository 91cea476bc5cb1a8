"""How much ``make reproduce`` generates and runs: the default sizes of every study's splits, and
:func:`plan_sizes`, every split's size for one run at a scale (``--scale k`` multiplies every split
and every "first N test pairs" subset by k). Counts are frame pairs, sequences or snapshots.

What these sizes resolve is measured, not assumed: ``results/power_analysis.csv``
(:mod:`eval.engine.power_analysis`, written by ``make report``) gives per covered comparison the
test clusters a ±5-point half-width or a 5-point MDD would need (docs/evaluation.md, "Power
analysis"). The sizes below are not derived from it; the cold-run budget decides whether those
clusters are drawn."""

from __future__ import annotations

import argparse
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from eval.studies import study

ROOT = Path(__file__).resolve().parents[2]
SCENARIOS = (
    "scenarios/cad-intersection.toml",
    "scenarios/mrc-arena.toml",
    "scenarios/cad-dense.toml",
)
VAL_SEED_OFFSET = 1000
DEFAULT_VAL_PAIRS = 50
TABLE1_TEST_PAIRS = {"CAD": 100, "CAD-dense": 100}
"""Table I's test pairs where more than the scenario's 50 are drawn (one episode each): the CAD
datasets, so that a difficulty level (a third of the pairs) holds ~33 clusters; MRC keeps 50
(docs/evaluation.md, "Difficulty levels"). ``--pairs`` overrides. The clusters the headline
level's maximin-against-rival MDD of 5 points would need: ``power_analysis.csv``."""
# The sweeps are lighter than Table I to keep a cold `make reproduce` within 15 minutes on two
# cores (docs/evaluation.md). Noise: the first SWEEP_PAIRS test pairs, SWEEP_RUNS seeds.
SWEEP_PAIRS = 25
SWEEP_RUNS = 4
SWEEP_DATASETS = ("CAD", "MRC")  # Fig. 4 rows: the paper's CAD, and MRC for its geometry
# Regime sweep: every dataset, the first REGIME_PAIRS test pairs × REGIME_RUNS runs per level (each
# run its own thinning draw: 5 independent draws), τ recalibrated per level on the thinned
# validation set with run 0 alone.
REGIME_PAIRS = 25
REGIME_RUNS = 5
REGIME_VAL_RUNS = 1
# Dataset spread: the default CAD generated again with these scenario-seed offsets.
SPREAD_DATASET = "CAD"
SPREAD_SEED_OFFSETS = (2000, 3000)
SPREAD_PAIRS = 25
SPREAD_RUNS = 4
# Localisation sweep (CAD): the first LOCALISATION_PAIRS test pairs × LOCALISATION_RUNS seeds per
# position error, τ per error on the validation set re-drawn at that error.
LOCALISATION_DATASET = "CAD"
LOCALISATION_PAIRS = 25
LOCALISATION_RUNS = 4
# External benchmark (DMGM CAD): EXTERNAL_RUNS seeds; parameters tuned and τ calibrated on all of
# sequence 070 (EXTERNAL_TUNE_PAIRS = 0: every pair), as the prior defaults were derived
# (docs/external-data.md). Shipped data: not scaled.
EXTERNAL_RUNS = 1
EXTERNAL_TUNE_PAIRS = 0
# V2X realism (cad-v2x, outside Table I): test, validation and training splits on disjoint
# scenario seeds (seed, seed + VAL_SEED_OFFSET, seed + V2X_TRAIN_SEED_OFFSET; the training split,
# V2X_TRAIN_FACTOR × the test pairs, is for learned matchers and is never evaluated on: the
# transfer study generates it, its only reader), then the localisation sweep's preset axes
# (error scale, latency) with CAD's tuned parameters, τ per level.
V2X_SCENARIO = "scenarios/cad-v2x.toml"
V2X_LABEL = "CAD-V2X"
V2X_PAIRS = 100  # test: one pair per episode (the scenarios' pairs_per_episode = 1), 100 clusters
# (the clusters each preset's best − runner-up ±5-point half-width needs: power_analysis.csv)
V2X_VAL_PAIRS = 50
V2X_TRAIN_SEED_OFFSET = 2000
V2X_TRAIN_FACTOR = 1
V2X_RUNS = 2  # runs only average the stochastic matchers; 100 clusters carry the precision
# Multi-agent (cad-multi: 4 vehicles + 2 roadside units per snapshot): test and validation
# snapshots on disjoint scenario seeds, two-view matchers on every pair of views, fused per
# subset of N views (eval.studies.multiagent.evaluation), MULTIAGENT_RUNS seeds. The multi-agent
# and temporal split sizes are the studies' own (Study.data); the clusters their goals' 5-point
# MDD needs: power_analysis.csv.
MULTIAGENT_RUNS = 2
# Transfer of the learned matchers (eval.studies.transfer.evaluation): CAD's training split on its own
# scenario seed (seed + CAD_TRAIN_SEED_OFFSET; 1000 is validation, 2000/3000 the spread sets),
# CAD_TRAIN_PAIRS pairs; models trained into DATA/models.
CAD_TRAIN_SEED_OFFSET = 4000
CAD_TRAIN_PAIRS = 50


def parse_scale(text: str) -> int:
    """``--scale``: an integer ≥ 1 (argparse reports anything else as one line, exit 2)."""
    try:
        value = int(text)
    except ValueError:
        value = 0
    if value < 1 or str(value) != text.strip():
        raise argparse.ArgumentTypeError(f"expected an integer >= 1, got {text!r}")
    return value


@dataclass(frozen=True)
class SplitSizes:
    """Every split's size for one run, scale applied. ``datasets``: per Table I scenario (in
    order) its label and (test, validation) pairs; ``spread``: pairs of each extra spread dataset;
    ``v2x``, ``multiagent``, ``temporal``: per split (test, val[, train]); ``lidar``: pairs of each
    two-sensor split (test, val); ``cad_train``: CAD's training pairs; ``sweep``, ``regime``,
    ``localisation``: the first N test pairs those sweeps use (None: all)."""

    scale: int
    datasets: tuple[tuple[str, int, int], ...]
    spread: int
    v2x: dict[str, int]
    lidar: dict[str, int]
    multiagent: dict[str, int]
    temporal: dict[str, int]
    cad_train: int
    sweep: int | None
    regime: int | None
    localisation: int | None

    def data_root(self, data: Path) -> Path:
        """Where this run's datasets go: ``data`` at scale 1, ``data/scale-k`` otherwise (a
        dataset folder holds one size)."""
        return data if self.scale == 1 else data / f"scale-{self.scale}"

    def record(self) -> dict:
        """The sizes under the run record's keys (``v2x.test.pairs``, ``temporal.test.sequences``,
        ``multiagent.test.snapshots``, ``datasets[i].test_pairs``, …)."""
        return {
            "scale": self.scale,
            "datasets": [
                {"label": label, "test_pairs": test, "val_pairs": val}
                for label, test, val in self.datasets
            ],
            "dataset_spread": {"pairs": self.spread},
            "v2x": {split: {"pairs": n} for split, n in self.v2x.items()}
            | {"lidar": {split: {"pairs": n} for split, n in self.lidar.items()}},
            "multiagent": {split: {"snapshots": n} for split, n in self.multiagent.items()},
            "temporal": {split: {"sequences": n} for split, n in self.temporal.items()},
            "transfer": {"cad_train": {"pairs": self.cad_train}},
            "noise_sweep": {"pairs": self.sweep},
            "regime_sweep": {"pairs": self.regime},
            "localisation_sweep": {"pairs": self.localisation},
        }


def _capped(cap: int | None, n: int) -> int:
    """``n``, capped by ``--pairs`` when given."""
    return n if cap is None else min(cap, n)


def _subset(n: int, scale: int) -> int | None:
    """A "first N test pairs" option at a scale (0: every pair, None)."""
    return n * scale or None


def plan_sizes(args: argparse.Namespace, scenarios: Sequence[tuple[str, int]]) -> SplitSizes:
    """Every split's size from the parsed options (``--pairs``, ``--val-pairs``, the sweeps'
    ``--*-pairs`` and ``--scale``) and the Table I ``scenarios`` as (label, scenario's pairs);
    generates nothing. Scale 1 gives the sizes the options alone give."""
    k = args.scale
    unscaled = []  # (label, test pairs, validation pairs) at scale 1
    for label, scenario_pairs in scenarios:
        pairs = TABLE1_TEST_PAIRS.get(label, scenario_pairs) if args.pairs is None else args.pairs
        unscaled.append((label, pairs, args.val_pairs or min(DEFAULT_VAL_PAIRS, pairs)))
    spread_test = next((test for label, test, _ in unscaled if label == SPREAD_DATASET), 0)
    v2x = _capped(args.pairs, V2X_PAIRS) * k
    multi = study("multiagent").data_named("cad-multi").splits  # as each study declares them
    sequences = study("temporal").data_named("cad-v2x-seq").splits
    v2x_val = _capped(args.pairs, V2X_VAL_PAIRS) * k
    return SplitSizes(
        scale=k,
        datasets=tuple((label, test * k, val * k) for label, test, val in unscaled),
        spread=min(args.spread_pairs, spread_test) * k,
        v2x={"test": v2x, "val": v2x_val, "train": V2X_TRAIN_FACTOR * v2x},
        lidar={"test": v2x, "val": v2x_val},
        multiagent={
            "test": _capped(args.pairs, multi["test"]) * k,
            "val": _capped(args.pairs, multi["val"]) * k,
        },
        temporal={
            "test": _capped(args.pairs, sequences["test"]) * k,
            "val": _capped(args.pairs, sequences["val"]) * k,
        },
        cad_train=_capped(args.pairs, CAD_TRAIN_PAIRS) * k,
        sweep=_subset(args.sweep_pairs, k),
        regime=_subset(args.regime_pairs, k),
        localisation=_subset(args.localisation_pairs, k),
    )
