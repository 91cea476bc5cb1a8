"""The equal-cue protocol: every one of the paper's eight matchers reads metric geometry and
appearance (inspected by behaviour, not by declaration alone), the metric term is the stated
equation, and the protocol runs tuned with its own grids and writes its own table."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from frame_pair_fakes import make_dataset

from eval.core import tasks
from eval.core.cache import ResultCache
from eval.core.executor import SerialExecutor
from eval.core.runner import Runner
from eval.core.tasks import MatcherSpec
from eval.engine.protocol_run import evaluate
from eval.engine.splits import open_entry
from eval.protocol.cues import (
    EQUAL_CUE_OPTIONS,
    EQUAL_CUES,
    PUBLISHED_CUES,
    cues_read,
    equal_cue_spec,
    search_space_of,
)
from eval.protocol.tuning import candidates_of
from eval.report.tables import write_tables
from matchers import Problem, get
from matchers.blocks.cue_terms import metric_factor, weighted_tensor
from matchers.core.scale import median_spacing
from matchers.hypergraph.tensor_build import build_tensor

PAPER_EIGHT = ("sm", "rrwm", "tm", "hgm", "bcagm", "rrwhm", "mos", "maximin")


def _views(seed: int = 1) -> tuple[Problem, Problem, Problem]:
    """A problem, the same with view 2 scaled by 1.5 (same angles, other distances), and the same
    with view 2's features redrawn (same geometry, other appearance)."""
    rng = np.random.default_rng(seed)
    points1 = rng.uniform(-20, 20, (8, 3))
    keep = [3, 1, 0, 7, 5, 2]
    points2 = points1[keep] + rng.normal(0, 0.3, (6, 3))
    features1 = rng.random((8, 16))
    features2 = features1[keep] + 0.3 * rng.random((6, 16))
    return (
        Problem(points1, points2, features1, features2),
        Problem(points1, 1.5 * points2, features1, features2),
        Problem(points1, points2, features1, rng.random((6, 16))),
    )


def _observed_cues(name: str, options: dict) -> frozenset[str]:
    """The cues matcher `name` is seen to read: distances when scaling one view changes its
    scores (angles do not change), appearance when redrawing one view's features does."""
    problem, scaled, refeatured = _views()
    matcher = get(name)
    scores = matcher(problem, **options).scores
    seen = set()
    if not np.allclose(scores, matcher(scaled, **options).scores, rtol=0, atol=1e-9):
        seen.add("distances")
    if not np.allclose(scores, matcher(refeatured, **options).scores, rtol=0, atol=1e-9):
        seen.add("appearance")
    return frozenset(seen)


@pytest.mark.parametrize("name", PAPER_EIGHT)
def test_every_paper_matcher_reads_the_same_cues_under_the_equal_cue_protocol(name):
    options = dict(equal_cue_spec(MatcherSpec(name)).options)
    assert _observed_cues(name, options) == EQUAL_CUES
    assert cues_read(name, options) >= EQUAL_CUES


@pytest.mark.parametrize("name", PAPER_EIGHT)
def test_the_published_cue_table_matches_what_each_matcher_reads(name):
    observed = _observed_cues(name, {})
    assert observed == PUBLISHED_CUES[name] & EQUAL_CUES
    assert cues_read(name, {}) == PUBLISHED_CUES[name]


def test_as_published_maximin_lacks_the_metric_cue_that_mos_has():
    assert "distances" not in PUBLISHED_CUES["maximin"]
    assert "distances" in PUBLISHED_CUES["mos"]
    assert cues_read("sm", {"pairwise": "image"}) == frozenset()


