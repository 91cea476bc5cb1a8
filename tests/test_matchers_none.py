"""``none``: the matcher that declares no match."""

import numpy as np
import pytest

from matchers import Problem, available, get, search_space


@pytest.mark.parametrize("threshold", [None, 0.0, -1.0, 0.5])
@pytest.mark.parametrize(("n", "m"), [(0, 0), (0, 3), (4, 0), (3, 5)])
def test_none_declares_nothing_whatever_the_threshold(n, m, threshold):
    rng = np.random.default_rng(n * 10 + m)
    matching = get("none")(
        Problem(rng.normal(size=(n, 3)), rng.normal(size=(m, 3))), threshold=threshold
    )
    assert matching.pairs.shape == (0, 2) and matching.pairs.dtype.kind == "i"
    assert matching.scores.shape == (n, m) and not matching.scores.any()
    assert matching.name == "none"


def test_none_is_a_registered_builtin_without_a_grid():
    assert "none" in available()
    assert search_space("none") == [{}]


def test_none_checks_its_arguments():
    problem = Problem(np.zeros((2, 3)), np.zeros((2, 3)))
    with pytest.raises(ValueError, match="threshold"):
        get("none")(problem, threshold=float("nan"))
    with pytest.raises(ValueError, match="seed"):
        get("none")(problem, seed=1.5)
    with pytest.raises(TypeError):
        get("none")(problem, sigma=1.0)
