"""End to end with highway-env as the traffic source: a 2-pair dataset, generated twice."""

from __future__ import annotations

from pathlib import Path

import pytest

from cadsim.dataset import Dataset
from cadsim.generation.pipeline import generate_dataset

pytestmark = pytest.mark.render

SCENARIO = Path(__file__).resolve().parents[1] / "scenarios" / "highway-intersection.toml"


@pytest.fixture(scope="module")
def small_scenario(tmp_path_factory) -> Path:
    """The shipped scenario with smaller images (faster to render), otherwise unchanged."""
    text = SCENARIO.read_text()
    for old, new in (("width = 640", "width = 320"), ("height = 480", "height = 240")):
        assert old in text
        text = text.replace(old, new, 1)
    path = tmp_path_factory.mktemp("scenario") / "highway-small.toml"
    path.write_text(text)
    return path


def test_two_pair_generation_is_reproducible(small_scenario, tmp_path):
    first = generate_dataset(small_scenario, tmp_path / "a", pairs=2, workers=1, progress=False)
    second = generate_dataset(small_scenario, tmp_path / "b", pairs=2, workers=1, progress=False)
    assert first.pairs == second.pairs == 2
    assert first.checksum == second.checksum  # same scenario and seed => identical records

    ds = Dataset(tmp_path / "a", verify=True)
    assert ds.scenario_name == "highway-intersection"
    for pair in ds:
        assert len(pair.gt_pairs) >= 3  # DESIGN §5 acceptance held
        assert len(pair.view1) > len(pair.gt_pairs) or len(pair.view2) > len(pair.gt_pairs)
        snapshot_meta = pair.record["meta"]["snapshot"]
        arms = {snapshot_meta["approaches"][o]["arm"] for o in pair.observer_ids}
        assert len(arms) == 2  # observers approach on different arms
        classes = {o.cls for o in pair.objects}
        assert {"traffic_light", "sign", "building", "road"} <= classes
