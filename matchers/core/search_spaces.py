"""Tuning grids: which options of each built-in matcher a tuner may set, and to which values.

A grid is a list of at most ``MAX_CONFIGS`` (12) option dicts, each a complete configuration
(``{}`` = the matcher's defaults). Every kernel width of a matcher is in its grid, and every
width is *relative* to the problem itself — a multiple of the median within-view distance
(``sigma_scale``), of the prior's stated uncertainty (``spread``, ``gate``) or scale-free by
construction (Eq. (1)'s ``sigma`` on angle cosines) — so one grid serves a 2 m robot arena
and an 18 m road junction. The defaults are always a candidate, so tuning can only confirm
or improve on them on the validation data. docs/matchers.md says why each grid is what it is.

Imports nothing from ``cadsim`` or ``eval``.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

MAX_CONFIGS = 12
TUNING_BUDGET = 8
"""Configurations every tunable built-in matcher gets on every dataset (its defaults included):
an equal budget, so that no matcher wins by having been searched harder. A matcher whose grid
is only its defaults is not tuned (and not listed in ``tuning.csv``)."""

_TENSOR_WIDTHS = (0.02, 0.05, 0.1, 0.2, 1.0, 2.0, 5.0)  # Eq. (1) sigma (0.5 default)
_PAIRWISE_WIDTHS = (0.01, 0.02, 0.05, 0.1, 0.2, 0.5, 1.0)  # sigma / median within-view distance
_MOS_WIDTHS = (0.02, 0.05, 0.1, 0.2, 0.5)  # its pairwise width; its tensor sigma: 0.1, 0.2
_TOLERANCES = (0.02, 0.03, 0.05, 0.15, 0.2, 0.3, 0.5)  # consistency (0.1 default)


def _hypergraph() -> list[dict]:
    """Third-order matchers: Eq. (1)'s bandwidth, the default 0.5 first, 0.02-5 around it."""
    return [{}] + [{"sigma": s} for s in _TENSOR_WIDTHS]


def _context() -> list[dict]:
    """CBM / FreeAlign: the tolerance around its default 0.1, and the context size."""
    return (
        [{}]
        + [{"tolerance_scale": s} for s in (0.03, 0.05, 0.2, 0.3, 0.5)]
        + [{"neighbours": 4}, {"neighbours": 10}]
    )


def _context_pose() -> list[dict]:
    """The prior variants: the tolerance, and the prior's width (spread 3, gate 8 by default)."""
    return (
        [{}]
        + [{"tolerance_scale": s} for s in (0.05, 0.2, 0.3)]
        + [{"spread": 1.0}, {"spread": 2.0}, {"gate": 4.0}, {"gate": 12.0}]
    )


def _pairwise() -> list[dict]:
    """SM / RRWM: the default absolute sigma2 = 0.5, then relative kernel widths."""
    return [{}] + [{"sigma_scale": s} for s in _PAIRWISE_WIDTHS]


BUILTIN_SEARCH_SPACES: dict[str, list[dict]] = {
    "appearance": [{}],
    "none": [{}],
    "sm": _pairwise(),
    "rrwm": _pairwise(),
    "mos": [{}] + [{"sigma_scale": s} for s in _MOS_WIDTHS] + [{"sigma": 0.1}, {"sigma": 0.2}],
    "tm": _hypergraph(),
    "hgm": _hypergraph(),
    "bcagm": _hypergraph(),
    "rrwhm": _hypergraph(),
    "maximin": _hypergraph(),
    # The prior matchers' defaults come from DMGM sequence 070 (eval/data/prior-defaults.json);
    # their grids hold absolute values, the defaults they replaced among them.
    "pose": [{}]  # spread 3, gate 8
    + [{"spread": s} for s in (1.0, 2.0, 4.0)]
    + [{"gate": 4.0}, {"gate": 12.0}, {"spread": 1.0, "gate": 4.0}, {"spread": 4.0, "gate": 12.0}],
    "pose_refine": [{}]  # spread 4, gate 8, tighten 0.5, rigid (yaw fitted too)
    + [{"spread": s} for s in (1.0, 2.0, 3.0)]
    + [{"tighten": 0.25}, {"tighten": 1.0}, {"gate": 4.0}, {"rotation": False}],
    "pose_appearance": [{}]  # spread 4, gate 8, refined prior
    + [{"spread": s, "refine": False} for s in (2.0, 3.0, 4.0)]
    + [{"spread": 1.0}, {"spread": 2.0}, {"gate": 4.0}, {"gate": 12.0}],
    "consistency": [{}] + [{"tolerance_scale": s} for s in _TOLERANCES],
    "maximin_pose": [{}, {"refine": False}, {"spread": 1.0}, {"spread": 4.0}]  # refined, 2, 12
    + [{"gate": 4.0}, {"gate": 8.0}, {"sigma": 0.2}, {"sigma": 1.0}],
    # The V2X association baselines: their distance tolerance (0.1 x the median within-view
    # distance by default) and the size of a local context; their prior variants also the
    # prior's width. Eight configurations each, the equal budget.
    "cbm": _context(),
    "freealign": _context(),
    "optimal_transport": [{}]
    + [{"tolerance_scale": s} for s in (0.05, 0.2, 0.3)]
    + [{"epsilon": 0.03}, {"epsilon": 0.3}, {"dustbin": 0.1}, {"dustbin": 0.5}],
    # V2X-Reg++ (matchers.v2x_reg): the boxes kept (top-25 by default; their other published
    # setting top-10, and all), the correspondence distances and the support a pair needs.
    "v2x_reg": [{}]
    + [{"top_k": 10}, {"top_k": 0}]
    + [{"distance_scale": s} for s in (0.5, 2.0)]
    + [{"min_support": s} for s in (2, 6)]
    + [{"top_k": 10, "distance_scale": 2.0}],
    "cbm_pose": _context_pose(),
    "freealign_pose": _context_pose(),
    "optimal_transport_pose": _context_pose(),
    # The learned matchers: the classifier is their tuning (trained, not searched); the hybrids
    # search their base matcher's kernel widths.
    "learned": [{}],
    "learned_pose": [{}],
    "maximin_learned": _hypergraph(),
    "rrwm_learned": _pairwise(),
}


