"""Degenerate input never raises and never produces NaN: empty views, < 3 objects, duplicate
and collinear positions, all-zero features (hypothesis explores the combinations)."""

import warnings

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from learned_fixture import needed_options

from matchers import Problem, available, get, requires

NAMES = ["appearance", "bcagm", "consistency", "hgm", "maximin", "mos", "rrwhm", "rrwm", "sm", "tm"]
# with the localisation prior, and `none`: tests/test_matchers_degenerate_prior.py


def check_valid(matching, n, m, threshold):
    pairs = matching.pairs
    assert pairs.shape[1] == 2 and len(set(pairs[:, 0])) == len(pairs) == len(set(pairs[:, 1]))
    assert matching.scores.shape == (n, m) and np.all(np.isfinite(matching.scores))
    if matching.scores.size:
        assert matching.scores.min() >= 0 and matching.scores.max() <= 1
    if threshold is None:
        assert len(pairs) == min(n, m)
    else:
        assert np.all(matching.scores[pairs[:, 0], pairs[:, 1]] >= threshold)


@st.composite
def degenerate_views(draw):
    dim = draw(st.sampled_from([2, 3]))

    def view():
        n = draw(st.integers(0, 6))
        kind = draw(st.sampled_from(["random", "identical", "duplicates", "collinear"]))
        rng = np.random.default_rng(draw(st.integers(0, 2**16)))
        pts = rng.normal(size=(n, dim))
        if kind == "identical":
            pts[:] = pts[:1] if n else pts
        elif kind == "duplicates" and n > 1:
            pts[n // 2 :] = pts[: n - n // 2]
        elif kind == "collinear":
            pts = np.outer(rng.normal(size=n), rng.normal(size=dim)) + rng.normal(size=dim)
        return pts

    p1, p2 = view(), view()
    features = draw(st.sampled_from(["none", "zeros", "some zero rows", "random"]))
    f1 = f2 = None
    if features != "none":
        rng = np.random.default_rng(draw(st.integers(0, 2**16)))
        f1, f2 = rng.random((len(p1), 4)), rng.random((len(p2), 4))
        if features == "zeros":
            f1[:], f2[:] = 0, 0
        elif features == "some zero rows":
            f1[::2], f2[1::2] = 0, 0
    return Problem(p1, p2, f1, f2)


@pytest.mark.parametrize("name", NAMES)
@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(problem=degenerate_views(), threshold=st.sampled_from([None, 0.0, 0.5]))
def test_degenerate_input_gives_a_valid_matching(name, problem, threshold):
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no RuntimeWarning (division by zero, overflow, NaN)
        matching = get(name)(problem, threshold=threshold)
    check_valid(matching, problem.n1, problem.n2, threshold)


@pytest.mark.parametrize("name", NAMES)
def test_fewer_than_three_objects_means_no_spatial_evidence(name):
    problem = Problem(
        np.array([[0.0, 0.0], [1.0, 0.0]]), np.array([[0.0, 0.0], [1.0, 0.0], [5.0, 5.0]])
    )
    matching = get(name)(problem, threshold=0.5)
    if name in ("bcagm", "hgm", "rrwhm", "tm"):  # third order only: nothing to go on
        assert np.all(matching.scores == 0) and len(matching.pairs) == 0
    check_valid(matching, 2, 3, 0.5)


def test_problem_rejects_nan_with_the_array_name():
    with pytest.raises(ValueError, match="points2"):
        Problem(np.zeros((3, 2)), np.array([[0.0, np.nan]]))


def test_every_listed_matcher_handles_an_empty_problem():
    empty = np.zeros((0, 3))
    prior = {"world1": empty, "world2": empty, "world_sigma": 1.0}
    for name in available():
        fields = prior if requires(name) else {}
        check_valid(get(name)(Problem(empty, empty, **fields), **needed_options(name)), 0, 0, None)
