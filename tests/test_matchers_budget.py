"""Issue 15 items 8-9 on the matcher side: a per-process memory budget refuses oversized calls
before allocating; huge feature norms and ragged arrays get clear answers."""

from __future__ import annotations

import numpy as np
import pytest

from matchers import Problem, ProblemTooLarge, get
from matchers.appearance_similarity import appearance_similarity
from matchers.memory_budget import BUDGET_ENV, budget_mb


def scene(n: int, seed: int = 0) -> Problem:
    rng = np.random.default_rng(seed)
    p = rng.uniform(0, 30, (n, 3))
    f = rng.random((n, 6))
    return Problem(p, p + 0.05 * rng.standard_normal((n, 3)), f, f)


def test_budget_comes_from_the_environment(monkeypatch):
    monkeypatch.delenv(BUDGET_ENV, raising=False)
    assert budget_mb() == 4096
    monkeypatch.setenv(BUDGET_ENV, "12.5")
    assert budget_mb() == 12.5
    for bad in ("0", "-1", "inf", "lots"):
        monkeypatch.setenv(BUDGET_ENV, bad)
        with pytest.raises(ValueError, match=BUDGET_ENV):
            budget_mb()


def test_uncapped_tensor_over_budget_is_refused_before_allocating(monkeypatch):
    monkeypatch.setenv(BUDGET_ENV, "60")
    problem = scene(30)
    with pytest.raises(ProblemTooLarge) as err:
        get("maximin")(problem, max_tensor_entries=None)
    message = str(err.value)
    assert "third-order tensor (30 x 30 objects" in message and "60 MB budget" in message
    assert "max_tensor_entries" in message and BUDGET_ENV in message
    assert isinstance(err.value, ValueError)
    get("maximin")(problem, max_tensor_entries=250_000)  # a lower cap fits the budget


def test_dense_pairwise_over_budget_names_the_option(monkeypatch):
    monkeypatch.setenv(BUDGET_ENV, "10")
    problem = scene(30)  # (900)^2 entries x 24 bytes ~ 19 MB dense
    for name in ("sm", "rrwm"):
        with pytest.raises(ProblemTooLarge, match="affinity_neighbours"):
            get(name)(problem, affinity_neighbours=None)
    get("sm")(problem, affinity_neighbours=50)  # sparse: within budget


def test_default_budget_admits_the_paper_sizes():
    problem = scene(20)
    for name in ("maximin", "rrwhm", "sm", "rrwm", "mos"):
        assert len(get(name)(problem).pairs) == 20


def test_huge_feature_norms_still_give_their_cosine():
    f = np.array([[1e200, 1e200], [3e-200, 4e-200]])
    problem = Problem(np.zeros((2, 3)), np.zeros((2, 3)), f, f[::-1] * 2.0)
    b = appearance_similarity(problem)
    assert np.all(np.isfinite(b))
    np.testing.assert_allclose(b[0, 1], 1.0)  # the same direction, whatever the magnitude
    np.testing.assert_allclose(b[1, 0], 1.0)
    np.testing.assert_allclose(b[0, 0], (3 + 4) / (np.sqrt(2) * 5))


@pytest.mark.parametrize("field", ["points1", "points2", "features1"])
def test_ragged_or_object_arrays_name_the_argument(field):
    good = {
        "points1": np.zeros((2, 3)),
        "points2": np.zeros((2, 3)),
        "features1": np.ones((2, 2)),
        "features2": np.ones((2, 2)),
    }
    good[field] = [[0.0, 1.0, 2.0], [0.0]] if field.startswith("points") else [["a", "b"], [1, 2]]
    with pytest.raises(ValueError, match=f"^{field}: expected a rectangular array of numbers"):
        Problem(**good)
