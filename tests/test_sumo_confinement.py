"""Issue 15 #1: a scenario cannot make netgenerate or SUMO write outside the run folder. Each
reproduction from the issue is tried (netgenerate ``extra_args``, a ``.sumocfg`` declaring
outputs, additional and route files declaring outputs with absolute and ``../`` paths); the file
it aims at must not exist afterwards."""

from __future__ import annotations

import gzip
import itertools
import os
from pathlib import Path

import pytest
import sumo
from test_sumo_source import in_fresh_processes

from cadsim.scenario import ScenarioError, load_scenario
from cadsim.sources.sumo.build import build_network
from cadsim.sources.sumo.confinement import ConfinementError, confined_files
from cadsim.sources.sumo.options import (
    OptionError,
    check_netgenerate_args,
    netgenerate_option_allowed,
    sumo_option_allowed,
    tool_options,
)

GAME = Path(sumo.SUMO_HOME) / "tools" / "game"
ROOT = Path(__file__).resolve().parents[1]
VTYPES = ROOT / "scenarios" / "cad-vtypes.add.xml"


def _network_scenario(tmp_path: Path, extra_args: list[str]) -> Path:
    args = ", ".join(f'"{a}"' for a in extra_args)
    path = tmp_path / "scn" / "net.toml"
    path.parent.mkdir(exist_ok=True)
    path.write_text(
        f'[traffic]\nsource = "sumo"\n[traffic.network]\nextra_args = [{args}]\n'
        f'[traffic.demand]\nvtypes = "{VTYPES}"\n'
    )
    return path


def test_netgenerate_extra_args_that_write_files_are_refused(tmp_path):
    log, prefix = tmp_path / "outside" / "ng.log", tmp_path / "outside" / "plain"
    path = _network_scenario(tmp_path, ["--tls.cycle.time", "60", "--log", str(log)])
    with pytest.raises(ScenarioError) as info:
        load_scenario(path)
    assert info.value.key == "traffic.network.extra_args[2]" and "--log" in str(info.value)
    for bad, index in (
        (["--plain-output-prefix", str(prefix)], 0),
        ([f"--output-file={prefix}"], 0),
        (["-l", str(log)], 0),  # a short synonym of --log
        (["--sidewalks.guess", "true", str(log)], 2),  # a stray value
        (["--configuration-file", str(log)], 0),
        (["--sidewalks.guess=--log=x.log"], 0),  # a boolean must be a boolean
        (["--tls.cycle.time", "--log=x.log"], 1),  # a number expected: not another option
        (["--tls.cycle.time=sixty"], 0),
        (["--default.lanenumber", "1", "--grid.number", "2x"], 3),
    ):
        with pytest.raises(OptionError) as err:
            check_netgenerate_args(bad)
        assert err.value.index == index
    # The builder refuses them too, should a scenario skip the check.
    params = load_scenario(_network_scenario(tmp_path, [])).traffic["network"]
    with pytest.raises(OptionError):
        build_network({**params, "extra_args": ["--log", str(log)]}, tmp_path / "work")
    # Allowed options shape the network as asked.
    net = build_network({**params, "extra_args": ["--tls.cycle.time=60"]}, tmp_path / "work")
    assert net.is_file() and tmp_path / "work" in net.parents
    assert not (tmp_path / "outside").exists() and not list(tmp_path.glob("plain*"))


def test_allowlists_hold_no_file_option_of_the_installed_sumo():
    for tool, allowed in (("netgenerate", netgenerate_option_allowed), ("sumo", sumo_option_allowed)):  # fmt: skip
        passed = {o for o in tool_options(tool).values() if allowed(o)}
        assert passed, tool
        for option in passed:
            assert not option.type.startswith("FILE"), option
            assert not any(w in option.name for w in ("output", "file", "log", "prefix")), option
        names = {o.name for o in passed}
        assert not names & {"log", "remote-port", "configuration-file", "save-configuration"}


