"""pygmtools as an oracle: our sm and rrwm give its assignment on the same affinity matrix."""

from __future__ import annotations

import numpy as np
import pygmtools as pygm
import pytest

from matchers import Problem, get
from matchers.blocks.pairwise import pairwise_affinity
from matchers.core.indexing import to_column_major

pygm.set_backend("numpy")

# pygmtools' RRWM weighting, passed explicitly: 0.2 on the reweighted jump, beta 30, 50 iterations.
PYGM_RRWM = {"alpha": 0.2, "beta": 30, "max_iter": 50}
OURS_AS_PYGM = {"jump": 0.2, "beta": 30, "max_iter": 50}


def _problems(count: int, noise: float, extra: tuple[int, int], seed: int):
    """Random 2-D problems: n points, view 2 = noisy permuted copy plus `extra` outliers."""
    rng = np.random.default_rng(seed)
    for _ in range(count):
        n = int(rng.integers(5, 15))
        m = n + int(rng.integers(extra[0], extra[1] + 1))
        p1 = rng.uniform(0.0, 3.0, (n, 2))
        perm = rng.permutation(m)
        p2 = np.concatenate([p1 + rng.normal(0.0, noise, p1.shape), rng.uniform(0, 3, (m - n, 2))])
        yield Problem(p1, p2[perm]), np.argsort(perm)[:n]


def _ours(matching, n: int, m: int) -> np.ndarray:
    x = np.zeros((n, m))
    x[matching.pairs[:, 0], matching.pairs[:, 1]] = 1
    return x


def _agreement(solver: str, count: int, noise: float, extra: tuple[int, int], seed: int):
    same, errors = 0, 0
    for problem, truth in _problems(count, noise, extra, seed):
        n, m = problem.n1, problem.n2
        k_ours = pairwise_affinity(problem)
        k_pygm = to_column_major(k_ours, n, m)
        if solver == "sm":
            ref = pygm.hungarian(pygm.sm(k_pygm, n, m), n, m)
            got = _ours(get("sm")(problem, affinity=k_ours), n, m)
        else:
            ref = pygm.hungarian(pygm.rrwm(k_pygm, n, m, **PYGM_RRWM), n, m)
            got = _ours(get("rrwm")(problem, affinity=k_ours, **OURS_AS_PYGM), n, m)
        same += np.array_equal(ref, got)
        errors += int(np.sum(ref.argmax(1) != truth))
    return same, errors


@pytest.mark.parametrize("extra", [(0, 0), (1, 3)], ids=["square", "with-outliers"])
def test_sm_matches_pygmtools(extra):
    same, errors = _agreement("sm", 15, 0.1, extra, seed=11)
    assert same == 15
    assert errors > 0  # the oracle makes mistakes here, so agreement is not just both being right


def test_rrwm_matches_pygmtools_on_square_problems():
    same, errors = _agreement("rrwm", 15, 0.1, (0, 0), seed=12)
    assert same == 15
    assert errors > 0


def test_index_conventions_round_trip():
    # a = i*m + j (ours) vs a = j*n + i (pygmtools): the same entry under both layouts
    problem = next(_problems(1, 0.1, (2, 2), seed=3))[0]
    n, m = problem.n1, problem.n2
    k = pairwise_affinity(problem)
    kc = to_column_major(k, n, m)
    i, j, p, q = 1, 2, 3, 0
    assert kc[j * n + i, q * n + p] == k[i * m + j, p * m + q]
