"""``v2x_reg`` (V2X-Reg++'s box association) and its box selection: a planted scene's true pairs
are recovered from headings and from centres alone, the selection ranks as theirs does, it is
registered with the equal tuning budget, and box-only records hand it their headings."""

from __future__ import annotations

import numpy as np
import pytest

from cadsim.dataset import Dataset
from cadsim.importers.dair_v2x import import_dair_v2x
from eval.bench.dair_import import write_dair_layout
from matchers import Problem, get
from matchers.blocks.box_selection import top_k_boxes
from matchers.core.registry import available
from matchers.core.search_spaces import BUILTIN_SEARCH_SPACES, TUNING_BUDGET


def _turn_y(theta: float) -> np.ndarray:
    """Rotation of camera-frame points (x right, y down, z forward) about the vertical axis."""
    c, s = np.cos(theta), np.sin(theta)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def _scene(seed: int, headings: bool):
    """View 1: 8 cars + 3 pedestrians; view 2: the cars turned and shifted (shuffled), plus 3
    pedestrians of its own. Truth: car k of view 1 is view 2's order.index(k)."""
    rng = np.random.default_rng(seed)
    xz = rng.uniform(-40, 40, (11, 2))
    p1 = np.column_stack([xz[:, 0], np.full(11, 1.5), xz[:, 1]])
    h1 = rng.uniform(-np.pi, np.pi, 11)
    theta = rng.uniform(-np.pi, np.pi)
    order = rng.permutation(8)
    turn, shift = _turn_y(theta), np.array([6.0, 0.0, -9.0])
    cars2 = (p1[:8][order] - shift) @ turn  # view-2 frame: Rᵀ (p − t)
    own = np.column_stack([rng.uniform(-40, 40, 3), np.full(3, 1.5), rng.uniform(-40, 40, 3)])
    p2 = np.vstack([cars2, own])
    # a heading h is the direction (sin h, cos h) in (x, z); turning the frame by θ about y
    # subtracts θ from every heading seen in view 2
    h2 = np.concatenate([h1[:8][order] - theta, rng.uniform(-np.pi, np.pi, 3)])
    meta = {"headings": (h1, h2)} if headings else {}
    problem = Problem(p1, p2, classes1=("car",) * 8 + ("pedestrian",) * 3,
                      classes2=("car",) * 8 + ("pedestrian",) * 3, meta=meta)  # fmt: skip
    return problem, {(int(order[k]), k) for k in range(8)}


@pytest.mark.parametrize("headings", [True, False])
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_the_planted_pairs_are_recovered_and_nothing_else(seed, headings):
    problem, truth = _scene(seed, headings)
    found = get("v2x_reg")(problem, threshold=0.5)
    assert {tuple(p) for p in found.pairs.tolist()} == truth
    assert found.info["headings"] is headings


def test_a_lone_pair_of_boxes_supports_nothing():
    problem = Problem(np.array([[0.0, 1.5, 10.0]]), np.array([[3.0, 1.5, 4.0]]),
                      classes1=("car",), classes2=("car",))  # fmt: skip
    assert get("v2x_reg")(problem, threshold=0.01).pairs.size == 0


def test_the_selection_keeps_bus_truck_car_first_then_the_nearest_within_range():
    points = np.array([[0, 0, 5.0], [0, 0, 200.0], [0, 0, 30.0], [0, 0, 3.0], [0, 0, 50.0]])
    classes = ["pedestrian", "bus", "car", "car", "bus"]
    assert top_k_boxes(points, classes, 3).tolist() == [2, 3, 4]  # the bus at 200 m is out
    assert top_k_boxes(points, classes, 0).tolist() == [0, 2, 3, 4]
    assert top_k_boxes(points, classes, 1).tolist() == [4]


def test_registered_with_the_equal_tuning_budget():
    assert "v2x_reg" in available()
    grid = BUILTIN_SEARCH_SPACES["v2x_reg"]
    assert len(grid) == TUNING_BUDGET and grid[0] == {}
    problem, _ = _scene(0, True)
    for options in grid:
        get("v2x_reg")(problem, threshold=0.5, **options)


def test_box_only_records_hand_it_their_headings(tmp_path):
    data = Dataset(import_dair_v2x(write_dair_layout(tmp_path / "s", frames=4, seed=2), tmp_path / "d").out)  # fmt: skip
    for pair in data:
        problem = pair.problem()
        assert len(problem.meta["headings"][0]) == problem.n1
        found = get("v2x_reg")(problem, threshold=0.3)
        assert found.info["headings"]
        assert {tuple(p) for p in found.pairs.tolist()} == {
            tuple(p) for p in pair.gt_pairs.tolist()
        }


def test_optimal_transport_no_longer_claims_to_be_v2x_reg():
    import matchers.optimal_transport as ot

    assert "as V2X-Reg++" not in (ot.__doc__ or "")
