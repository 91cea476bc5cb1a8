"""Argument checks every built-in matcher shares (problem type, seed, numeric options)."""

from __future__ import annotations

import numpy as np

from matchers.core.problem import Problem


def check_problem(problem: object) -> Problem:
    if not isinstance(problem, Problem):
        raise TypeError(f"problem: expected a matchers.Problem, got {type(problem).__name__}")
    return problem


def rng_from_seed(seed: int | None) -> np.random.Generator:
    """numpy Generator for ``seed`` (an int, or None for OS entropy)."""
    if seed is not None and (isinstance(seed, bool) or not isinstance(seed, int | np.integer)):
        raise ValueError(f"seed: expected an int or None, got {seed!r}")
    return np.random.default_rng(seed)


def check_range(name: str, value: float, low: float, high: float, open_low: bool = False) -> float:
    """``value`` as float if low <= value <= high (low < value if open_low), else ValueError."""
    try:
        value = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name}: expected a number, got {value!r}") from None
    below = value <= low if open_low else value < low
    if not np.isfinite(value) or below or value > high:
        bracket = "(" if open_low else "["
        raise ValueError(f"{name}: expected a number in {bracket}{low}, {high}], got {value!r}")
    return value


def check_count(name: str, value: int) -> int:
    if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < 1:
        raise ValueError(f"{name}: expected a positive integer, got {value!r}")
    return int(value)
