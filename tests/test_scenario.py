"""Scenario files: loading, defaults, path resolution and the promised error messages."""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

import pytest

from cadsim.scenario import (
    CameraConfig,
    Field,
    ScenarioContext,
    ScenarioError,
    Table,
    load_scenario,
    register_source_schema,
    validate_dataclass_table,
)

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT / "tests" / "data" / "scenarios"
DEFAULT = ROOT / "scenarios" / "cad-intersection.toml"
GAME_CROSS = "$SUMO_HOME/tools/game/cross.sumocfg"


def write(tmp_path: Path, text: str, name: str = "s.toml") -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


def external(extra: str = "") -> str:
    return f'[traffic]\nsource = "sumo"\nsumocfg = "{GAME_CROSS}"\n' + extra


def error_of(path: Path) -> ScenarioError:
    with pytest.raises(ScenarioError) as info:
        load_scenario(path)
    return info.value


# --------------------------------------------------------------------------- valid files


def test_default_scenario_loads_with_its_values():
    s = load_scenario(DEFAULT)
    assert s.name == "cad-intersection" and s.seed == 7 and s.pairs == 50
    assert s.text == DEFAULT.read_text()
    assert s.camera == CameraConfig(800, 600, 90.0, "roof", 0.0)
    t = s.traffic
    assert t["source"] == "sumo" and t["sumocfg"] is None and t["net"] is None
    assert t["network"]["junctions"] == 1 and t["network"]["traffic_lights"] is True
    # Relative paths resolve against the scenario's folder, to absolute paths.
    assert t["demand"]["vtypes"] == str(ROOT / "scenarios" / "cad-vtypes.add.xml")
    assert s.observers["classes"] == ["car", "van", "bus", "truck"]
    assert s.observers["arm_relations"] == ["opposite", "adjacent"]
    assert s.observers["aim"] == "junction" and s.observers["min_shared_area_m2"] == 900.0
    assert s.sampling["warm_up"] == 150.0 and s.sampling["max_time"] is None
    assert s.sampling["distinct_observers"] is True
    assert s.noise["noise_rate"] == 0.001 and s.detection["min_pixels"] == 40


def test_defaults_fill_absent_tables_and_ints_widen_to_floats(tmp_path):
    s = load_scenario(write(tmp_path, external("[observers]\nmax_distance = 30\n")))
    assert s.name == "s" and s.seed == 0 and s.pairs == 50
    assert s.camera == CameraConfig()
    assert s.observers["max_distance"] == 30.0 and isinstance(s.observers["max_distance"], float)
    assert s.sampling == {
        "warm_up": 60.0,
        "interval": 2.0,
        "pairs_per_snapshot": 1,
        "pairs_per_episode": 10,
        "max_time": None,
        "distinct_observers": False,
    }
    # The observer-geometry keys default to today's rule: no relation, area or aim constraint.
    assert s.observers["arm_relations"] == [] and s.observers["aim"] == "heading"
    assert s.observers["min_shared_area_m2"] == 0.0
    assert s.traffic["scene"]["buildings"] is True and s.traffic["network"] is None
    assert s.noise == {} and s.detection == {}


def test_sumo_home_expands_and_roof_mount_is_accepted(tmp_path):
    import sumo

    s = load_scenario(write(tmp_path, external('[camera]\nmount_height = "roof"\n')))
    expected = Path(sumo.SUMO_HOME, "tools", "game", "cross.sumocfg").resolve()
    assert s.traffic["sumocfg"] == str(expected)
    assert s.camera.mount_height == "roof"


def test_absolute_paths_are_accepted_and_a_net_without_junction_is_rejected(tmp_path):
    text = f"""
[traffic]
source = "sumo"
net = "{DATA / "straight.net.xml"}"
routes = ["{DATA / "straight.rou.xml"}"]
"""
    err = error_of(write(tmp_path, text))
    assert err.key == "traffic.net" and str(DATA / "straight.net.xml") in str(err)


# --------------------------------------------------------------------------- promised errors


@pytest.mark.parametrize(
    ("fixture", "key", "words"),
    [
        ("unknown-key.toml", "camera.widht", ["unknown key", "width"]),
        ("wrong-type.toml", "observers.max_distance", ["wrong type", "'far'", "a number > 0"]),
        ("missing-file.toml", "traffic.sumocfg", ["no-such-scenario.sumocfg", "does not exist"]),
        ("no-junction.toml", "traffic.net", ["no junction", "two different arms"]),
    ],
)
def test_fixture_files_give_the_promised_messages(fixture, key, words):
    path = DATA / fixture
    err = error_of(path)
    assert err.key == key
    assert err.path == path.resolve()
    text = str(err)
    assert text.startswith(f"{path.resolve()}: {key}: ")
    assert "expected" in text
    for word in words:
        assert word in text