def test_the_metric_term_multiplies_each_entry_by_its_three_edges_pairwise_affinity():
    problem = _views()[0]
    tensor = build_tensor(problem, "paper", rng=0)
    weighted = weighted_tensor(tensor, problem, distance_scale=0.2)
    assert np.array_equal(weighted.indices, tensor.indices)
    m = problem.n2
    width = 0.2 * median_spacing(problem.points1, problem.points2)
    for row in (0, tensor.nnz // 2, tensor.nnz - 1):
        a, b, c = tensor.indices[row]
        expected = tensor.values[row]
        for u, v in ((a, b), (b, c), (a, c)):
            d1 = np.linalg.norm(problem.points1[u // m] - problem.points1[v // m])
            d2 = np.linalg.norm(problem.points2[u % m] - problem.points2[v % m])
            expected *= np.exp(-((d1 - d2) ** 2) / width**2)
        assert weighted.values[row] == pytest.approx(expected, rel=1e-12)
    assert np.all(weighted.values <= tensor.values)
    same = metric_factor(problem, np.array([0]), np.array([1]), 0.2)
    assert same.shape == (1,) and 0 < same[0] <= 1


def test_mos_under_equal_cues_multiplies_its_cues_into_m_and_t_and_differs_from_published():
    # the additive first-order share alone (as published) is not the equal-cue form: the scores
    # change once appearance and the metric kernel enter every higher-order entry
    problem = _views()[0]
    published = get("mos")(problem).scores
    equal = get("mos")(problem, **dict(equal_cue_spec(MatcherSpec("mos")).options)).scores
    assert not np.allclose(published, equal, rtol=0, atol=1e-6)
    # no features and no metric term: the equal-cue switch alone changes nothing
    bare = Problem(problem.points1, problem.points2)
    assert np.array_equal(get("mos")(bare).scores, get("mos")(bare, appearance=True).scores)


def test_without_features_the_appearance_factor_changes_nothing():
    problem = _views()[0]
    bare = Problem(problem.points1, problem.points2)
    for name in ("sm", "rrwhm"):
        plain = get(name)(bare).scores
        assert np.array_equal(plain, get(name)(bare, appearance=True).scores)


@pytest.mark.parametrize("bad", [0, -1.0, float("nan"), float("inf"), "0.1", True])
def test_a_bad_distance_scale_is_refused_naming_the_option(bad):
    with pytest.raises(ValueError, match="distance_scale"):
        get("maximin")(_views()[0], distance_scale=bad)


def test_the_equal_cue_grids_have_the_equal_budget_and_search_the_metric_width():
    for name in PAPER_EIGHT:
        base = equal_cue_spec(MatcherSpec(name))
        candidates = candidates_of(base)
        assert len(candidates) == 8, name
        for spec, _ in candidates:
            options = dict(spec.options)
            assert all(options.get(k) is not None for k in EQUAL_CUE_OPTIONS[name]), name
    widths = {
        dict(s.options)["distance_scale"]
        for s, _ in candidates_of(equal_cue_spec(MatcherSpec("maximin")))
    }
    assert len(widths) == 5
    assert search_space_of(MatcherSpec("maximin")) is None  # as published: its own grid


@pytest.fixture
def world(monkeypatch):
    datasets = {"data/cad": make_dataset(100, 4), "data/cad-val": make_dataset(900, 3)}
    monkeypatch.setattr(tasks, "open_dataset", lambda path: datasets[path])
    return datasets


def test_the_equal_cue_protocol_is_tuned_on_validation_and_writes_its_own_table(world, tmp_path):
    out = tmp_path / "out"
    runner = Runner(ResultCache(tmp_path / "cache"), SerialExecutor(), version="v", progress=False)
    entry = open_entry("data/cad", "data/cad-val")
    specs = [MatcherSpec("maximin"), MatcherSpec("sm"), MatcherSpec("none")]
    evaluate([entry], specs, [0], runner, out, tune=True, protocol="equal_cues")
    per_pair = pd.read_csv(out / "metrics_per_pair_equal_cues.csv")
    assert set(per_pair["matcher"]) == {"maximin", "sm", "none"}  # rows keep their labels
    params = set(per_pair.loc[per_pair["matcher"] == "maximin", "params"])
    assert all('"distance_scale"' in p for p in params)
    assert set(per_pair.loc[per_pair["matcher"] == "sm", "params"]) <= {
        p for p in set(per_pair["params"]) if '"appearance":true' in p
    }
    tuning = pd.read_csv(out / "tuning_equal_cues.csv")
    assert set(tuning["matcher"]) == {"maximin", "sm"}
    assert not (out / "metrics_per_pair.csv").exists()  # the as-published files are untouched
    write_tables(out)
    assert (out / "table1_equal_cues.md").is_file()
    assert (out / "paired_differences_equal_cues.csv").is_file()
