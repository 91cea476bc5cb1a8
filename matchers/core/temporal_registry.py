"""Name -> temporal matcher: matchers that take a whole
:class:`~matchers.core.sequence_problem.SequenceProblem` and return one
:class:`~matchers.core.matching.Matching` per frame (issue 41).

A temporal matcher is any callable ``matcher(seq, seed=0, threshold=None, **options) ->
list[Matching]`` (one per frame, in time order; frame t may use frames <= t only). They are kept
apart from the two-view :func:`matchers.core.registry.available` on purpose: everything that
runs "all matchers" on one frame pair (the evaluation, the fuzz and budget tests) would
otherwise hand them a Problem.

Names: the built-ins ``temporal_pose`` and ``trajectory_pose``, :func:`register_temporal`ed names, and the family
``windowed:<name>`` — any two-view matcher ``<name>`` (built-in, registered, entry point or
import path) lifted to a window of frames along the agents' own tracks
(:mod:`matchers.temporal.windowed`), resolved through the ``families`` hook of
:func:`matchers.core.named_lookup.lookup`.
"""

from __future__ import annotations

from collections.abc import Callable

from matchers.core.named_lookup import load, lookup
from matchers.core.search_spaces import TEMPORAL_SEARCH_SPACES, check_search_space

TemporalMatcher = Callable[..., list]

_BUILTIN: dict[str, str] = {
    "temporal_pose": "matchers.temporal.temporal_pose:temporal_pose",
    "trajectory_pose": "matchers.temporal.trajectory_pose:trajectory_pose",
}
_FAMILIES: dict[str, str] = {"windowed": "matchers.temporal.windowed:windowed"}
_registered: dict[str, TemporalMatcher] = {}


def _family(prefix: str) -> Callable[[str], TemporalMatcher]:
    return lambda rest: load(_FAMILIES[prefix])(rest)


def register_temporal(name: str, fn: TemporalMatcher, *, replace: bool = False) -> None:
    """Make ``fn`` available as ``get_temporal(name)``; a taken name raises ValueError unless
    ``replace=True``. Names with a family prefix (``windowed:``) are the family's."""
    if not isinstance(name, str) or not name:
        raise ValueError(f"name: expected a non-empty string, got {name!r}")
    if not callable(fn):
        raise TypeError(f"fn: expected a callable temporal matcher, got {type(fn).__name__}")
    if name.partition(":")[0] in _FAMILIES:
        raise ValueError(f"name: {name!r} belongs to a family of temporal matchers")
    if (name in _registered or name in _BUILTIN) and not replace:
        raise ValueError(f"name: temporal matcher {name!r} already exists; pass replace=True")
    _registered[name] = fn


def get_temporal(name: str) -> TemporalMatcher:
    """The temporal matcher called ``name``: registered, built-in, ``windowed:<two-view name>``,
    or a ``package.module:function`` import path. ValueError naming an unknown one.

    >>> get_temporal("windowed:sm").__name__
    'windowed:sm'
    """
    return lookup(
        name,
        "temporal matcher",
        _registered,
        _BUILTIN,
        {},
        temporal_available,
        {prefix: _family(prefix) for prefix in _FAMILIES},
    )


def temporal_available() -> list[str]:
    """Sorted names of the temporal matchers other than the ``windowed:`` family (which has one
    member per two-view matcher, :func:`matchers.core.registry.available`)."""
    return sorted(set(_BUILTIN) | set(_registered))


def temporal_search_space(name: str) -> list[dict]:
    """The tuning grid of temporal matcher ``name`` (1 to 12 option dicts, ``{}`` = defaults):
    ``windowed:<base>`` searches ``<base>``'s two-view grid
    (:func:`matchers.core.registry.search_space`) unless
    :data:`~matchers.core.search_spaces.TEMPORAL_SEARCH_SPACES` names it (``windowed:pose_refine``:
    with the partner hysteresis ``margin``, issue 61), a built-in its entry in
    :data:`~matchers.core.search_spaces.TEMPORAL_SEARCH_SPACES`, any other its callable's
    ``search_space`` attribute (none: ``[{}]``). ``window`` is never a grid option (it is the
    table's axis): a grid that sets it raises ValueError. Returns a fresh copy.

    >>> len(temporal_search_space("temporal_pose"))
    8
    """
    prefix, _, rest = name.partition(":")
    if name in TEMPORAL_SEARCH_SPACES and name not in _registered:  # e.g. windowed:pose_refine
        space = TEMPORAL_SEARCH_SPACES[name]
    elif prefix in _FAMILIES and rest:
        from matchers.core.registry import search_space

        space = search_space(rest)
    elif name in _BUILTIN and name not in _registered:
        space = TEMPORAL_SEARCH_SPACES.get(name, [{}])
    else:
        fn = get_temporal(name)
        space = check_search_space(getattr(fn, "search_space", None) or [{}], name)
    if any("window" in config for config in space):
        raise ValueError(
            f"search_space of temporal matcher {name!r}: sets 'window', which is the table's "
            "axis (W), not a tuned option"
        )
    return [dict(config) for config in space]
