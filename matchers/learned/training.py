"""Training the learned matchers' classifiers: gradient-boosted trees (LightGBM) on the features
of every candidate match of every training problem, labelled by the ground truth.

Deterministic: one thread, fixed seeds, row-wise histograms, no bagging or feature sampling, so
that the same problems give the same trees — and the same model-file bytes — on every machine.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence

import numpy as np

from matchers.core.problem import Problem
from matchers.learned.features import feature_names, pair_features
from matchers.learned.model import VARIANTS, LearnedModel

ROUNDS = 200
PARAMS = {
    "objective": "binary",
    "learning_rate": 0.05,
    "num_leaves": 15,
    "min_data_in_leaf": 20,
    "lambda_l2": 1.0,
    "max_bin": 255,
    "num_threads": 1,
    "deterministic": True,
    "force_row_wise": True,
    "seed": 0,
    "verbosity": -1,
}


def labels(problem: Problem, truth: np.ndarray) -> np.ndarray:
    """(n * m,) 1 for the ground-truth matches (``truth``: (g, 2) int pairs (i, j)), else 0."""
    y = np.zeros(problem.n1 * problem.n2)
    truth = np.asarray(truth, dtype=int).reshape(-1, 2)
    y[truth[:, 0] * problem.n2 + truth[:, 1]] = 1.0
    return y


def training_table(
    examples: Iterable[tuple[Problem, np.ndarray]], prior: bool
) -> tuple[np.ndarray, np.ndarray]:
    """(X, y): the features and labels of every candidate match of every (problem, truth)."""
    xs, ys = [], []
    for problem, truth in examples:
        xs.append(pair_features(problem, prior))
        ys.append(labels(problem, truth))
    width = len(feature_names(prior))
    if not xs:
        return np.zeros((0, width)), np.zeros(0)
    return np.vstack(xs), np.concatenate(ys)


def fit_booster(x: np.ndarray, y: np.ndarray, prior: bool, rounds: int = ROUNDS) -> str:
    """LightGBM's text model of a binary classifier trained on (x, y); ValueError without
    examples of both classes."""
    import lightgbm

    positives = int(y.sum())
    if positives == 0 or positives == len(y):
        raise ValueError(
            f"training data: {len(y)} candidate matches of which {positives} true; "
            "needs both true and false matches"
        )
    data = lightgbm.Dataset(
        x, y, feature_name=feature_names(prior), free_raw_data=True, params={"verbosity": -1}
    )
    booster = lightgbm.train(PARAMS, data, num_boost_round=rounds)
    return booster.model_to_string(num_iteration=-1)


def train_model(
    examples: Sequence[tuple[Problem, np.ndarray]],
    training: dict,
    variants: Sequence[str] = tuple(VARIANTS),
    rounds: int = ROUNDS,
) -> LearnedModel:
    """A model with one classifier per variant trained on ``examples`` ((problem, truth) pairs);
    ``training`` (the datasets' names and checksums) is recorded in it, with the row counts and
    the parameters."""
    boosters, rows, positives = {}, {}, {}
    # the plain variant's features are the first columns of the prior variant's: computed once
    x_all, y = training_table(examples, any(VARIANTS[v] for v in variants))
    for variant in variants:
        x = x_all[:, : len(feature_names(VARIANTS[variant]))]
        boosters[variant] = fit_booster(x, y, VARIANTS[variant], rounds)
        rows[variant], positives[variant] = int(len(y)), int(y.sum())
    record = dict(training) | {
        "rows": rows,
        "positives": positives,
        "params": dict(PARAMS),
        "rounds": rounds,
    }
    return LearnedModel(boosters, record)
