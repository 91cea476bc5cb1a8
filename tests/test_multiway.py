"""Multi-way matching: the fusion registry (matchers.fusion) and its metrics
(eval.protocol.multiway_metrics) — planted universes recovered, cycle consistency, counts,
refusals, the memory budget and fuzzing over every registered fusion."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from eval.protocol.multiway_metrics import multiway_counts, summarise_counts
from matchers import ProblemTooLarge
from matchers.core.memory_budget import BUDGET_ENV
from matchers.fusion import (
    PairwiseEvidence,
    available_fusions,
    get_fusion,
    register_fusion,
    registry,
)
from matchers.fusion.universe import components

FUSIONS = available_fusions()
FUSED = [name for name in FUSIONS if name != "independent"]


def planted(seed: int, n_views: int, objects: int, score: float = 0.9):
    """Views that each see a random subset of ``objects`` (in a random order), their true
    object per detection, and the exact pairwise matches between every two views."""
    rng = np.random.default_rng(seed)
    views = [rng.permutation(objects)[: rng.integers(2, objects + 1)] for _ in range(n_views)]
    scores, matches = {}, {}
    for i in range(n_views):
        for j in range(i + 1, n_views):
            where = {o: r for r, o in enumerate(views[j])}
            m = np.array([(r, where[o]) for r, o in enumerate(views[i]) if o in where])
            m = m.reshape(-1, 2).astype(np.int64)
            s = rng.uniform(0, 0.3, (len(views[i]), len(views[j])))
            s[m[:, 0], m[:, 1]] = score
            scores[(i, j)], matches[(i, j)] = s, m
    evidence = PairwiseEvidence(tuple(len(v) for v in views), scores, matches)
    return evidence, views


def as_set(pairs: np.ndarray) -> set[tuple[int, int]]:
    return {(int(a), int(b)) for a, b in pairs}


@pytest.mark.parametrize("name", FUSIONS)
@pytest.mark.parametrize("seed,n_views,objects", [(0, 2, 6), (1, 3, 8), (2, 4, 10), (3, 6, 12)])
def test_each_fusion_recovers_a_planted_universe_exactly(name, seed, n_views, objects):
    evidence, views = planted(seed, n_views, objects)
    universe = get_fusion(name)(evidence)
    for key, truth in evidence.matches.items():
        assert as_set(universe.pairs[key]) == as_set(truth), (name, key)
    present = len(set(np.concatenate(views)))
    assert universe.count == present
    counts = multiway_counts(universe, views)
    metrics = summarise_counts([counts])
    assert metrics["f1_pooled"] == 1.0 and metrics["count_error"] == 0.0
    assert metrics["cluster_precision"] == 1.0 and metrics["cluster_recall"] == 1.0
    assert metrics["cycle_violation_rate"] == 0.0


def inconsistent() -> tuple[PairwiseEvidence, list[np.ndarray]]:
    """Three views of the same 3 objects in the same order: A-B and B-C right, A-C wrong for
    two objects (swapped) — every chain through B disagrees with A-C there."""
    right = np.array([[0, 0], [1, 1], [2, 2]])
    swapped = np.array([[0, 1], [1, 0], [2, 2]])
    scores = {key: np.full((3, 3), 0.5) for key in ((0, 1), (1, 2), (0, 2))}
    scores[(0, 2)][1, 0] = scores[(0, 2)][0, 1] = 0.1  # the wrong pairs are the weak ones
    matches = {(0, 1): right, (1, 2): right, (0, 2): swapped}
    truth = [np.arange(3)] * 3
    return PairwiseEvidence((3, 3, 3), scores, matches), truth


def test_an_inconsistent_input_violates_cycles_and_every_fusion_removes_them():
    evidence, truth = inconsistent()
    alone = summarise_counts([multiway_counts(get_fusion("independent")(evidence), truth)])
    # chains: 6 ordered triples x 3 detections; the two swapped objects break 2 of 3 per triple
    assert alone["cycle_violation_rate"] == pytest.approx(4 / 6)
    for name in FUSED:
        universe = get_fusion(name)(evidence)
        assert universe.fused
        metrics = summarise_counts([multiway_counts(universe, truth)])
        assert metrics["cycle_violation_rate"] == 0.0, name
    fixed = summarise_counts([multiway_counts(get_fusion("transitive")(evidence), truth)])
    assert fixed["f1_pooled"] == 1.0  # the strong chains win, the weak swapped pairs go


def test_count_error_is_exact_on_planted_cases():
    evidence, views = planted(7, 4, 9)
    present = len(set(np.concatenate(views)))
    bare = PairwiseEvidence(evidence.sizes)  # no matches: every detection its own object
    universe = get_fusion("independent")(bare)
    counts = multiway_counts(universe, views)
    assert counts.objects_estimated == evidence.total and counts.objects_present == present
    expected = (evidence.total - present) / present
    assert summarise_counts([counts])["count_error"] == pytest.approx(expected)
    assert summarise_counts([counts])["recall_pooled"] == 0.0


def test_independent_keeps_the_pairs_and_counts_by_the_fusions_clustering_rule():
    evidence, truth = inconsistent()
    universe = get_fusion("independent")(evidence)
    assert not universe.fused
    for key, pairs in evidence.matches.items():
        assert as_set(universe.pairs[key]) == as_set(pairs)
    # connected components chain objects 0 and 1 into one (2 objects); the greedy closure with
    # one detection per view keeps the strong chains and drops the weak swapped pairs: 3
    assert len(np.unique(components(evidence))) == 2
    assert universe.count == 3
    clustered = get_fusion("transitive")(evidence)
    for mine, rule in zip(universe.labels, clustered.labels, strict=True):
        np.testing.assert_array_equal(mine, rule)
    assert summarise_counts([multiway_counts(universe, truth)])["count_error"] == 0.0


def test_independent_never_puts_two_detections_of_a_view_in_one_object():
    # A0-B0 (0.9), B0-C0 (0.8), A1-C0 (0.3): the match graph is one component holding both of
    # view A's detections; the rule drops the weakest match that would join them
    evidence = PairwiseEvidence(
        (2, 1, 1),
        {
            (0, 1): np.array([[0.9], [0.1]]),
            (1, 2): np.array([[0.8]]),
            (0, 2): np.array([[0.1], [0.3]]),
        },
        {(0, 1): [[0, 0]], (1, 2): [[0, 0]], (0, 2): [[1, 0]]},
    )
    truth = [np.array([0, 1]), np.array([0]), np.array([0])]
    assert len(np.unique(components(evidence))) == 1  # what components would count
    universe = get_fusion("independent")(evidence)
    assert universe.count == 2 and universe.labels[0][0] != universe.labels[0][1]
    assert universe.labels[0][0] == universe.labels[1][0] == universe.labels[2][0]
    assert as_set(universe.pairs[(0, 2)]) == {(1, 0)}  # its pairs are still the input's
    counts = multiway_counts(universe, truth)
    assert counts.objects_estimated == counts.objects_present == 2
    assert counts.violations > 0  # the raw pairs still break a cycle


@pytest.mark.parametrize(
    "kwargs,message",
    [
        ({"sizes": (2, 2), "matches": {(0, 1): [[0, 0], [1, 0]]}}, "matched twice"),
        ({"sizes": (2, 2), "matches": {(0, 1): [[0, 5]]}}, "outside"),
        ({"sizes": (2, 2), "matches": {(1, 0): [[0, 0]]}}, "views i < j"),
        ({"sizes": (2, 2), "scores": {(0, 1): np.ones((3, 2))}}, "shape"),
        ({"sizes": (2, 2), "scores": {(0, 1): np.full((2, 2), 2.0)}}, r"\[0, 1\]"),
        ({"sizes": (2, -1)}, "non-negative"),
    ],
)
def test_malformed_evidence_is_refused_naming_the_pair(kwargs, message):
    with pytest.raises(ValueError, match=message):
        PairwiseEvidence(**kwargs)


def test_the_registry_lists_registers_and_refuses(monkeypatch):
    assert {"independent", "spectral", "clear", "transitive"} <= set(FUSIONS)
    assert registry.ENTRY_POINT_GROUP == "cadsim.fusions"
    monkeypatch.setattr(registry, "_registered", {})
    with pytest.raises(ValueError, match="already exists"):
        register_fusion("spectral", get_fusion("clear"))
    register_fusion("mine", get_fusion("transitive"))
    assert "mine" in available_fusions() and get_fusion("mine") is get_fusion("transitive")
    with pytest.raises(ValueError, match="unknown fusion 'nope'"):
        get_fusion("nope")
    assert get_fusion("matchers.fusion.clear:clear") is get_fusion("clear")
    with pytest.raises(ValueError, match="imports but has no 'missing'"):
        get_fusion("matchers.fusion.clear:missing")


@pytest.mark.parametrize("name", FUSIONS)
def test_every_fusion_carries_a_memory_estimate_and_is_held_to_the_budget(name, monkeypatch):
    fn = get_fusion(name)
    assert callable(getattr(fn, "memory_bytes", None)), name
    big = PairwiseEvidence((3000, 3000, 3000))  # 9,000 detections, no matches
    if fn.memory_bytes(big) > 64 * 2**20:
        monkeypatch.setenv(BUDGET_ENV, "64")
        with pytest.raises(ProblemTooLarge, match="64 MB budget"):
            fn(big)


@st.composite
def evidences(draw):
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    sizes = tuple(draw(st.lists(st.integers(0, 6), min_size=0, max_size=6)))
    scores, matches = {}, {}
    for i in range(len(sizes)):
        for j in range(i + 1, len(sizes)):
            if draw(st.booleans()):
                continue  # a pair of views nobody matched
            k = int(rng.integers(0, min(sizes[i], sizes[j]) + 1))
            rows = rng.permutation(sizes[i])[:k]
            cols = rng.permutation(sizes[j])[:k]
            matches[(i, j)] = np.stack([rows, cols], axis=1)
            scores[(i, j)] = np.round(rng.random((sizes[i], sizes[j])), draw(st.integers(0, 3)))
    return PairwiseEvidence(sizes, scores, matches)


@pytest.mark.parametrize("name", FUSIONS)
@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(evidence=evidences())
def test_fuzz_every_fusion_returns_a_valid_universe(name, evidence):
    universe = get_fusion(name)(evidence)
    assert [len(lab) for lab in universe.labels] == list(evidence.sizes)
    flat = np.concatenate(universe.labels) if universe.labels else np.empty(0, int)
    assert flat.size == 0 or (flat.min() >= 0 and flat.max() < universe.count)
    assert universe.count == len(np.unique(flat))
    for (i, j), pairs in universe.pairs.items():
        assert len(set(pairs[:, 0])) == len(pairs) == len(set(pairs[:, 1]))
        assert i < j < len(evidence.sizes)
    if universe.fused:
        for view in universe.labels:
            assert len(np.unique(view)) == len(view)  # one detection per view per object
        truth = [np.arange(s) + 100 * v for v, s in enumerate(evidence.sizes)]
        assert multiway_counts(universe, truth).violations == 0
