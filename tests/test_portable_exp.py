"""The tensor values' exp: the same bits from numpy and from the compiled loop, within 1 ulp of
numpy's exp, 0 below its floor."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from matchers.core import portable_exp
from matchers.core.portable_exp import LOW, decay, exp_nonpositive


def _both(x: np.ndarray, divisor: float) -> tuple[np.ndarray, np.ndarray]:
    compiled = np.empty_like(x)
    decay(x, divisor, compiled)
    return compiled, exp_nonpositive(-x / divisor)


@pytest.mark.parametrize("divisor", [0.5, 1.0, 0.3711])
def test_compiled_and_numpy_give_the_same_bits_within_an_ulp_of_numpy_exp(divisor):
    rng = np.random.default_rng(1)
    x = np.concatenate([rng.uniform(0, 6, 50_000), rng.uniform(0, 700, 5_000), [0.0, 5e-324]])
    compiled, by_numpy = _both(x, divisor)
    assert np.array_equal(compiled, by_numpy)
    want = np.exp(-x / divisor)
    normal = want > 1e-300
    assert np.all(np.abs(compiled - want)[normal] <= np.spacing(want[normal]))
    assert compiled[-2] == 1.0


@settings(max_examples=200, deadline=None)
@given(st.floats(min_value=0.0, max_value=1e6, allow_nan=False))
def test_any_non_negative_distance(value):
    x = np.array([value])
    compiled, by_numpy = _both(x, 0.5)
    assert np.array_equal(compiled, by_numpy)
    assert 0.0 <= compiled[0] <= 1.0
    if -value / 0.5 <= LOW:
        assert compiled[0] == 0.0


def test_without_numba_the_numpy_function_serves(monkeypatch):
    x = np.linspace(0, 10, 101)
    compiled = np.empty_like(x)
    decay(x, 0.7, compiled)
    monkeypatch.setattr(portable_exp, "_exp_into_jit", None)
    plain = np.empty_like(x)
    decay(x, 0.7, plain)
    assert np.array_equal(compiled, plain)
