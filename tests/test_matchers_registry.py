"""Registry: built-in names, register(), and the ``cadsim.matchers`` entry-point group."""

import sys
import textwrap

import numpy as np
import pytest
from learned_fixture import needed_options

import matchers
from matchers import Matching, Problem, available, get, register
from matchers.core import registry


def test_available_lists_the_builtins_sorted():
    names = available()
    assert names == sorted(names)
    assert set(names) >= {
        "appearance",
        "bcagm",
        "consistency",
        "hgm",
        "maximin",
        "maximin_pose",
        "mos",
        "none",
        "pose",
        "pose_appearance",
        "pose_refine",
        "rrwhm",
        "rrwm",
        "sm",
        "tm",
    }


def test_get_unknown_name_lists_what_exists():
    with pytest.raises(ValueError, match="unknown matcher 'nope'.*maximin"):
        get("nope")


def _constant(problem, seed=0, threshold=None):
    scores = np.ones((problem.n1, problem.n2))
    return Matching(np.zeros((0, 2), dtype=int), scores, "constant")


def test_register_adds_and_refuses_silent_overrides(monkeypatch):
    monkeypatch.setattr(registry, "_registered", {})
    register("constant", _constant)
    assert "constant" in available() and get("constant") is _constant
    with pytest.raises(ValueError, match="already exists"):
        register("maximin", _constant)
    register("maximin", _constant, replace=True)
    assert get("maximin") is _constant
    with pytest.raises(TypeError, match="fn"):
        register("other", 42)


def test_entry_point_group_is_discovered_lazily(tmp_path, monkeypatch):
    package = tmp_path / "third_party_matcher.py"
    package.write_text(
        textwrap.dedent(
            """
            import numpy as np
            from matchers import Matching

            def flipped(problem, seed=0, threshold=None, *, width=1.0):
                n = min(problem.n1, problem.n2)
                pairs = np.stack([np.arange(n), np.arange(n)[::-1]], axis=1)
                return Matching(pairs, np.zeros((problem.n1, problem.n2)), "flipped")

            flipped.search_space = [{}, {"width": 2.0}]
            flipped.requires = ("world1", "world2", "world_sigma")
            """
        )
    )
    dist = tmp_path / "third_party_matcher-1.0.dist-info"
    dist.mkdir()
    (dist / "METADATA").write_text(
        "Metadata-Version: 2.1\nName: third-party-matcher\nVersion: 1.0\n"
    )
    (dist / "entry_points.txt").write_text(
        f"[{matchers.ENTRY_POINT_GROUP}]\nflipped = third_party_matcher:flipped\n"
    )
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.setattr(registry, "_registered", {})
    registry._entry_points.cache_clear()
    try:
        assert "flipped" in available()
        assert "third_party_matcher" not in sys.modules  # listed without importing
        fn = get("flipped")
        result = fn(Problem(np.zeros((3, 2)), np.zeros((3, 2))))
        assert result.pairs.tolist() == [[0, 2], [1, 1], [2, 0]]
        assert matchers.search_space("flipped") == [{}, {"width": 2.0}]
        assert matchers.requires("flipped") == {"world1", "world2", "world_sigma"}
    finally:
        registry._entry_points.cache_clear()
        sys.modules.pop("third_party_matcher", None)


def test_matchers_that_declare_themselves_seed_free_are():
    # the runner runs a deterministic matcher once for all seeds: a wrong declaration would
    # silently drop run-to-run variation from every table
    from matchers import available, deterministic

    rng = np.random.default_rng(3)
    world = rng.uniform(0, 30, (20, 3))
    p1, p2 = world[:14], world[6:] + rng.normal(0, 0.3, (14, 3))
    features = rng.random((20, 6))
    problem = Problem(
        p1, p2, features[:14], features[6:], world1=p1, world2=p2 + 0.5, world_sigma=1.0
    )
    declared = [name for name in available() if deterministic(name)]
    assert {"none", "appearance", "sm", "rrwm", "consistency", "pose"} <= set(declared)
    assert not deterministic("maximin") and not deterministic("rrwhm")
    for name in declared:
        options = needed_options(name)
        a, b = get(name)(problem, seed=0, **options), get(name)(problem, seed=7, **options)
        assert np.array_equal(a.pairs, b.pairs), name
        assert np.array_equal(a.scores, b.scores), name
