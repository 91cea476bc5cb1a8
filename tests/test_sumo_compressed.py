"""SUMO inputs compressed with gzip are read as SUMO reads them (networks, routes, additional
files), a gzip bomb is a clear error, and SUMO's clock-format begin times are understood — so
published scenarios such as SUMO's own Braunschweig demo (``tools/game/fokr_bs_demo.sumocfg``)
generate unedited."""

from __future__ import annotations

import gzip
import json
import shutil
from pathlib import Path

import pytest
import sumo

from cadsim.cli import main
from cadsim.scenario import ScenarioError, load_scenario
from cadsim.sources.sumo import xml_files
from cadsim.sources.sumo.options import OptionError, sumo_time
from cadsim.sources.sumo.xml_files import XmlSizeError, check_size, open_xml, parse_xml

GAME = Path(sumo.SUMO_HOME) / "tools" / "game"


def _gzip(path: Path) -> Path:
    out = path.with_name(path.name + ".gz")
    out.write_bytes(gzip.compress(path.read_bytes()))
    path.unlink()
    return out


def _compressed_cross(tmp_path: Path) -> Path:
    """SUMO's game/cross scenario with its network and routes gzip-compressed."""
    folder = tmp_path / "cross"
    shutil.copytree(GAME / "cross", folder)
    shutil.copy(GAME / "input_additional.add.xml", tmp_path)
    text = (GAME / "cross.sumocfg").read_text()
    for name in ("cross.net.xml", "cross.rou.xml"):
        if (folder / name).is_file():
            _gzip(folder / name)
            text = text.replace(name, name + ".gz")
    (tmp_path / "cross.sumocfg").write_text(text)
    assert ".xml.gz" in text
    scenario = tmp_path / "cross.toml"
    scenario.write_text(
        f'[traffic]\nsource = "sumo"\nsumocfg = "{tmp_path / "cross.sumocfg"}"\n'
        "[sampling]\nwarm_up = 30.0\ninterval = 2.0\nmax_time = 300.0\n"
    )
    return scenario


def test_plain_and_gzip_files_read_the_same(tmp_path):
    plain = tmp_path / "a.xml"
    plain.write_text('<routes><vType id="car"/></routes>')
    packed = tmp_path / "b.xml"  # gzip recognised by its bytes, whatever the name
    packed.write_bytes(gzip.compress(plain.read_bytes()))
    with open_xml(plain) as f, open_xml(packed) as g:
        assert f.read() == g.read()
    assert parse_xml(packed).getroot()[0].get("id") == "car"


def test_a_gzip_bomb_is_refused_by_its_decompressed_size(tmp_path, monkeypatch):
    bomb = tmp_path / "bomb.rou.xml.gz"
    with gzip.open(bomb, "wb") as f:
        f.write(b"<routes>")
        for _ in range(64):
            f.write(b" " * 2**16)  # 4 MiB of spaces: a few KiB compressed
        f.write(b"</routes>")
    assert bomb.stat().st_size < 2**16
    with pytest.raises(XmlSizeError, match="more than 1 MiB"):
        parse_xml(bomb, limit=2**20)
    with pytest.raises(XmlSizeError):
        check_size(bomb, limit=2**20)
    check_size(bomb, limit=2**23)  # under the limit: fine
    # In a scenario: one line naming the file and the limit, not an out-of-memory.
    monkeypatch.setattr(xml_files, "MAX_XML_BYTES", 2**20)
    scenario = tmp_path / "bomb.toml"
    scenario.write_text(
        f'[traffic]\nsource = "sumo"\nnet = "{GAME / "cross" / "cross.net.xml"}"\n'
        f'routes = ["{bomb}"]\n'
    )
    with pytest.raises(ScenarioError) as caught:
        load_scenario(scenario)
    message = str(caught.value)
    assert "bomb.rou.xml.gz" in message and "MiB" in message and "traffic" in message


def test_a_truncated_gzip_file_is_named(tmp_path):
    broken = tmp_path / "cut.rou.xml.gz"
    broken.write_bytes(gzip.compress(b"<routes>" + b" " * 5000 + b"</routes>")[:40])
    scenario = tmp_path / "cut.toml"
    scenario.write_text(
        f'[traffic]\nsource = "sumo"\nnet = "{GAME / "cross" / "cross.net.xml"}"\n'
        f'routes = ["{broken}"]\n'
    )
    with pytest.raises(ScenarioError, match="cut.rou.xml.gz"):
        load_scenario(scenario)


@pytest.mark.parametrize(
    "text, seconds",
    [("0", 0.0), ("54000", 54000.0), ("0.05", 0.05), ("15:0:0", 54000.0), ("1:2:3:4", 93784.0)],
)
def test_sumo_times_in_seconds_and_clock_format(text, seconds):
    assert sumo_time(text) == pytest.approx(seconds)


@pytest.mark.parametrize("text", ["", "15:00", "noon", "1:2:3:4:5", "inf"])
def test_malformed_sumo_times_are_refused_by_name(text):
    with pytest.raises(OptionError, match="begin"):
        sumo_time(text)


@pytest.mark.slow
def test_a_scenario_with_compressed_network_and_routes_generates(tmp_path):
    scenario = _compressed_cross(tmp_path)
    out = tmp_path / "data"
    assert main(["generate", str(scenario), "--pairs", "1", "--out", str(out)]) == 0
    manifest = json.loads((out / "manifest.json").read_text())
    assert len(manifest["records"]) == 1
    for name in ("cross.net.xml", "cross.rou.xml"):  # nothing decompressed beside the inputs
        assert not (tmp_path / "cross" / name).exists()


@pytest.mark.slow
def test_sumo_braunschweig_demo_generates_unedited(tmp_path):
    # gzip-compressed network and trips, begin "15:0:0", 0.05 s steps
    cfg = GAME / "fokr_bs_demo.sumocfg"
    assert "15:0:0" in cfg.read_text() and ".xml.gz" in cfg.read_text()
    scenario = tmp_path / "fokr.toml"
    scenario.write_text(
        f'[traffic]\nsource = "sumo"\nsumocfg = "{cfg}"\n'
        "[sampling]\nwarm_up = 30.0\ninterval = 2.0\nmax_time = 600.0\n"
    )
    out = tmp_path / "data"
    assert main(["generate", str(scenario), "--pairs", "1", "--out", str(out)]) == 0
    record = json.loads(next(out.glob("pairs/*/record.json")).read_text())
    assert record["counts"]["covisible"] >= 1
    assert record["meta"]["pair"]["time"] >= 54000.0 + 30.0  # after the clock-format begin
