"""In-process random demand (cadsim/sources/sumo/demand.py): routes that exist in the network,
departures at the period, types at their probabilities, the same files for the same seed (warm or
cold plan cache), other files for another seed; and real generation that gives one dataset with
one worker or two, in one call or resumed (the same checksum)."""

from __future__ import annotations

import re
from collections import Counter
from pathlib import Path

import pytest
import sumolib

from cadsim.dataset import Dataset
from cadsim.generation.pipeline import generate_dataset
from cadsim.scenario import load_scenario
from cadsim.sources.sumo import demand as demand_module
from cadsim.sources.sumo.build import build_network
from cadsim.sources.sumo.demand import DEMAND_MODEL, departures, read_types, write_demand

ROOT = Path(__file__).resolve().parents[1]
SCENARIO = ROOT / "scenarios" / "cad-v2x.toml"
VTYPES = ROOT / "scenarios" / "cad-vtypes.add.xml"


@pytest.fixture(scope="module")
def net(tmp_path_factory) -> Path:
    scenario = load_scenario(SCENARIO)
    return build_network(scenario.traffic["network"], tmp_path_factory.mktemp("net"))


@pytest.fixture(scope="module")
def demand() -> dict:
    return dict(load_scenario(SCENARIO).traffic["demand"])


def _files(net: Path, demand: dict, seed: int, folder: Path) -> dict[str, str]:
    drawn = write_demand(net, demand, seed, folder)
    return {p.name: p.read_text() for p in drawn.routes}


def test_same_seed_same_files_warm_or_cold_other_seed_other_files(net, demand, tmp_path):
    demand_module._plans.clear()
    cold = _files(net, demand, 5, tmp_path / "a")
    warm = _files(net, demand, 5, tmp_path / "b")  # the plan now cached
    assert cold == warm and set(cold) == {"vehicles.rou.xml", "bicycles.rou.xml", "persons.rou.xml"}
    other = _files(net, demand, 6, tmp_path / "c")
    assert other["vehicles.rou.xml"] != cold["vehicles.rou.xml"]


def test_routes_exist_in_the_network_from_fringe_to_fringe(net, demand, tmp_path):
    files = _files(net, demand, 11, tmp_path)
    road = sumolib.net.readNet(str(net))
    routes = re.findall(r'type="([^"]+)".*?<route edges="([^"]+)"', files["vehicles.rou.xml"])
    assert len(routes) == len(departures(demand["vehicle_period"], demand["end"]))
    classes = {
        t: c for c in read_types(VTYPES).values() for t, c in zip(c.ids, c.classes, strict=True)
    }
    for vtype, route in routes:
        edges = [road.getEdge(e) for e in route.split()]
        assert not edges[0].getIncoming() and not edges[-1].getOutgoing()  # fringe to fringe
        for a, b in zip(edges, edges[1:], strict=False):
            assert b in a.getOutgoing()  # every step a connection: a route sumo can drive
        assert all(e.allows(classes[vtype]) for e in edges)
        # never back out along the arm it came from (U-turns are disabled)
        assert edges[0].getFromNode() != edges[-1].getToNode()
    walks = re.findall(r'<walk from="([^"]+)" to="([^"]+)"', files["persons.rou.xml"])
    assert len(walks) == len(departures(demand["person_period"], demand["end"]))
    assert all(road.getEdge(a).allows("pedestrian") for pair in walks for a in pair)


def test_departures_follow_the_period_and_types_their_probabilities(net, demand, tmp_path):
    assert list(departures(4.0, 20.0)) == [0.0, 4.0, 8.0, 12.0, 16.0]
    assert len(departures(0.0, 20.0)) == 0
    dense = demand | {"vehicle_period": 0.05, "end": 1000.0}  # 20,000 vehicles
    files = _files(net, dense, 3, tmp_path)
    times = [float(t) for t in re.findall(r'depart="([^"]+)"', files["vehicles.rou.xml"])]
    assert times[:3] == [0.0, 0.05, 0.1] and len(times) == 20_000
    counts = Counter(re.findall(r'<vehicle id="[^"]+" type="([^"]+)"', files["vehicles.rou.xml"]))
    choice = read_types(VTYPES)["vehicles"]
    total = choice.cumulative[-1]
    previous = 0.0
    for vtype, cumulative in zip(choice.ids, choice.cumulative, strict=True):
        share = (cumulative - previous) / total
        previous = cumulative
        assert counts[vtype] / 20_000 == pytest.approx(share, abs=0.012), vtype


# --------------------------------------------------------------------------- whole datasets


@pytest.fixture(scope="module")
def one_call(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("demand-gen") / "one"
    generate_dataset(SCENARIO, out, pairs=3, workers=1, progress=False)
    return out


@pytest.mark.slow
@pytest.mark.render
def test_the_manifest_states_the_demand_model(one_call):
    assert Dataset(one_call).manifest["generation"]["demand"] == DEMAND_MODEL


@pytest.mark.slow
@pytest.mark.render
def test_two_workers_give_the_same_dataset(one_call, tmp_path):
    out = tmp_path / "two"
    generate_dataset(SCENARIO, out, pairs=3, workers=2, progress=False)
    assert Dataset(out).checksum == Dataset(one_call).checksum


@pytest.mark.slow
@pytest.mark.render
def test_a_resumed_run_gives_the_same_dataset(one_call, tmp_path):
    """Two pairs (episode 0), then three: episode 1 is run in the second call."""
    out = tmp_path / "resumed"
    generate_dataset(SCENARIO, out, pairs=2, workers=1, progress=False)
    result = generate_dataset(SCENARIO, out, pairs=3, workers=1, progress=False)
    assert result.new_records == 1
    assert Dataset(out).checksum == Dataset(one_call).checksum
