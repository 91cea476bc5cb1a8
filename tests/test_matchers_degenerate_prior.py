"""Degenerate input for the matchers added with the localisation prior (and ``none``): empty
views, 1-2 objects, identical positions, all-zero features, a prior that puts every object in
one spot — a valid Matching, never an exception, a NaN or a numpy warning."""

import warnings

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from matchers import Problem, get

PRIOR = ["maximin_pose", "pose", "pose_appearance", "pose_refine"]
NEW = [*PRIOR, "consistency", "none"]


def check_valid(name, matching, n, m, threshold):
    pairs = matching.pairs
    assert pairs.shape[1] == 2 and len(set(pairs[:, 0])) == len(pairs) == len(set(pairs[:, 1]))
    assert matching.scores.shape == (n, m) and np.all(np.isfinite(matching.scores))
    if matching.scores.size:
        assert matching.scores.min() >= 0 and matching.scores.max() <= 1
    if name == "none":
        assert len(pairs) == 0
    elif threshold is None:
        assert len(pairs) == min(n, m)
    else:
        assert np.all(matching.scores[pairs[:, 0], pairs[:, 1]] >= threshold)


@st.composite
def degenerate_views(draw):
    def view():
        n = draw(st.integers(0, 6))
        kind = draw(st.sampled_from(["random", "identical", "duplicates", "collinear"]))
        rng = np.random.default_rng(draw(st.integers(0, 2**16)))
        pts = rng.normal(size=(n, 3)) * draw(st.sampled_from([1e-6, 1.0, 50.0]))
        if kind == "identical":
            pts[:] = pts[:1] if n else pts
        elif kind == "duplicates" and n > 1:
            pts[n // 2 :] = pts[: n - n // 2]
        elif kind == "collinear":
            pts = np.outer(rng.normal(size=n), rng.normal(size=3)) + rng.normal(size=3)
        return pts

    p1, p2 = view(), view()
    prior = draw(st.sampled_from(["same", "shifted", "one spot", "far"]))
    shift = {"same": 0.0, "shifted": 3.0, "one spot": 0.0, "far": 1e4}[prior]
    w1, w2 = p1.copy(), p2 + shift
    if prior == "one spot":
        w1[:], w2[:] = 7.0, 7.0
    features = draw(st.sampled_from(["none", "zeros", "some zero rows", "random"]))
    f1 = f2 = None
    if features != "none":
        rng = np.random.default_rng(draw(st.integers(0, 2**16)))
        f1, f2 = rng.random((len(p1), 4)), rng.random((len(p2), 4))
        if features == "zeros":
            f1[:], f2[:] = 0, 0
        elif features == "some zero rows":
            f1[::2], f2[1::2] = 0, 0
    sigma = draw(st.sampled_from([1e-3, 1.2, 100.0]))
    return Problem(p1, p2, f1, f2, world1=w1, world2=w2, world_sigma=sigma)


@pytest.mark.parametrize("name", NEW)
@settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(problem=degenerate_views(), threshold=st.sampled_from([None, 0.0, 0.5]))
def test_degenerate_input_gives_a_valid_matching(name, problem, threshold):
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no RuntimeWarning (division by zero, overflow, NaN)
        matching = get(name)(problem, threshold=threshold)
    check_valid(name, matching, problem.n1, problem.n2, threshold)


@pytest.mark.parametrize("name", NEW)
@pytest.mark.parametrize(("n", "m"), [(0, 0), (0, 4), (3, 0), (1, 1), (1, 2), (2, 2)])
def test_tiny_views(name, n, m):
    rng = np.random.default_rng(n * 7 + m)
    p1, p2 = rng.normal(size=(n, 3)), rng.normal(size=(m, 3))
    problem = Problem(p1, p2, world1=p1, world2=p2, world_sigma=0.5)
    for threshold in (None, 0.5):
        check_valid(name, get(name)(problem, threshold=threshold), n, m, threshold)


@pytest.mark.parametrize("name", PRIOR)
def test_one_object_each_with_an_exact_prior_is_matched(name):
    p = np.array([[1.0, 2.0, 0.0]])
    problem = Problem(p, p, world1=p, world2=p, world_sigma=1.0)
    assert get(name)(problem, threshold=0.5).pairs.tolist() == [[0, 0]]
