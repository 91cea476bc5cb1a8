"""Network reading, sumocfg handling and static-scene geometry, without running a simulation."""

from __future__ import annotations

import os
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest
import sumo

from cadsim.sources.sumo.command import sumo_run
from cadsim.sources.sumo.config import read_sumocfg
from cadsim.sources.sumo.network import RoadNetwork
from cadsim.sources.sumo.static_scene import (
    SIGNAL_COLORS,
    SignalHead,
    non_overlapping,
    rectangles_clear_of_points,
    representative_signal,
)
from cadsim.world import WorldObject

GAME = Path(sumo.SUMO_HOME) / "tools" / "game"
DATA = Path(__file__).resolve().parent / "data" / "scenarios"
ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def cross() -> RoadNetwork:
    return RoadNetwork(GAME / "cross" / "cross.net.xml")


def test_usable_junctions_need_two_arms_and_three_neighbours(cross):
    # game/cross: one signalised crossing; its roads are split by plain nodes, which do not count.
    assert list(cross.junction_arms) == ["0"]
    assert cross.junction_arms["0"] == ["1si", "2si", "3si", "4si"]
    assert RoadNetwork(DATA / "straight.net.xml").junction_arms == {}


def test_approach_walks_the_route_across_split_edges(cross):
    route = ("1fi", "1si", "3o", "3fo")
    first, second = cross.edge_length["1fi"], cross.edge_length["1si"]
    lane = "1fi_0"
    a = cross.approach(route, 0, lane, 10.0, max_distance=1e4)
    assert (a.junction, a.edge, a.arm) == ("0", "1si", cross.edge_from["1si"])
    assert a.distance == pytest.approx(cross.lane_length[lane] - 10.0 + second)
    assert cross.lane_length[lane] == pytest.approx(first)
    assert cross.approach(route, 0, lane, 10.0, max_distance=a.distance - 1.0) is None
    assert cross.approach(
        route, 1, "1si_0", second - 3.0, max_distance=5.0
    ).distance == pytest.approx(3.0)
    assert cross.approach(route, 1, ":0_0_0", 1.0, max_distance=50.0) is None  # inside the junction
    assert cross.approach(route, 2, "3o_0", 1.0, max_distance=1e4) is None  # leaving: none ahead
    assert cross.approach(route, 0, lane, 10.0, 1e4, junctions={"elsewhere"}) is None


def test_sumocfg_inputs_resolve_and_outputs_are_found():
    cfg = read_sumocfg(GAME / "square.sumocfg")
    assert cfg.net == (GAME / "square" / "square.net.xml").resolve()
    assert [p.name for p in cfg.additional] == [
        "square.tll.xml",
        "square.poi.xml",
        "square.rou.xml",
        "input_additional.add.xml",
    ]
    assert cfg.outputs == {"tripinfo-output": "tripinfos.xml"}  # not write-undeparted (a flag)


def test_sumo_run_passes_allowlisted_options_and_confines_additional_files(tmp_path):
    traffic = {
        "sumocfg": str(GAME / "square.sumocfg"),
        "net": None,
        "network": None,
        "demand": None,
        "routes": [],
        "additional": [str(DATA / "straight.rou.xml")],
        "step_length": None,
    }
    run = sumo_run(traffic, 5, tmp_path / "cache", tmp_path / "run", end=300.0)
    args = run.args
    assert "-c" not in args  # SUMO never reads the sumocfg itself
    assert args[0] == "-n" and tmp_path / "run" in Path(args[1]).parents  # through the run folder
    assert Path(args[1]).resolve() == (GAME / "square" / "square.net.xml").resolve()
    assert not any(a.startswith("--tripinfo") or a == "--gui-settings-file" for a in args)
    files = [Path(p) for p in args[args.index("--additional-files") + 1].split(",")]
    assert [p.name for p in files][-1] == "straight.rou.xml" and len(files) == 5
    for path in files:
        assert tmp_path / "run" in path.parents
    assert files[0].is_symlink()
    assert files[0].resolve() == (GAME / "square" / "square.tll.xml").resolve()
    # input_additional.add.xml declares outputs: a rewritten copy writes them into the run folder.
    confined = files[3]
    assert confined.name == "input_additional.add.xml" and not confined.is_symlink()
    root = ET.parse(confined).getroot()
    for element, attribute in (("edgeData", "file"), ("timedEvent", "dest")):
        for e in root.iter(element):
            assert tmp_path / "run" / "outputs" in Path(e.get(attribute)).parents
    assert "--step-length=.1" in args  # the sumocfg's own step, value and name one argument
    assert "--begin=0" in args
    assert args[args.index("--seed") + 1] == "5" and args[args.index("--end") + 1] == "300"
    assert args.count("--end") == 1 and args.count("--seed") == 1
    assert run.net == (GAME / "square" / "square.net.xml").resolve()


def test_signal_heads_show_the_commonest_signal_of_their_links():
    assert representative_signal(["r", "G", "G", "r", "g"]) == "G"  # tie: greener
    assert representative_signal(["r", "r", "G"]) == "r"
    assert representative_signal(["G", "r"]) == "G"  # tie: greener
    assert representative_signal([]) == "o"
    obj = WorldObject(
        "tls:t:e", "traffic_light", "traffic_light", (0, 0, 1), 0.0, (0.4, 0.4, 3.5), (0, 0, 0)
    )
    head = SignalHead(obj, "t", (1, 2))
    shown = head.at_state("GyyG")
    assert shown.state == "y" and shown.color == SIGNAL_COLORS["y"] and shown.id == obj.id


def test_rectangle_clearance_and_overlap():
    centres = np.array([[0.0, 0.0], [10.0, 0.0], [13.0, 0.0], [30.0, 0.0]])
    yaws = np.array([0.0, 0.0, np.pi / 2, 0.0])
    # A disc at (-6, 0) of radius 1.5 reaches into rectangle 0 (x in [-5, 5]); one at (22, 0) of
    # radius 1 stays clear of rectangle 3 (x in [25, 35]) and of the vertical rectangle 2.
    points, radius = np.array([[-6.0, 0.0], [22.0, 0.0]]), np.array([1.5, 1.0])
    clear = rectangles_clear_of_points(centres, yaws, 5.0, 2.0, points, radius)
    assert clear.tolist() == [False, True, True, True]
    # Rectangles 1 and 2 overlap (rotated), 0 and 1 touch only at x = 5 (not overlapping).
    assert non_overlapping(centres, yaws, 5.0, 2.0).tolist() == [0, 1, 3]


def test_no_file_is_written_next_to_the_sumocfg(tmp_path):
    before = sorted(os.listdir(GAME))
    read_sumocfg(GAME / "cross.sumocfg")
    assert sorted(os.listdir(GAME)) == before