def _escaping_scenario(tmp_path: Path) -> tuple[Path, list[Path]]:
    """A SUMO scenario whose config, additional and route files aim outputs outside."""
    folder = tmp_path / "scn"
    folder.mkdir()
    outside = tmp_path / "outside"
    targets = [outside / f"escape{k}.xml" for k in range(7)]
    # The network itself (gzip-compressed) declares an output: an actuated light's detector file.
    net = (GAME / "cross" / "cross.net.xml").read_text()
    net = net.replace('<tlLogic id="0" type="static"', '<tlLogic id="0" type="actuated"').replace(
        '<phase duration="33"', '<phase duration="33" minDur="5" maxDur="50"'
    )
    net = net.replace(
        "    </tlLogic>",
        f'<param key="file" value="{targets[6]}"/><param key="freq" value="5"/></tlLogic>',
        1,
    )
    assert str(targets[6]) in net
    (folder / "cross.net.xml.gz").write_bytes(gzip.compress(net.encode()))
    (folder / "escape.add.xml").write_text(
        "<additional>\n"
        f'  <edgeData id="a" file="{targets[0]}"/>\n'
        '  <laneData id="b" file="../outside/escape1.xml"/>\n'
        f'  <timedEvent type="SaveTLSStates" source="0" dest="{targets[2]}"/>\n'
        "</additional>\n"
    )
    routes = (GAME / "cross" / "cross.rou.xml").read_text()
    vtype = (
        '<vType id="ssm-car" vClass="passenger">'
        '<param key="has.ssm.device" value="true"/>'
        f'<param key="device.ssm.file" value="{targets[3]}"/></vType>'
    )
    flow = '<flow id="ssm" type="ssm-car" route="1_right" begin="0" end="100" period="5"/>'
    head, _, tail = routes.partition(">")
    tail = tail.replace("</routes>", flow + "</routes>")
    (folder / "cross.rou.xml").write_text(head + ">" + vtype + tail)
    (folder / "escape.sumocfg").write_text(
        "<configuration>\n"
        '  <input><net-file value="cross.net.xml.gz"/>\n'
        '    <route-files value="cross.rou.xml"/>\n'
        f'    <additional-files value="{GAME / "cross" / "cross.tls.add.xml"},escape.add.xml"/>'
        "</input>\n"
        f'  <output><tripinfo-output value="{targets[4]}"/></output>\n'
        f'  <routing><device.rerouting.output value="{targets[5]}"/>\n'
        '    <device.rerouting.probability value="0.5"/></routing>\n'
        '  <report><log value="../outside/sumo.log"/></report>\n'
        '  <time><begin value="0"/><end value="120"/></time>\n'
        "</configuration>\n"
    )
    (folder / "escape.toml").write_text(
        '[traffic]\nsource = "sumo"\nsumocfg = "escape.sumocfg"\n'
        "[sampling]\nwarm_up = 10.0\ninterval = 5.0\n"
    )
    return folder / "escape.toml", [*targets, outside / "sumo.log"]


def _run_source(scenario: str, workdir: str) -> dict:
    """Fresh process: a few snapshots; what the run folder's outputs hold before closing."""
    from cadsim.scenario import load_scenario
    from cadsim.sources import make_source

    source = make_source(load_scenario(scenario), 3, Path(workdir))
    with source:
        times = [s.time for s in itertools.islice(source.snapshots(), 4)]
        outputs = sorted(
            str(p.relative_to(source.run_dir)) for p in source.run_dir.rglob("*") if p.is_file()
        )
        routes = (source.run_dir / "routes" / "0" / "cross.rou.xml").read_text()
    return {"times": times, "outputs": outputs, "args": source.run.args, "routes": routes}


def test_outputs_declared_by_the_scenario_stay_in_the_run_folder(tmp_path):
    scenario, targets = _escaping_scenario(tmp_path)
    cwd_before = sorted(os.listdir(Path.cwd()))
    (result,) = in_fresh_processes([(_run_source, str(scenario), str(tmp_path / "work"))])
    assert result["times"] == pytest.approx([10.0, 15.0, 20.0, 25.0])
    for target in targets:
        assert not target.exists(), target
    assert not (tmp_path / "outside").exists()
    assert sorted(os.listdir(tmp_path / "scn")) == [
        "cross.net.xml.gz", "cross.rou.xml", "escape.add.xml", "escape.sumocfg", "escape.toml",
    ]  # fmt: skip
    assert sorted(os.listdir(Path.cwd())) == cwd_before
    # The rewritten declarations wrote where they were sent: the run folder's outputs.
    written = [p for p in result["outputs"] if p.startswith("outputs/")]
    assert any("escape0" in p for p in written), written
    assert any("net0" in p and "escape6" in p for p in written), written  # the net's detector
    # The device parameter in the route file was rewritten too (SSM writes when vehicles leave).
    assert f'value="{tmp_path / "work"}' in result["routes"] and "escape3" in result["routes"]
    args = result["args"]
    assert "--tripinfo-output" not in args and "--log" not in args and "-c" not in args
    assert "--device.rerouting.output" not in args
    assert "--device.rerouting.probability=0.5" in args


