"""Issue 15 #4 and #9: every number in a scenario is finite and bounded where memory or time grow
with it, ranges are consistent, lists that must not be empty are not; a file that is not UTF-8
is named; ``cadsim schema`` prints a JSON Schema generated from the same declarations."""

from __future__ import annotations

import json
import tomllib
from pathlib import Path

import pytest

from cadsim.cli import main
from cadsim.scenario import CAMERA, OBSERVERS, SAMPLING, ScenarioError, load_scenario
from cadsim.scenario_schema import scenario_json_schema

ROOT = Path(__file__).resolve().parents[1]
SCENARIOS = sorted((ROOT / "scenarios").glob("*.toml"))
CROSS = '[traffic]\nsource = "sumo"\nsumocfg = "$SUMO_HOME/tools/game/cross.sumocfg"\n'
ARENA = (ROOT / "scenarios" / "mrc-arena.toml").read_text()
HIGHWAY = (ROOT / "scenarios" / "highway-intersection.toml").read_text()
CAD = (
    ROOT / "scenarios" / "cad-dense.toml"
).read_text()  # the old default: its values are pinned below


def _error(tmp_path: Path, text: str | bytes) -> ScenarioError:
    path = tmp_path / "s.toml"
    if isinstance(text, bytes):
        path.write_bytes(text)
    else:
        path.write_text(text)
        (tmp_path / "cad-vtypes.add.xml").write_bytes(
            (ROOT / "scenarios" / "cad-vtypes.add.xml").read_bytes()
        )
    with pytest.raises(ScenarioError) as info:
        load_scenario(path)
    assert str(info.value).startswith(str(path.resolve()))
    return info.value


@pytest.mark.parametrize(
    "text, key",
    [
        (CROSS + "[camera]\nhfov_deg = inf\n", "camera.hfov_deg"),
        (CROSS + "[observers]\nmax_distance = nan\n", "observers.max_distance"),
        (CROSS + "[sampling]\nmax_time = inf\n", "sampling.max_time"),
        (CROSS + "[noise]\nnoise_rate = inf\n", "noise.noise_rate"),
        (
            CROSS + "[traffic.scene]\nbuilding_heights = [6.0, inf]\n",
            "traffic.scene.building_heights[1]",
        ),  # fmt: skip
        (HIGHWAY.replace("duration = 40", "duration = inf"), "traffic.env.duration"),
        (ARENA.replace("size = [8.0, 6.0]", "size = [-inf, 6.0]", 1), "traffic.size[0]"),
    ],
)
def test_inf_and_nan_are_refused_naming_the_key(tmp_path, text, key):
    err = _error(tmp_path, text)
    assert err.key == key and "a finite number" in str(err)


@pytest.mark.parametrize(
    "text, key, words",
    [
        (CROSS + "[camera]\nwidth = 100000\n", "camera.width", "<= 4096"),
        ("pairs = 10000000\n" + CROSS, "pairs", "<= 100000"),
        (
            CROSS + "[sampling]\npairs_per_episode = 100000\n",
            "sampling.pairs_per_episode",
            "<= 10000",
        ),  # fmt: skip
        (
            CROSS + "[observers]\nmin_distance = 50.0\nmax_distance = 40.0\n",
            "observers.min_distance",
            "min_distance <= max_distance",
        ),  # fmt: skip
        (CROSS + "[observers]\nclasses = []\n", "observers.classes", "non-empty"),
        (CROSS + "[detection]\nmax_truncation = 1.5\n", "detection.max_truncation", "<= 1.0"),
        (
            CROSS + "[detection]\nmin_visible_fraction = -0.1\n",
            "detection.min_visible_fraction",
            ">= 0.0",
        ),  # fmt: skip
        (CROSS + "[noise]\nnoise_rate = 5.0\n", "noise.noise_rate", "<= 1.0"),
        (
            CAD.replace("vehicle_period = 0.9", "vehicle_period = 1e-6"),
            "traffic.demand.vehicle_period",
            ">= 0.01",
        ),  # fmt: skip
        (
            CAD.replace("person_period = 2.5", "person_period = 0.01").replace(
                "end = 1200.0", "end = 100000.0"
            ),
            "traffic.demand.person_period",
            "at most 1000000 trips",
        ),  # fmt: skip
        (CAD.replace("junctions = 1 ", "junctions = 1000 "), "traffic.network.junctions", "<= 20"),
        (ARENA.replace("count = ", "count = 10000000 #", 1), "traffic.robots[0].count", "<= 1000"),
    ],
)
def test_limits_and_consistency(tmp_path, text, key, words):
    err = _error(tmp_path, text)
    assert err.key == key and words in str(err)


def test_a_file_that_is_not_utf8_is_named(tmp_path):
    err = _error(tmp_path, b'name = "caf\xe9"\n' + CROSS.encode())
    assert err.key == "" and "not UTF-8" in str(err) and "0xe9 at offset 11" in str(err)


# --------------------------------------------------------------------------- cadsim schema


def test_schema_is_generated_from_the_declarations(capsys):
    assert main(["schema"]) == 0
    schema = json.loads(capsys.readouterr().out)
    assert schema == json.loads(json.dumps(scenario_json_schema()))
    props = schema["properties"]
    for name, table in (("camera", CAMERA), ("observers", OBSERVERS), ("sampling", SAMPLING)):
        assert set(props[name]["properties"]) == set(table.fields)
    assert props["camera"]["properties"]["width"]["maximum"] == 4096
    kinds = {v["properties"]["source"]["const"] for v in props["traffic"]["oneOf"]}
    assert kinds >= {"sumo", "arena", "highway-env"}  # and any a test registered
    assert {"noise_rate", "correlation_length_px"} <= set(props["noise"]["properties"])


@pytest.mark.parametrize("path", SCENARIOS, ids=lambda p: p.name)
def test_every_shipped_scenario_satisfies_the_schema(path):
    jsonschema = pytest.importorskip("jsonschema")
    jsonschema.validate(tomllib.loads(path.read_text()), scenario_json_schema())


@pytest.mark.parametrize(
    "text",
    [
        CROSS + "[camera]\nwidth = 100000\n",
        CROSS + "[camera]\nwidht = 640\n",
        CROSS + "pairs = 0\n",
        '[traffic]\nsource = "carla"\n',
        CROSS + "[noise]\nnoise_rat = 0.1\n",
    ],
)
def test_the_schema_rejects_what_the_validator_rejects(text):
    jsonschema = pytest.importorskip("jsonschema")
    with pytest.raises(jsonschema.ValidationError):
        jsonschema.validate(tomllib.loads(text), scenario_json_schema())


def test_scenario_errors_survive_the_trip_from_a_worker_process():
    import pickle

    err = pickle.loads(pickle.dumps(ScenarioError("/x/s.toml", "traffic.sumocfg", "bad", "good")))
    assert (str(err.path), err.key, err.problem, err.expected) == (
        "/x/s.toml", "traffic.sumocfg", "bad", "good",
    )  # fmt: skip
    assert str(err) == "/x/s.toml: traffic.sumocfg: bad; expected good"
