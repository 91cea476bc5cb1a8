"""SUMO front-bumper/compass poses -> world centres/yaws: hand-built cases, round trips, and a live
libsumo vehicle on a straight, oblique edge."""

from __future__ import annotations

import multiprocessing
import subprocess
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from cadsim.sources.sumo.frames import (
    center_to_front,
    compass_to_yaw,
    front_to_center,
    sumo_color,
    yaw_to_compass,
)


@pytest.mark.parametrize(
    ("angle", "yaw"),
    [
        (0.0, np.pi / 2),
        (90.0, 0.0),
        (180.0, -np.pi / 2),
        (270.0, np.pi),
        (45.0, np.pi / 4),
        (-90.0, np.pi),
    ],
)
def test_compass_angles_become_ccw_yaws_from_east(angle, yaw):
    assert compass_to_yaw(angle) == pytest.approx(yaw)


def test_hand_built_vehicles():
    # East-bound 4 m car, front bumper at (10, 0): centre 2 m behind, half its height up.
    # North-bound 12 m bus at (0, 50, 1) on a 1 m high road: centre 6 m south, 1 + 1.6 up.
    # South-west-bound (225 deg) 2*sqrt(2) m vehicle at (0, 0): centre at (1, 1).
    front = [(10.0, 0.0, 0.0), (0.0, 50.0, 1.0), (0.0, 0.0, 0.0)]
    center, yaw = front_to_center(
        front, [90.0, 0.0, 225.0], [4.0, 12.0, 2 * np.sqrt(2)], [1.5, 3.2, 1.0]
    )
    np.testing.assert_allclose(
        center, [(8.0, 0.0, 0.75), (0.0, 44.0, 2.6), (1.0, 1.0, 0.5)], atol=1e-12
    )
    np.testing.assert_allclose(yaw, [0.0, np.pi / 2, -3 * np.pi / 4], atol=1e-12)


@given(
    st.floats(-1e4, 1e4),
    st.floats(-1e4, 1e4),
    st.floats(-10, 10),
    st.floats(0, 360, exclude_max=True),
    st.floats(0.1, 30),
    st.floats(0.1, 5),
)
def test_front_center_round_trip(x, y, z, angle, length, height):
    center, yaw = front_to_center([(x, y, z)], [angle], [length], [height])
    assert -np.pi < yaw[0] <= np.pi
    # The front is length/2 ahead of the centre along the heading.
    ahead = np.array([np.cos(yaw[0]), np.sin(yaw[0])]) * length / 2
    np.testing.assert_allclose(center[0, :2] + ahead, [x, y], atol=1e-6)
    front, back_angle = center_to_front(center, yaw, [length], [height])
    np.testing.assert_allclose(front[0], [x, y, z], atol=1e-6)
    diff = (back_angle[0] - angle + 180.0) % 360.0 - 180.0
    assert abs(diff) < 1e-6
    assert 0.0 <= yaw_to_compass(yaw[0]) < 360.0


def test_sumo_colours_are_rgb_in_unit_range():
    assert sumo_color((255, 0, 51, 128)) == pytest.approx((1.0, 0.0, 0.2))


# --------------------------------------------------------------------------- live libsumo

NODES = """<nodes>
    <node id="a" x="0" y="0"/>
    <node id="b" x="-60" y="80"/>
    <node id="c" x="-120" y="160"/>
</nodes>"""
EDGES = """<edges>
    <edge id="ab" from="a" to="b" numLanes="1" speed="10"/>
    <edge id="bc" from="b" to="c" numLanes="1" speed="10"/>
</edges>"""
ROUTES = """<routes>
    <vType id="long" length="7.5" width="2.2" height="2.9"/>
    <vehicle id="v" type="long" depart="0" departSpeed="5"><route edges="ab bc"/></vehicle>
</routes>"""


def _live_vehicle(folder: str) -> dict:
    """Run in a fresh process: step until the vehicle is well inside edge ab, read its pose."""
    import libsumo

    from cadsim.sources.sumo.frames import front_to_center

    libsumo.start(
        [
            "sumo",
            "-n",
            f"{folder}/line.net.xml",
            "-r",
            f"{folder}/line.rou.xml",
            "--no-step-log",
            "true",
        ]
    )
    try:
        for _ in range(100):
            libsumo.simulationStep()
            if libsumo.vehicle.getIDList() and libsumo.vehicle.getLanePosition("v") > 30:
                break
        v = libsumo.vehicle
        front = v.getPosition3D("v")
        center, yaw = front_to_center(
            [front], [v.getAngle("v")], [v.getLength("v")], [v.getHeight("v")]
        )
        return {
            "front": front,
            "center": center[0].tolist(),
            "yaw": float(yaw[0]),
            "lane": v.getLaneID("v"),
            "lane_pos": v.getLanePosition("v"),
            "lane_shape": libsumo.lane.getShape(v.getLaneID("v")),
            "length": v.getLength("v"),
        }
    finally:
        libsumo.close()


def test_live_libsumo_vehicle_centre_lies_half_a_length_back_on_its_lane(tmp_path: Path):
    from cadsim.sources.sumo.install import sumo_home

    (tmp_path / "line.nod.xml").write_text(NODES)
    (tmp_path / "line.edg.xml").write_text(EDGES)
    (tmp_path / "line.rou.xml").write_text(ROUTES)
    netconvert = sumo_home() / "bin" / "netconvert"
    subprocess.run(
        [
            str(netconvert),
            "-n",
            "line.nod.xml",
            "-e",
            "line.edg.xml",
            "--offset.disable-normalization",
            "true",
            "-o",
            "line.net.xml",
        ],
        cwd=tmp_path,
        check=True,
        capture_output=True,
    )
    with ProcessPoolExecutor(1, mp_context=multiprocessing.get_context("spawn")) as pool:
        r = pool.submit(_live_vehicle, str(tmp_path)).result(timeout=120)
    assert r["lane"] == "ab_0" and r["length"] == 7.5
    start, end = np.array(r["lane_shape"][0]), np.array(r["lane_shape"][-1])
    direction = (end - start) / np.linalg.norm(end - start)
    # Heading: the lane direction (north-west), yaw CCW from east.
    assert r["yaw"] == pytest.approx(np.arctan2(direction[1], direction[0]), abs=1e-6)
    # SUMO's position is the front bumper at lane_pos; the centre is length/2 further back.
    np.testing.assert_allclose(r["front"][:2], start + direction * r["lane_pos"], atol=1e-3)
    np.testing.assert_allclose(
        r["center"][:2], start + direction * (r["lane_pos"] - 3.75), atol=1e-3
    )
    assert r["center"][2] == pytest.approx(1.45)