@pytest.mark.parametrize(
    ("body", "key", "words"),
    [
        ('nmae = "x"\n' + external(), "nmae", ["unknown key", "name"]),
        ("pairs = 0\n" + external(), "pairs", ["is 0", ">= 1"]),
        ("seed = 1.5\n" + external(), "seed", ["wrong type", "an integer"]),
        ("camera = 3\n" + external(), "camera", ["a table"]),
        (external("[camera]\nwidth = true\n"), "camera.width", ["wrong type", "a boolean"]),
        (external("[camera]\nhfov_deg = 200\n"), "camera.hfov_deg", ["<= 170"]),
        (external('[camera]\nmount_height = "top"\n'), "camera.mount_height", ['"roof"']),
        (external("[observers]\nclasses = ['car', 3]\n"), "observers.classes[1]", ["wrong type"]),
        (external("[sampling]\ninterval = 0\n"), "sampling.interval", ["> 0"]),
        (
            external("[traffic.scene]\nbuilding_heights = [9.0, 3.0]\n"),
            "traffic.scene.building_heights",
            ["min <= max"],
        ),
        (
            external("[traffic.scene]\nbuilding_colors = ['red']\n"),
            "traffic.scene.building_colors",
            ["#rrggbb"],
        ),
        ("[camera]\nwidth = 640\n", "traffic", ["missing"]),
        ('[traffic]\nsource = "carla"\n', "traffic.source", ["unknown source 'carla'", "sumo"]),
        ('[traffic]\nsumocfg = "x"\n', "traffic.source", ["missing"]),
        ('[traffic]\nsource = "sumo"\n', "traffic.sumocfg", ["none given", "exactly one of"]),
        (
            external('net = "$SUMO_HOME/tools/game/cross/cross.net.xml"\n'),
            "traffic.sumocfg",
            ["several given (sumocfg, net)"],
        ),
        (
            '[traffic]\nsource = "sumo"\n[traffic.network]\njunctions = 1\n',
            "traffic.demand",
            ["missing", "generated network"],
        ),
        (
            '[traffic]\nsource = "sumo"\nnet = "$SUMO_HOME/tools/game/cross/cross.net.xml"\n',
            "traffic.routes",
            ["no routes"],
        ),
        (external("[noise]\nnoise_rat = 0.1\n"), "noise.noise_rat", ["unknown key", "noise_rate"]),
        (external('[noise]\nnoise_rate = "high"\n'), "noise.noise_rate", ["wrong type", "float"]),
        (
            external("[noise]\nnoise_rate = -1.0\n"),
            "noise.noise_rate",
            ["invalid value", "must be >= 0"],
        ),
        (
            external("[detection]\nmin_pixels = 2.5\n"),
            "detection.min_pixels",
            ["wrong type", "int"],
        ),
        ("this is = not toml", "", ["invalid TOML"]),
    ],
)
def test_malformed_files_name_file_key_and_expectation(tmp_path, body, key, words):
    path = write(tmp_path, body)
    err = error_of(path)
    assert err.key == key
    assert str(err).startswith(str(path.resolve()))
    for word in words:
        assert word in str(err)


def test_demand_type_ids_must_exist_in_the_vtypes_file(tmp_path):
    vtypes = ROOT / "scenarios" / "cad-vtypes.add.xml"
    body = f"""
[traffic]
source = "sumo"
[traffic.network]
junctions = 1
[traffic.demand]
vtypes = "{vtypes}"
vehicle_type = "lorries"
"""
    err = error_of(write(tmp_path, body))
    assert err.key == "traffic.demand.vehicle_type"
    assert "'lorries' is not defined" in str(err) and "vehicles" in str(err)


def test_files_named_inside_a_sumocfg_must_exist(tmp_path):
    cfg = tmp_path / "x.sumocfg"
    cfg.write_text('<configuration><input><net-file value="gone.net.xml"/></input></configuration>')
    err = error_of(write(tmp_path, '[traffic]\nsource = "sumo"\nsumocfg = "x.sumocfg"\n'))
    assert err.key == "traffic.sumocfg" and "gone.net.xml" in str(err)


def test_missing_scenario_file_is_a_scenario_error(tmp_path):
    err = error_of(tmp_path / "absent.toml")
    assert "does not exist" in str(err)


# --------------------------------------------------------------------------- extension points


@dataclass
class _LocalConfig:
    rate: float = 0.5
    count: int = 3
    enabled: bool = True
    name: str = "x"
    sizes: tuple[float, ...] = (1.0,)
    mode: str | None = None

    def __post_init__(self):
        if self.rate > 1:
            raise ValueError(f"rate must be <= 1, got {self.rate}")


