"""Issue 15 items 8-9 on the matcher side: a per-process memory budget refuses oversized calls
before allocating; huge feature norms and ragged arrays get clear answers."""

from __future__ import annotations

import numpy as np
import pytest
from learned_fixture import needed_options

from matchers import Problem, ProblemTooLarge, get
from matchers.blocks.appearance_similarity import appearance_similarity
from matchers.core.memory_budget import BUDGET_ENV, budget_mb


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


# --- issue 22 #5: every matcher checks an estimate that holds, before it allocates ---

MB = 2**20


def prior_scene(n: int, seed: int = 0) -> Problem:
    """n v n objects with features, pixels and a localisation prior: every matcher runs on it."""
    rng = np.random.default_rng(seed)
    p = rng.uniform(0, 60, (n, 3))
    q = p + 0.05 * rng.standard_normal((n, 3))
    f = rng.random((n, 64))
    return Problem(
        p, q, f, f + 0.01 * rng.random((n, 64)), pixels1=p[:, :2] * 10, pixels2=q[:, :2] * 10,
        world1=p, world2=q + 0.5, world_sigma=1.2,
    )  # fmt: skip


def _traced_peak(fn, problem) -> int:
    import tracemalloc

    tracemalloc.start()
    try:
        fn(problem)
        return tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()


def test_every_registered_matcher_carries_a_memory_estimate():
    from matchers.core.registry import available

    missing = [
        name for name in available() if not callable(getattr(get(name), "memory_bytes", None))
    ]
    assert not missing, f"matchers without memory_bytes (register(..., memory=...)): {missing}"


def _all_matchers():
    from matchers.core.registry import available

    return available()


@pytest.mark.parametrize("name", _all_matchers())
@pytest.mark.parametrize("n", [30, 60])
def test_the_estimate_is_within_1_5x_of_the_measured_peak(name, n):
    matcher, options = get(name), needed_options(name)

    def fn(problem):
        return matcher(problem, **options)

    fn(prior_scene(8))  # compile the kernels first: their one-off cost is not the call's
    problem = prior_scene(n)
    estimate = matcher.memory_bytes(problem)
    peak = _traced_peak(fn, problem)
    assert peak <= max(1.5 * estimate, 10 * MB), (peak / MB, estimate / MB)  # the budget holds
    if peak >= 10 * MB:  # where memory matters, the estimate is also not far above
        assert estimate <= 1.5 * peak, (peak / MB, estimate / MB)


def test_the_resident_growth_of_a_large_tensor_build_is_within_its_estimate():
    # The k-d tree and radius search allocate outside Python (tracemalloc cannot see them): their
    # growth is measured as the process's resident memory, in a fresh process.
    import subprocess
    import sys

    code = (
        "import sys, threading, time; sys.path.insert(0, 'tests')\n"
        "from test_matchers_budget import prior_scene\n"
        "from matchers import get\n"
        "fn = get('maximin'); fn(prior_scene(8)); problem = prior_scene(250)\n"
        "rss = lambda: int(open('/proc/self/statm').read().split()[1]) * 4096\n"
        "base = rss(); peak = [base]; done = []\n"
        "def poll():\n"
        "    while not done:\n"
        "        peak[0] = max(peak[0], rss()); time.sleep(0.002)\n"
        "t = threading.Thread(target=poll); t.start(); fn(problem); done.append(1); t.join()\n"
        "print(peak[0] - base, fn.memory_bytes(problem))\n"
    )
    from pathlib import Path

    root = Path(__file__).resolve().parents[1]
    out = subprocess.run([sys.executable, "-c", code], cwd=root, capture_output=True, text=True,
                         timeout=600, check=True).stdout.split()  # fmt: skip
    grown, estimate = float(out[-2]), float(out[-1])
    assert grown / 1.5 <= estimate <= 1.5 * grown, (grown / MB, estimate / MB)


@pytest.mark.parametrize("name", _all_matchers())
def test_a_1024_mb_budget_holds_at_300_v_300(name, monkeypatch):
    monkeypatch.setenv(BUDGET_ENV, "1024")
    matcher, options = get(name), needed_options(name)

    def fn(problem):
        return matcher(problem, **options)

    problem = prior_scene(300)
    estimate = matcher.memory_bytes(problem)
    if estimate > 1024 * MB:
        import tracemalloc

        tracemalloc.start()
        try:
            with pytest.raises(ProblemTooLarge, match="1,024 MB budget"):
                fn(problem)
            allocated = tracemalloc.get_traced_memory()[1]
        finally:
            tracemalloc.stop()
        assert allocated < 16 * MB  # refused before anything large was allocated
    else:
        assert _traced_peak(fn, problem) <= 1024 * MB


def test_a_registered_matcher_is_held_to_its_estimate(monkeypatch):
    from matchers.core import registry

    monkeypatch.setattr(registry, "_registered", dict(registry._registered))
    monkeypatch.setattr(registry, "_registered_spaces", dict(registry._registered_spaces))
    monkeypatch.setenv(BUDGET_ENV, "1")
    registry.register(
        "dense_thing", get("none"), memory=lambda problem, **options: 1e9, replace=True
    )
    with pytest.raises(ProblemTooLarge, match="dense_thing|none"):
        get("dense_thing")(scene(5))
    assert get("dense_thing").memory_bytes(scene(5)) == 1e9