TEMPORAL_SEARCH_SPACES: dict[str, list[dict]] = {
    # The temporal reference method (matchers.temporal.temporal_pose): the prior's width and
    # gate (spread 2, gate 8), the aligned tightening (0.5) and the prior's weight in the
    # refinement (1), around its defaults as pose_refine's grid is. The window W is never in a
    # grid: it is an axis of the temporal table. ``windowed:<name>`` searches <name>'s own grid.
    "temporal_pose": [{}]
    + [{"spread": s} for s in (1.0, 3.0)]
    + [{"gate": 12.0}, {"tighten": 1.0}, {"prior_weight": 4.0}]
    + [{"margin": 0.1}, {"spread": 1.0, "margin": 0.2}],
    # The pose-free one (matchers.temporal.trajectory_pose): the support's cutoff and the
    # association's width (metres: camera depth error at 30-60 m is metres), the weight of a
    # pair of different reported classes, and the GNSS prior as a light soft term (no effect
    # where there is no prior).
    # Issue 61: the partner hysteresis ``margin`` (matchers.temporal.partner_hold; 0, the
    # behaviour before it, in every other configuration) combined with the values chosen most
    # often before; it took the places of the two configurations with the lowest validation F1
    # in results/temporal/tuning.csv of b2fd3b6 (trajectory_pose: cutoff 2, other_class 1;
    # temporal_pose: gate 4, tighten 0.25; pose_refine: tighten 1, rotation off).
    # trajectory_pose holds its window's motion by the same margin (per detection), which
    # wants small values: on the validation split (gnss-urban and denied, W = 10) validation F1
    # peaked at 0.02-0.05 and fell beyond (cutoff 5: 0.72 at 0, 0.58 at 0.2, 0.47 at 0.3).
    "trajectory_pose": [{}]
    + [{"cutoff": 5.0}]
    + [{"width": w} for w in (0.5, 2.0)]
    + [{"other_class": 0.2}, {"prior_weight": 0.1}]
    + [{"margin": 0.02}, {"prior_weight": 0.1, "margin": 0.05}],
    # ``windowed:pose_refine``: pose_refine's two-view grid with the same two swaps.
    "windowed:pose_refine": [{}]
    + [{"spread": s} for s in (1.0, 2.0, 3.0)]
    + [{"tighten": 0.25}, {"gate": 4.0}]
    + [{"gate": 4.0, "margin": 0.1}, {"spread": 1.0, "margin": 0.1}],
}


def check_search_space(space: object, name: str, field: str = "search_space") -> list[dict]:
    """``space`` as a list of option dicts, or ValueError naming ``field`` and the matcher:
    a non-empty sequence of at most 12 mappings whose keys are option names (identifiers) and
    whose values are JSON scalars (numbers, strings, booleans, None) or lists/tuples of them —
    so that a chosen configuration can be written to a results table."""
    where = f"{field} of matcher {name!r}"
    if isinstance(space, str | bytes | Mapping) or not isinstance(space, Sequence):
        raise ValueError(f"{where}: expected a list of option dicts, got {type(space).__name__}")
    if not 1 <= len(space) <= MAX_CONFIGS:
        raise ValueError(f"{where}: expected 1 to {MAX_CONFIGS} configurations, got {len(space)}")
    configs = []
    for config in space:
        if not isinstance(config, Mapping):
            raise ValueError(f"{where}: expected option dicts, got {config!r}")
        for key, value in config.items():
            if not isinstance(key, str) or not key.isidentifier():
                raise ValueError(f"{where}: option names must be identifiers, got {key!r}")
            values = value if isinstance(value, list | tuple) else [value]
            if not all(_is_scalar(v) for v in values):
                raise ValueError(f"{where}: option {key}={value!r} is not a JSON scalar or list")
        configs.append(dict(config))
    if len({repr(sorted(c.items())) for c in configs}) != len(configs):
        raise ValueError(f"{where}: repeats a configuration")
    return configs


def _is_scalar(value: object) -> bool:
    if isinstance(value, float):
        return math.isfinite(value)
    return value is None or isinstance(value, bool | int | str)