@pytest.mark.parametrize(
    ("table", "key", "words"),
    [
        ({"rat": 0.1}, "t.rat", ["unknown key", "rate"]),
        ({"rate": "a"}, "t.rate", ["wrong type", "float"]),
        ({"count": 1.5}, "t.count", ["wrong type", "int"]),
        ({"count": True}, "t.count", ["wrong type"]),
        ({"enabled": 1}, "t.enabled", ["wrong type", "bool"]),
        ({"sizes": [1.0, "b"]}, "t.sizes", ["wrong type", "tuple[float, ...]"]),
        ({"rate": 2.0}, "t.rate", ["invalid value", "rate must be <= 1"]),
    ],
)
def test_generic_dataclass_validation_rejects(table, key, words):
    ctx = ScenarioContext(Path("/x/s.toml"))
    with pytest.raises(ScenarioError) as info:
        validate_dataclass_table(table, _LocalConfig, ctx, "t")
    assert info.value.key == key
    for word in words:
        assert word in str(info.value)


def test_generic_dataclass_validation_accepts_matching_values():
    ctx = ScenarioContext(Path("/x/s.toml"))
    good = {"rate": 1, "count": 2, "enabled": False, "name": "n", "sizes": [1, 2.5], "mode": "m"}
    validate_dataclass_table(good, _LocalConfig, ctx, "t")


def test_registered_source_schemas_validate_the_traffic_table(tmp_path):
    register_source_schema(
        "test-dict-source",
        {"robots": Field(int, 4, "robot count", ge=1), "area": Table({"size": Field(float, 10.0)})},
    )
    register_source_schema("test-dataclass-source", _LocalConfig)
    s = load_scenario(write(tmp_path, '[traffic]\nsource = "test-dict-source"\nrobots = 6\n'))
    assert s.traffic == {"source": "test-dict-source", "robots": 6, "area": {"size": 10.0}}
    err = error_of(write(tmp_path, '[traffic]\nsource = "test-dict-source"\nrobots = 0\n'))
    assert err.key == "traffic.robots"
    s = load_scenario(write(tmp_path, '[traffic]\nsource = "test-dataclass-source"\nrate = 1\n'))
    assert s.traffic["rate"] == 1 and s.traffic["count"] == 3
    err = error_of(write(tmp_path, '[traffic]\nsource = "test-dataclass-source"\ncount = "x"\n'))
    assert err.key == "traffic.count" and "int" in str(err)


def test_scenario_is_picklable_for_worker_processes():
    import pickle

    s = load_scenario(DEFAULT)
    assert pickle.loads(pickle.dumps(s)) == s


def test_environment_variables_expand_in_paths(tmp_path, monkeypatch):
    (tmp_path / "sub").mkdir()
    (tmp_path / "sub" / "t.xml").write_text("<additional/>")
    monkeypatch.setenv("CADSIM_TEST_DIR", str(tmp_path / "sub"))
    ctx = ScenarioContext(tmp_path / "s.toml")
    assert ctx.resolve("$CADSIM_TEST_DIR/t.xml") == (tmp_path / "sub" / "t.xml").resolve()
    assert ctx.resolve("sub/t.xml") == (tmp_path / "sub" / "t.xml").resolve()
    assert os.path.isabs(ctx.resolve("x"))


def test_sumo_home_paths_fall_back_to_the_installed_wheel(monkeypatch, tmp_path):
    # libsumo sets SUMO_HOME to its data-only package; a user's SUMO_HOME may lack tools/ too.
    monkeypatch.setenv("SUMO_HOME", str(tmp_path))
    s = load_scenario(ROOT / "scenarios" / "sumo-game-cross.toml")
    cfg = Path(s.traffic["sumocfg"])
    assert cfg.is_file() and cfg.name == "cross.sumocfg" and tmp_path not in cfg.parents


def test_a_misspelt_key_gets_a_suggestion_and_no_class_name_leaks(tmp_path):
    text = (ROOT / "scenarios" / "cad-intersection.toml").read_text()
    bad = tmp_path / "bad.toml"
    for right, wrong, want in (
        ("step_length = 0.1", "step_lenght = 0.1", "did you mean 'step_length'?"),
        ("noise_rate = 0.001", "noise_rat = 0.001", "did you mean 'noise_rate'?"),
    ):
        assert right in text
        bad.write_text(text.replace(right, wrong, 1))
        (tmp_path / "cad-vtypes.add.xml").write_text(
            (ROOT / "scenarios" / "cad-vtypes.add.xml").read_text()
        )
        with pytest.raises(ScenarioError, match=want.replace("?", r"\?")):
            load_scenario(bad)
    bad.write_text(text.replace("noise_rate = 0.001", "noise_rate = -1.0", 1))
    with pytest.raises(ScenarioError) as exc:
        load_scenario(bad)
    assert "Config" not in str(exc.value) and "noise_rate must be >= 0" in str(exc.value)
