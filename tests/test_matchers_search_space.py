"""Tuning grids: every matcher declares one (at most 12 configurations, relative scales), the
grids are accepted by their matchers, and register()/entry points can carry their own."""

import inspect

import numpy as np
import pytest
from learned_fixture import needed_options

from matchers import Problem, available, get, register, requires, search_space
from matchers.core import registry
from matchers.core.search_spaces import MAX_CONFIGS, check_search_space

# Options that hold a length or a kernel width: every one a matcher has must be tunable, and a
# grid may only set it in a form relative to the problem (never an absolute length).
ABSOLUTE_WIDTHS = {"sigma2", "tolerance"}
WIDTHS = {"sigma_scale", "sigma", "spread", "gate", "tolerance_scale", "tighten"}


def rich_problem(n=5, m=6, seed=0):
    """A small problem with every optional field, so every option of every matcher applies."""
    rng = np.random.default_rng(seed)
    p1 = rng.uniform(0, 30, (n, 3))
    p2 = np.vstack([p1[:4] + rng.normal(size=(4, 3)) * 0.1, rng.uniform(0, 30, (m - 4, 3))])
    return Problem(
        p1,
        p2,
        rng.random((n, 8)),
        rng.random((m, 8)),
        pixels1=rng.uniform(0, 1000, (n, 2)),
        pixels2=rng.uniform(0, 1000, (m, 2)),
        world1=p1 + [1.0, 2.0, 0.0],
        world2=p2,
        world_sigma=1.2,
    )


@pytest.mark.parametrize("name", available())
def test_every_matcher_has_a_valid_grid_its_matcher_accepts(name):
    space = search_space(name)
    assert 1 <= len(space) <= MAX_CONFIGS
    assert {} in space  # the defaults are always a candidate
    assert len({repr(sorted(c.items())) for c in space}) == len(space)
    problem = rich_problem()
    for config in space:
        assert not set(config) & ABSOLUTE_WIDTHS, config
        matching = get(name)(problem, seed=0, threshold=0.3, **config, **needed_options(name))
        assert matching.scores.shape == (problem.n1, problem.n2)
        assert np.all(np.isfinite(matching.scores))


@pytest.mark.parametrize("name", available())
def test_every_kernel_width_of_a_matcher_is_in_its_grid(name):
    options = set(inspect.signature(get(name)).parameters)
    if name in ("maximin_pose", "maximin_learned"):  # forward maximin's options (**options)
        options |= set(inspect.signature(get("maximin")).parameters)
    if name == "rrwm_learned":  # forwards RRWM's
        options |= set(inspect.signature(get("rrwm")).parameters)
    tunable = set().union(*search_space(name))
    assert options & WIDTHS <= tunable
    if options & ABSOLUTE_WIDTHS:  # an absolute width has its relative twin in the grid
        assert tunable & {"sigma_scale", "tolerance_scale"} or name == "consistency"


def test_grids_hold_the_relative_widths_the_issue_names():
    assert {c.get("sigma_scale") for c in search_space("sm")} > {None}
    assert {c.get("sigma") for c in search_space("maximin")} > {None}
    assert {c.get("spread") for c in search_space("pose")} > {None}
    assert search_space("appearance") == [{}]
    assert requires("sm") == frozenset()


def test_search_space_returns_a_copy():
    space = search_space("sm")
    space[1]["sigma_scale"] = 99.0
    assert search_space("sm")[1]["sigma_scale"] != 99.0


def _echo(problem, seed=0, threshold=None, *, width=1.0):
    return get("appearance")(problem, seed, threshold)


def test_register_takes_a_search_space_or_the_callables_attribute(monkeypatch):
    monkeypatch.setattr(registry, "_registered", {})
    monkeypatch.setattr(registry, "_registered_spaces", {})
    register("echo", _echo, search_space=[{"width": 0.5}, {"width": 2.0}])
    assert search_space("echo") == [{"width": 0.5}, {"width": 2.0}]

    def carried(problem, seed=0, threshold=None, *, width=1.0):
        return _echo(problem, seed, threshold, width=width)

    carried.search_space = [{}, {"width": 3.0}]
    register("carried", carried)
    assert search_space("carried") == [{}, {"width": 3.0}]
    register("plain", _echo)
    assert search_space("plain") == [{}]
    register("maximin", _echo, replace=True, search_space=[{"width": 1.0}])
    assert search_space("maximin") == [{"width": 1.0}]


def test_builtin_grid_returns_after_an_override_is_undone(monkeypatch):
    builtin = search_space("maximin")
    with monkeypatch.context() as patch:
        patch.setattr(registry, "_registered", {})
        register("maximin", _echo, replace=True, search_space=[{"width": 1.0}])
    assert search_space("maximin") == builtin


@pytest.mark.parametrize(
    ("space", "message"),
    [
        ([{"sigma": float(s)} for s in range(1, 14)], "1 to 12"),
        ([], "1 to 12"),
        ({"sigma": 1.0}, "list of option dicts"),
        ("sigma", "list of option dicts"),
        ([("sigma", 1.0)], "option dicts"),
        ([{"not a name": 1}], "identifiers"),
        ([{"sigma": float("nan")}], "JSON"),
        ([{"sigma": object()}], "JSON"),
        ([{"sigma": 1.0}, {"sigma": 1.0}], "repeats"),
    ],
)
def test_invalid_grids_are_refused_naming_the_field(space, message, monkeypatch):
    monkeypatch.setattr(registry, "_registered", {})
    with pytest.raises(ValueError, match=f"search_space.*{message}"):
        register("bad", _echo, search_space=space)
    with pytest.raises(ValueError, match=message):
        check_search_space(space, "bad")


def test_unknown_matcher_has_no_grid():
    with pytest.raises(ValueError, match="unknown matcher"):
        search_space("nope")
