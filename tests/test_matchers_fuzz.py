"""Property-based fuzzing of every registered matcher (issue 15): whatever the input, a matcher
returns a valid result or refuses with a ValueError/TypeError naming the offending argument (or
``ProblemTooLarge``); never a crash, a NaN, or pairs that are not a partial permutation.

A few hundred examples in CI; ``pytest --hypothesis-profile=long tests/test_matchers_fuzz.py``
runs thousands (profiles registered in tests/conftest.py)."""

from __future__ import annotations

import re
import warnings

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from learned_fixture import needed_options

from matchers import Problem, ProblemTooLarge, available, get, requires

MATCHERS = available()
# 30 examples per matcher normally; the "long" profile's count (tests/conftest.py) when selected.
EXAMPLES = 30 if settings().max_examples < 1000 else settings().max_examples
# The arguments a refusal may name: the problem's fields and any option passed.
ARGUMENTS = (
    "points1|points2|features1|features2|pixels1|pixels2|world1|world2|world_sigma|problem|seed|"
    "threshold|options?"
)


@st.composite
def views(draw, max_objects: int = 7):
    """Two views with adversarial geometry and features, and optionally the prior/pixels."""
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    n, m = draw(st.integers(0, max_objects)), draw(st.integers(0, max_objects))
    dim = draw(st.sampled_from([2, 3]))
    scale = draw(st.sampled_from([1e-9, 1e-3, 1.0, 1e3, 1e9]))
    layout = draw(st.sampled_from(["random", "identical", "collinear", "grid", "duplicates"]))

    def points(k):
        p = rng.normal(size=(k, dim)) * scale
        if layout == "identical" and k:
            p[:] = p[0]
        elif layout == "collinear":
            p = np.outer(rng.normal(size=k), rng.normal(size=dim)) * scale
        elif layout == "grid":
            p = np.round(p / scale) * scale
        elif layout == "duplicates" and k > 1:
            p[k // 2 :] = p[: k - k // 2]
        return p

    p1, p2 = points(n), points(m)
    kind = draw(st.sampled_from(["none", "zeros", "random", "huge", "tiny", "one-hot"]))
    f1 = f2 = None
    if kind != "none":
        d = draw(st.integers(1, 5))
        f1, f2 = rng.random((n, d)), rng.random((m, d))
        if kind == "zeros":
            f1[:], f2[:] = 0.0, 0.0
        elif kind == "huge":
            f1, f2 = f1 * 1e200, f2 * 1e200
        elif kind == "tiny":
            f1, f2 = f1 * 1e-300, f2 * 1e-300
        elif kind == "one-hot":
            f1, f2 = np.eye(n, d), np.eye(m, d)
    extra = {}
    if draw(st.booleans()):
        extra |= {"pixels1": rng.uniform(0, 640, (n, 2)), "pixels2": rng.uniform(0, 640, (m, 2))}
    if draw(st.booleans()):
        w1 = np.c_[rng.normal(size=(n, 2)) * scale, np.zeros(n)]
        w2 = np.c_[rng.normal(size=(m, 2)) * scale, np.zeros(m)]
        extra |= {
            "world1": w1,
            "world2": w2,
            "world_sigma": draw(st.sampled_from([1e-6, 1.2, 1e6])),
        }
    return Problem(p1, p2, f1, f2, **extra)


def _check(name: str, problem: Problem, threshold) -> None:
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error", RuntimeWarning)  # overflow/invalid = a silent NaN risk
            matching = get(name)(problem, seed=0, threshold=threshold, **needed_options(name))
    except ProblemTooLarge:
        return
    except (ValueError, TypeError) as exc:
        missing = set(requires(name)) - {
            f for f in requires(name) if getattr(problem, f) is not None
        }
        assert missing or re.match(rf"^({ARGUMENTS})\b", str(exc)), f"{name}: {exc}"
        return
    n, m = problem.n1, problem.n2
    scores = np.asarray(matching.scores)
    assert scores.shape == (n, m), name
    assert np.all(np.isfinite(scores)), f"{name}: NaN/inf scores"
    pairs = np.asarray(matching.pairs).reshape(-1, 2)
    assert np.all((pairs[:, 0] >= 0) & (pairs[:, 0] < n) & (pairs[:, 1] >= 0) & (pairs[:, 1] < m))
    assert len(set(pairs[:, 0].tolist())) == len(pairs) == len(set(pairs[:, 1].tolist())), name


@pytest.mark.parametrize("name", MATCHERS)
@settings(max_examples=EXAMPLES, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(problem=views(), threshold=st.sampled_from([None, 0.0, 0.5, 1.0]))
def test_matcher_survives_fuzzed_views(name, problem, threshold):
    _check(name, problem, threshold)


@pytest.mark.parametrize("name", MATCHERS)
@settings(max_examples=10, deadline=None)
@given(bad=st.sampled_from([float("nan"), float("inf"), -float("inf"), "high", [0.5], True]))
def test_bad_threshold_is_refused_by_name(name, bad):
    problem = Problem(np.eye(3), np.eye(3), world1=np.eye(3), world2=np.eye(3), world_sigma=1.0)
    with pytest.raises((ValueError, TypeError), match="threshold"):
        get(name)(problem, seed=0, threshold=bad, **needed_options(name))


@pytest.mark.parametrize("name", MATCHERS)
def test_unknown_option_is_refused(name):
    problem = Problem(np.eye(3), np.eye(3), world1=np.eye(3), world2=np.eye(3), world_sigma=1.0)
    with pytest.raises(TypeError, match="no_such_option"):
        get(name)(problem, no_such_option=1, **needed_options(name))