@pytest.mark.parametrize(
    "option, words",
    [
        ('<remote-port value="8813"/>', "remote-port"),
        ('<save-configuration value="/tmp/cadsim-escape.cfg"/>', "save-configuration"),
        ('<device.ssm.file value="/tmp/cadsim-escape.xml"/>', "device.ssm.file"),
        ('<no-such-option value="1"/>', "not a SUMO option"),
    ],
)
def test_sumocfg_options_that_cannot_be_confined_are_refused(tmp_path, option, words):
    (tmp_path / "x.sumocfg").write_text(
        f'<configuration><net-file value="{GAME / "cross" / "cross.net.xml"}"/>{option}'
        "</configuration>"
    )
    (tmp_path / "x.toml").write_text('[traffic]\nsource = "sumo"\nsumocfg = "x.sumocfg"\n')
    with pytest.raises(ScenarioError) as info:
        load_scenario(tmp_path / "x.toml")
    assert info.value.key == "traffic.sumocfg" and words in str(info.value)


@pytest.mark.parametrize(
    "option, words",
    [  # a value that SUMO's parser would take as the next option (issue: option injection)
        ('<collision.check-junctions value="--tripinfo-output=/tmp/cadsim-x.xml"/>', "BOOL"),
        ('<collision.check-junctions value="maybe"/>', "BOOL"),
        ('<collision.action value="--tripinfo-output=/tmp/cadsim-x.xml"/>', "start with '-'"),
        ('<time-to-teleport value="-tripinfo-output"/>', "TIME"),
        ('<default.speeddev value="1e3x"/>', "FLOAT"),
        ('<railsignal.default-classes value="rail,--log=/tmp/x"/>', "STR[]"),
    ],
)
def test_sumocfg_values_that_are_not_data_of_their_type_are_refused(tmp_path, option, words):
    (tmp_path / "x.sumocfg").write_text(
        f'<configuration><net-file value="{GAME / "cross" / "cross.net.xml"}"/>'
        f"<processing>{option}</processing></configuration>"
    )
    (tmp_path / "x.toml").write_text('[traffic]\nsource = "sumo"\nsumocfg = "x.sumocfg"\n')
    with pytest.raises(ScenarioError) as info:
        load_scenario(tmp_path / "x.toml")
    assert info.value.key == "traffic.sumocfg" and words in str(info.value)
    assert not Path("/tmp/cadsim-x.xml").exists()


def test_sumocfg_values_reach_sumo_as_one_argument_with_their_name():
    from cadsim.sources.sumo.options import check_value, tool_options

    options = tool_options("sumo")
    assert check_value(options["time-to-teleport"], "-1", "t") == "-1"  # a negative number is data
    assert check_value(options["begin"], "15:0:0", "b") == "15:0:0"
    assert check_value(options["collision.check-junctions"], "true", "c") == "true"


def test_include_in_an_additional_file_is_refused(tmp_path):
    (tmp_path / "inc.add.xml").write_text(
        '<additional><include href="/etc/other.xml"/></additional>'
    )
    scenario = tmp_path / "s.toml"
    scenario.write_text(
        '[traffic]\nsource = "sumo"\nsumocfg = "$SUMO_HOME/tools/game/cross.sumocfg"\n'
        'additional = ["inc.add.xml"]\n'
    )
    with pytest.raises(ScenarioError) as info:
        load_scenario(scenario)
    assert info.value.key == "traffic.additional[0]" and "<include" in str(info.value)
    with pytest.raises(ConfinementError):
        confined_files([tmp_path / "inc.add.xml"], tmp_path / "run", "additional")


def test_inputs_of_a_rewritten_file_are_read_from_where_they_were(tmp_path):
    (tmp_path / "defs.xml").write_text("<rerouter/>")
    (tmp_path / "r.add.xml").write_text(
        '<additional><rerouter id="r" edges="e" file="defs.xml"/>'
        '<edgeData id="d" file="out.xml" edgesFile="edges.txt"/></additional>'
    )
    (copy,) = confined_files([tmp_path / "r.add.xml"], tmp_path / "run", "additional")
    text = copy.read_text()
    assert f'file="{tmp_path / "defs.xml"}"' in text
    assert f'edgesFile="{tmp_path / "edges.txt"}"' in text
    assert f'file="{tmp_path / "run" / "outputs" / "additional0" / "0-out.xml"}"' in text
