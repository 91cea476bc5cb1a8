"""Every record of the studies' scenarios is its own cluster: one frame pair (snapshot,
sequence) per simulation episode, each episode its own simulation seed (docs/evaluation.md,
"Sizes for power")."""

from __future__ import annotations

from pathlib import Path

import pytest

from cadsim.dataset import Dataset
from cadsim.generation.pipeline import generate_dataset
from cadsim.scenario import load_scenario
from eval.pipeline.sizes import SCENARIOS, V2X_SCENARIO
from eval.studies.multiagent.evaluation import SCENARIO as MULTIAGENT
from eval.studies.temporal.evaluation import LIDAR_SCENARIO, SCENARIO
from eval.studies.v2x.lidar import SCENARIO as BOTH

ROOT = Path(__file__).resolve().parents[1]
STUDIED = (*SCENARIOS, V2X_SCENARIO, BOTH, MULTIAGENT, SCENARIO, LIDAR_SCENARIO)


@pytest.mark.parametrize("scenario", STUDIED)
def test_every_studied_scenario_draws_one_record_per_episode(scenario):
    assert load_scenario(ROOT / scenario).sampling["pairs_per_episode"] == 1


def test_each_record_is_its_own_simulation(tmp_path):
    generate_dataset(ROOT / "scenarios" / "mrc-arena.toml", tmp_path / "d", pairs=3, workers=1, progress=False)  # fmt: skip
    data = Dataset(tmp_path / "d")
    episodes = [data[k].episode for k in range(len(data))]
    seeds = [data[k].sim_seed for k in range(len(data))]
    assert len(set(episodes)) == len(data) == 3
    assert len(set(seeds)) == 3
