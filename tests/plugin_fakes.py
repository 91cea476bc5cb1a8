"""Hostile plug-ins for tests/test_plugin_guard.py: matchers and fusions that break their
contract one way each, named by import path (``plugin_fakes:none``) so that worker processes
import them too."""

from __future__ import annotations

import threading

import numpy as np

from matchers import Matching
from matchers.core.discretise import discretise
from matchers.fusion.universe import Universe, from_labels


def _scores(problem) -> np.ndarray:
    return np.full((problem.n1, problem.n2), 0.5)


def _matching(problem, pairs=None, scores=None, **fields) -> Matching:
    scores = _scores(problem) if scores is None else scores
    pairs = discretise(_scores(problem)) if pairs is None else pairs
    return Matching(pairs, scores, "fake", **fields)


def good(problem, seed=0, threshold=None):
    return _matching(problem, time_s=1e-3)


def raises(problem, seed=0, threshold=None):
    return 1 / 0


def none(problem, seed=0, threshold=None):
    return None


def a_tuple(problem, seed=0, threshold=None):
    return (np.zeros((0, 2), int), _scores(problem))


def flat_pairs(problem, seed=0, threshold=None):
    return _matching(problem, pairs=np.array([0, 0, 1, 1]))


def float_pairs(problem, seed=0, threshold=None):
    return _matching(problem, pairs=np.array([[0.0, 0.0], [1.0, 1.0]]))


def scores_of_another_shape(problem, seed=0, threshold=None):
    return _matching(problem, scores=np.full((problem.n1 + 1, problem.n2), 0.5))


def flat_scores(problem, seed=0, threshold=None):
    return _matching(problem, scores=np.full(problem.n1 * problem.n2, 0.5))


def pair_outside(problem, seed=0, threshold=None):
    return _matching(problem, pairs=np.array([[0, 0], [problem.n1, 1]]))


def negative_index(problem, seed=0, threshold=None):
    return _matching(problem, pairs=np.array([[0, -1]]))


def repeated_i(problem, seed=0, threshold=None):
    return _matching(problem, pairs=np.array([[0, 0], [0, 1]]))


def repeated_j(problem, seed=0, threshold=None):
    return _matching(problem, pairs=np.array([[0, 1], [2, 1]]))


def nan_scores(problem, seed=0, threshold=None):
    scores = _scores(problem)
    scores[1, 2] = np.nan
    return _matching(problem, scores=scores)


def inf_scores(problem, seed=0, threshold=None):
    scores = _scores(problem)
    scores[0, 0] = np.inf
    return _matching(problem, scores=scores)


def scores_above_one(problem, seed=0, threshold=None):
    return _matching(problem, scores=_scores(problem) * 3)


def negative_time(problem, seed=0, threshold=None):
    return _matching(problem, time_s=-1.0)


def nan_time(problem, seed=0, threshold=None):
    return _matching(problem, time_s=float("nan"))


def no_iterations(problem, seed=0, threshold=None):
    return _matching(problem, iterations=None)


_forever = threading.Event()  # never set


def sleeps_forever(problem, seed=0, threshold=None):
    _forever.wait()


def spins_forever(problem, seed=0, threshold=None):
    while True:
        pass


NOT_CALLABLE = 42


# --- fusions: fusion(evidence) -> Universe ---


def _transitive(evidence) -> Universe:
    from matchers.fusion.transitive import transitive

    return transitive(evidence)


def _replaced(evidence, **fields) -> Universe:
    u = _transitive(evidence)
    values = dict(vars(u)) | fields
    return Universe(**values)


def fusion_good(evidence):
    return _transitive(evidence)


def fusion_raises(evidence):
    raise KeyError("no such view")


def fusion_none(evidence):
    return None


def fusion_labels_of_another_shape(evidence):
    u = _transitive(evidence)
    return _replaced(evidence, labels=(u.labels[0][:-1], *u.labels[1:]))


def fusion_too_few_views(evidence):
    return _replaced(evidence, labels=_transitive(evidence).labels[:-1])


def fusion_label_outside(evidence):
    u = _transitive(evidence)
    return _replaced(evidence, labels=(u.labels[0] + u.count, *u.labels[1:]))


def fusion_wrong_count(evidence):
    return _replaced(evidence, count=_transitive(evidence).count + 3)


def fusion_two_in_one_view(evidence):
    u = _transitive(evidence)
    first = u.labels[0].copy()
    first[1] = first[0]
    flat = np.concatenate([first, *u.labels[1:]])
    return _replaced(evidence, labels=(first, *u.labels[1:]), count=len(np.unique(flat)))


def fusion_pair_outside(evidence):
    pairs = dict(_transitive(evidence).pairs)
    pairs[(0, 1)] = np.array([[evidence.sizes[0], 0]])
    return _replaced(evidence, pairs=pairs, fused=False)


def fusion_repeated_pairs(evidence):
    pairs = dict(_transitive(evidence).pairs)
    pairs[(0, 1)] = np.array([[0, 0], [0, 1]])
    return _replaced(evidence, pairs=pairs, fused=False)


def fusion_bad_key(evidence):
    pairs = dict(_transitive(evidence).pairs)
    pairs[(1, 0)] = pairs.pop((0, 1))
    return _replaced(evidence, pairs=pairs)


def fusion_inconsistent(evidence):
    u = _transitive(evidence)
    pairs = dict(u.pairs)
    pairs[(0, 1)] = pairs[(0, 1)][1:]  # fused, but a pair its labels imply is missing
    return _replaced(evidence, pairs=pairs)


def fusion_nan_time(evidence):
    return _replaced(evidence, time_s=float("nan"))


def fusion_negative_time(evidence):
    return _replaced(evidence, time_s=-0.5)


def fusion_sleeps_forever(evidence):
    _forever.wait()


def fusion_from_labels(evidence):
    """A correct plug-in built with the public helper."""
    import time

    return from_labels(evidence, np.arange(evidence.total), "singletons", time.perf_counter())
