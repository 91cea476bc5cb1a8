"""Name -> matcher registry: the built-ins, :func:`register`, and the ``cadsim.matchers``
entry-point group (third-party packages), loaded lazily on the first :func:`get`/:func:`available`.

A matcher is any callable ``matcher(problem, seed=0, threshold=None, **options) -> Matching``.
A matcher that needs optional Problem fields (the localisation prior) names them in a
``requires`` attribute, :func:`requires`; one whose result does not depend on its seed says so
with ``deterministic = True``, :func:`deterministic`. Each name also has a tuning grid, :func:`search_space`: given to :func:`register`, carried by
the callable as a ``search_space`` attribute (entry points), or, for the built-ins, from
:mod:`matchers.core.search_spaces`.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from functools import cache
from importlib.metadata import EntryPoint, entry_points

from matchers.core.matching import Matching
from matchers.core.memory_budget import budgeted
from matchers.core.named_lookup import is_builtin, lookup
from matchers.core.named_lookup import usable as _usable
from matchers.core.plugin_guard import guard_matcher
from matchers.core.search_spaces import BUILTIN_SEARCH_SPACES, check_search_space

log = logging.getLogger(__name__)

ENTRY_POINT_GROUP = "cadsim.matchers"

Matcher = Callable[..., Matching]

_BUILTIN: dict[str, str] = {
    "appearance": "matchers.appearance:appearance",
    "bcagm": "matchers.bcagm:bcagm",
    "hgm": "matchers.hgm:hgm",
    "learned": "matchers.learned.matcher:learned",
    "learned_pose": "matchers.learned.matcher:learned_pose",
    "maximin_learned": "matchers.learned.unary:maximin_learned",
    "rrwm_learned": "matchers.learned.unary:rrwm_learned",
    "maximin": "matchers.maximin:maximin",
    "mos": "matchers.mos:mos",
    "none": "matchers.none:none",
    "pose": "matchers.pose:pose",
    "pose_appearance": "matchers.pose:pose_appearance",
    "pose_refine": "matchers.pose_refine:pose_refine",
    "consistency": "matchers.consistency:consistency",
    "cbm": "matchers.cbm:cbm",
    "cbm_pose": "matchers.cbm:cbm_pose",
    "freealign": "matchers.freealign:freealign",
    "freealign_pose": "matchers.freealign:freealign_pose",
    "optimal_transport": "matchers.optimal_transport:optimal_transport",
    "optimal_transport_pose": "matchers.optimal_transport:optimal_transport_pose",
    "maximin_pose": "matchers.maximin:maximin_pose",
    "rrwhm": "matchers.rrwhm:rrwhm",
    "rrwm": "matchers.rrwm:rrwm",
    "sm": "matchers.sm:sm",
    "tm": "matchers.tm:tm",
    "v2x_reg": "matchers.v2x_reg:v2x_reg",
}
_registered: dict[str, Matcher] = {}
_registered_spaces: dict[str, list[dict]] = {}


def register(
    name: str,
    fn: Matcher,
    *,
    search_space: list[dict] | None = None,
    replace: bool = False,
    memory: Callable[..., float] | None = None,
) -> None:
    """Make ``fn`` available as ``get(name)``. Re-using a taken name (built-in, registered or
    entry point) raises ValueError unless ``replace=True``.

    ``memory``: ``memory(problem, **options)`` -> bytes of working memory the call needs; the
    matcher is then refused over the per-process budget before it runs
    (:func:`matchers.core.memory_budget.budgeted`) and carries it as ``memory_bytes``. Default:
    ``fn.memory_bytes`` if the callable carries one (every built-in does). The test suite holds
    every registered matcher's estimate to its measured peak (docs/extending-matchers.md).

    ``search_space``: the matcher's tuning grid, a list of at most 12 option dicts (see
    :func:`search_space`); default: ``fn.search_space`` if the callable carries one, else
    ``[{}]`` (no scale parameters: one configuration, the defaults).

    >>> register("my_pose", get("pose"), search_space=[{"gate": 3.0}, {"gate": 5.0}], replace=True)
    >>> search_space("my_pose")
    [{'gate': 3.0}, {'gate': 5.0}]
    """
    if not isinstance(name, str) or not name:
        raise ValueError(f"name: expected a non-empty string, got {name!r}")
    if not callable(fn):
        raise TypeError(f"fn: expected a callable matcher, got {type(fn).__name__}")
    taken = name in _registered or name in _BUILTIN or name in _entry_points()
    if taken and not replace:
        raise ValueError(f"name: matcher {name!r} already exists; pass replace=True to override")
    if search_space is None:
        space = check_search_space(getattr(fn, "search_space", None) or [{}], name)
    else:
        space = check_search_space(search_space, name, "search_space")
    if memory is not None:
        fn = budgeted(memory, "the view size or the matcher's options")(fn)
    _registered[name] = fn
    _registered_spaces[name] = space


def get(name: str) -> Matcher:
    """The matcher called ``name``: registered first, then built-in, then entry point, then a
    ``package.module:function`` import path (what a command line can name without registering
    anything; worker processes import it themselves)."""
    return lookup(name, "matcher", _registered, _BUILTIN, _entry_points(), available)


def search_space(name: str) -> list[dict]:
    """The tuning grid of matcher ``name``: a list of 1 to 12 option dicts, each a complete
    configuration to pass as keyword options (``{}`` = the defaults). Kernel widths in a grid
    are relative to each problem's own scale (e.g. ``sigma_scale``), so one grid serves every
    dataset. A matcher without scale parameters has ``[{}]``. Returns a fresh copy.

    >>> search_space("appearance")
    [{}]
    """
    if name in _registered and name in _registered_spaces:  # register()ed
        space = _registered_spaces[name]
    elif name in _BUILTIN and name not in _registered:
        space = BUILTIN_SEARCH_SPACES.get(name, [{}])
    else:
        fn = get(name)  # entry point (or ValueError naming the unknown matcher)
        space = check_search_space(getattr(fn, "search_space", None) or [{}], name)
    return [dict(config) for config in space]


def requires(name: str) -> frozenset[str]:
    """Names of the optional :class:`~matchers.core.problem.Problem` fields matcher ``name`` cannot
    run without (e.g. ``{"world1", "world2", "world_sigma"}`` for the pose matchers; empty for
    most): the callable's ``requires`` attribute, if it has one. Lets a harness skip a
    matcher on data that lacks what it needs instead of catching its ValueError.

    >>> sorted(requires("pose"))
    ['world1', 'world2', 'world_sigma']
    """
    return frozenset(getattr(get(name), "requires", ()))


def required_options(name: str) -> frozenset[str]:
    """Options matcher ``name`` cannot run without (``{"model"}`` for the learned matchers: a
    model file's path; empty for most): the callable's ``required_options`` attribute. A
    harness leaves such a matcher out of ``all`` and gives it the option when it has one.

    >>> sorted(required_options("learned")), sorted(required_options("sm"))
    (['model'], [])
    """
    return frozenset(getattr(get(name), "required_options", ()))


def deterministic(name: str) -> bool:
    """Whether matcher ``name`` ignores its ``seed`` (same problem, same result for every seed):
    the callable's ``deterministic`` attribute, False when it has none. A harness may then run
    it once instead of once per seed.

    >>> deterministic("sm"), deterministic("maximin")
    (True, False)
    """
    return bool(getattr(get(name), "deterministic", False))


def available() -> list[str]:
    """Sorted names of every matcher get() can return (entry points listed without importing
    them: one that cannot be loaded is listed too; :func:`usable` leaves it out)."""
    return sorted(set(_BUILTIN) | set(_registered) | set(_entry_points()))


def usable() -> list[str]:
    """:func:`available` without the entry points that cannot be loaded (an import error, a
    missing or non-callable attribute), each reported once as a warning line: what ``all``
    means, so that one broken package does not break every other matcher. Loads every entry
    point."""
    return _usable(available(), "matcher", get)


def plugin_label(name: str) -> str:
    """``matcher 'name'`` — with its entry point's target when it is one — for messages."""
    point = _entry_points().get(name)
    if point is not None and name not in _BUILTIN:
        return f"matcher {name!r} (entry point {point.value})"
    return f"matcher {name!r}"


def checked(name: str, fn: Matcher | None = None, time_limit_s: float | None = None) -> Matcher:
    """The callable the harness runs for matcher ``name`` (``fn``: already looked up): a
    built-in as it is — its results stay bit for bit what they are —, any other (a plug-in:
    registered, entry point, import path) wrapped so that each call runs under the per-problem
    time limit (``time_limit_s``, None: ``$CADSIM_PLUGIN_TIME_LIMIT_S`` or 600 s) and its result
    is checked against the contract; either failure is a
    :class:`~matchers.core.plugin_guard.PluginError` naming it
    (:mod:`matchers.core.plugin_guard`)."""
    fn = get(name) if fn is None else fn
    if is_builtin(fn, _BUILTIN):
        return fn
    return guard_matcher(plugin_label(name), fn, time_limit_s)


@cache
def _entry_points() -> dict[str, EntryPoint]:
    """Entry points of the ``cadsim.matchers`` group, scanned once per process
    (``_entry_points.cache_clear()`` rescans)."""
    found = {ep.name: ep for ep in entry_points(group=ENTRY_POINT_GROUP)}
    if found:
        log.debug("matcher entry points: %s", sorted(found))
    return found
