"""Reusing a problem's tensor search across hypergraph matchers (matchers.hypergraph.tensor_sharing) changes
no result and no reported time, and only applies inside the block."""

import numpy as np
import pytest

from matchers import Problem, build_tensor, get, shared_tensors
from matchers.hypergraph import tensor_sharing

HYPERGRAPH = ("tm", "hgm", "bcagm", "rrwhm", "mos", "maximin")


def _problem(seed: int) -> Problem:
    rng = np.random.default_rng(seed)
    world = rng.uniform(0, 30, (20, 3))
    p1, p2 = world[:14], world[5:] + rng.normal(0, 0.2, (15, 3))
    f = rng.random((20, 6))
    return Problem(p1, p2, f[:14], f[5:] + rng.normal(0, 0.05, (15, 6)))


def _builds(monkeypatch) -> list:
    calls = []
    original = tensor_sharing.build_or_reuse

    def counted(problem, rng, options, build):
        def counted_build():
            calls.append(options)
            return build()

        return original(problem, rng, options, counted_build)

    monkeypatch.setattr("matchers.hypergraph.tensor_build.build_or_reuse", counted)
    return calls


@pytest.mark.parametrize("seed", [0, 5])
def test_shared_tensor_gives_the_same_bits_and_builds_once(seed, monkeypatch):
    problems = [_problem(k) for k in range(2)]
    plain = [[get(name)(p, seed=seed) for name in HYPERGRAPH] for p in problems]
    builds = _builds(monkeypatch)
    shared = []
    for p in problems:
        with shared_tensors():
            shared.append([get(name)(p, seed=seed) for name in HYPERGRAPH])
    assert len(builds) == len(problems)  # one build per problem, five reuses
    for xs, ys in zip(plain, shared, strict=True):
        for x, y in zip(xs, ys, strict=True):
            assert np.array_equal(x.pairs, y.pairs) and np.array_equal(x.scores, y.scores)
    # every later matcher is told it reused the tensor, and is charged its build time
    for row in shared:
        assert not row[0].info["tensor"].get("reused")
        for later in row[1:]:
            assert later.info["tensor"]["reused"]
            assert later.time_s >= later.info["tensor"]["reused_s"] > 0


def test_the_generator_moves_on_as_if_the_tensor_had_been_built():
    # maximin's random start is drawn after the triangle sampling: a wrong generator state on
    # reuse would change it
    problem = _problem(2)
    alone = get("maximin")(problem, seed=9, init="random")
    with shared_tensors():
        get("tm")(problem, seed=9)
        reused = get("maximin")(problem, seed=9, init="random")
    assert reused.info["tensor"]["reused"]
    assert np.array_equal(alone.scores, reused.scores)


def test_matchers_with_other_bandwidths_share_the_search_not_the_values(monkeypatch):
    problem = _problem(4)
    runs = [("tm", 0.2), ("rrwhm", 0.1), ("maximin", 1.0), ("bcagm", None)]
    plain = [get(name)(problem, seed=2, sigma=sigma) for name, sigma in runs]
    builds = _builds(monkeypatch)
    with shared_tensors():
        shared = [get(name)(problem, seed=2, sigma=sigma) for name, sigma in runs]
    assert len(builds) == 1
    for x, y in zip(plain, shared, strict=True):
        assert np.array_equal(x.scores, y.scores)
        assert x.info["tensor"]["bandwidth"] == y.info["tensor"]["bandwidth"]


def test_nothing_is_shared_outside_the_block_or_across_options(monkeypatch):
    problem = _problem(3)
    builds = _builds(monkeypatch)
    get("tm")(problem, seed=0)
    get("rrwhm")(problem, seed=0)
    assert len(builds) == 2  # outside the block: every call builds (timing loops stay honest)
    with shared_tensors():
        get("tm")(problem, seed=0)
        get("rrwhm")(problem, seed=0, neighbours=50)  # other options: another tensor
        get("hgm")(problem, seed=1)  # another seed: another triangle sample
        get("mos")(problem, seed=0, tensor=build_tensor(problem, "paper", 0))  # prebuilt
    assert len(builds) == 5


def test_the_block_keeps_at_most_limit_tensors(monkeypatch):
    problems = [_problem(k) for k in range(3)]
    builds = _builds(monkeypatch)
    with shared_tensors(limit=2):
        for p in problems:  # three tensors: the first is dropped
            get("tm")(p, seed=0)
        get("tm")(problems[2], seed=0)
        get("tm")(problems[0], seed=0)
    assert len(builds) == 4
    with pytest.raises(ValueError, match="limit"):
        with shared_tensors(limit=0):
            pass
