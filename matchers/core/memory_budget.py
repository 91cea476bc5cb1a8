"""The per-process memory budget of a matcher call, checked before anything large is allocated.

Defaults keep every matcher bounded (the tensor entry cap, the sparse pairwise affinity), but an
explicit option can ask for more (``max_tensor_entries=None``, ``affinity_neighbours=None``, huge
``triangles``/``neighbours``, a view of thousands of objects). Such a call is refused with
:class:`ProblemTooLarge` — a ``ValueError`` naming the sizes, the budget and the option to change —
instead of exhausting the machine. The budget is ``$CADSIM_MAX_MATCHER_MB`` megabytes per process
(default 4096: one process per core on a 2-core, 24 GiB machine leaves more than half free).
"""

from __future__ import annotations

import functools
import os
from collections.abc import Callable

BUDGET_ENV = "CADSIM_MAX_MATCHER_MB"
DEFAULT_BUDGET_MB = 4096


class ProblemTooLarge(ValueError):
    """A matcher call whose working memory would exceed the per-process budget."""


def budget_mb() -> float:
    """The budget in MB: ``$CADSIM_MAX_MATCHER_MB`` (a positive number) or 4096."""
    text = os.environ.get(BUDGET_ENV, "").strip()
    if not text:
        return float(DEFAULT_BUDGET_MB)
    try:
        value = float(text)
    except ValueError:
        value = float("nan")
    if not (value > 0 and value < float("inf")):
        raise ValueError(f"${BUDGET_ENV}: expected a positive number of megabytes, got {text!r}")
    return value


def check_memory(what: str, n_bytes: float, option: str) -> None:
    """Raise :class:`ProblemTooLarge` if ``n_bytes`` (an estimate of the working memory of
    ``what``) exceeds the budget; ``option`` says what the caller can change.

    >>> check_memory("pairwise affinity (10 x 10 objects)", 1e6, "affinity_neighbours")
    """
    limit = budget_mb()
    need = float(n_bytes) / 2**20
    if need > limit:
        raise ProblemTooLarge(
            f"{what} needs about {need:,.0f} MB, over the {limit:,.0f} MB budget per process; "
            f"lower {option}, or raise ${BUDGET_ENV}"
        )


def budgeted(estimate: Callable[..., float], option: str) -> Callable:
    """Decorator: the matcher checks ``estimate(problem, **options)`` (bytes) against the budget
    before it runs, and carries the estimate as ``memory_bytes`` (a third-party matcher registered
    with ``register(..., memory=...)`` gets the same). ``option`` says what to change.

    >>> @budgeted(lambda problem, **options: 8.0 * problem.n1 * problem.n2, "the view size")
    ... def my_matcher(problem, seed=None, threshold=None): ...
    """

    def wrap(fn: Callable) -> Callable:
        @functools.wraps(fn)
        def call(problem, *args, **options):
            n1, n2 = getattr(problem, "n1", None), getattr(problem, "n2", None)
            if n1 is not None and n2 is not None:
                check_memory(
                    f"{getattr(fn, '__name__', 'matcher')} ({n1} x {n2} objects)",
                    estimate(problem, **options),
                    option,
                )
            return fn(problem, *args, **options)

        call.memory_bytes = estimate
        return call

    return wrap
