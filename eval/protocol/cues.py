"""The cues each of the paper's eight matchers reads, as published and under the equal-cue protocol.

A *cue* is a kind of evidence a matcher is handed (DESIGN §3, "Equal cues"):

- ``distances``: metric distances between the objects of one view (edge lengths, metres) — the
  scale of the scene; pairwise methods read them as edge lengths, hypergraph methods (with
  the equal-cue option) as the side lengths of their triangles (:mod:`matchers.blocks.cue_terms`);
- ``angles``: the scale-free shape of triangles of objects (Eq. (1)'s interior-angle cosines);
- ``appearance``: the cosine similarity of the feature vectors — image HOG and colour and the
  detector's attribute block, which carries the *reported* class and the estimated size.

Angles are a function of the distances (three side lengths fix a triangle), so a matcher that
reads distances has every geometric fact one that reads angles has, and more: the scene's scale.
The information each matcher gets is therefore {geometry: metric or scale-free, appearance}.
As published, the eight differ (:data:`PUBLISHED_CUES`: SM and RRWM read no appearance, the
hypergraph methods no appearance and no scale, maximin no scale, MOS everything — but appearance
only as an additive first-order share). The equal-cue protocol (:data:`EQUAL_CUE_OPTIONS`) hands
every one of them metric geometry and appearance, each in its family's natural form (MOS, too:
appearance and the metric kernel multiplied into its M and T, :mod:`matchers.mos`), with the same tuning budget (:data:`EQUAL_CUE_SPACES`, 8
configurations each, the kernel widths relative to the scene) and τ on validation.
"""

from __future__ import annotations

from collections.abc import Mapping

from eval.core.tasks import MatcherSpec

CUES = ("distances", "angles", "appearance")

PUBLISHED_CUES: Mapping[str, frozenset[str]] = {
    "sm": frozenset({"distances"}),
    "rrwm": frozenset({"distances"}),
    "tm": frozenset({"angles"}),
    "hgm": frozenset({"angles"}),
    "bcagm": frozenset({"angles"}),
    "rrwhm": frozenset({"angles"}),
    "mos": frozenset({"distances", "angles", "appearance"}),
    "maximin": frozenset({"angles", "appearance"}),
}
"""What each of the paper's matchers reads with its published options (the "as published" table)."""

DEFAULT_DISTANCE_SCALE = 0.1
"""σ_d of the hypergraph metric term as a multiple of the median within-view distance (a candidate
of every grid below, never the only one)."""

_HYPERGRAPH = {"appearance": True, "distance_scale": DEFAULT_DISTANCE_SCALE}
EQUAL_CUE_OPTIONS: Mapping[str, Mapping[str, object]] = {
    "sm": {"appearance": True},
    "rrwm": {"appearance": True},
    "tm": _HYPERGRAPH,
    "hgm": _HYPERGRAPH,
    "bcagm": _HYPERGRAPH,
    "rrwhm": _HYPERGRAPH,
    "mos": _HYPERGRAPH,
    "maximin": {"distance_scale": DEFAULT_DISTANCE_SCALE},
}
"""Options that hand each matcher the equal cue set (metric geometry + appearance)."""

EQUAL_CUES: frozenset[str] = frozenset({"distances", "appearance"})
"""The information every matcher gets under the equal-cue protocol (angles follow from distances;
the hypergraph methods read both)."""


def _hypergraph_space() -> list[dict]:
    """Eq. (1)'s bandwidth (0.5 default) and the metric term's width (0.1 default), 8 in all."""
    return (
        [{}]
        + [{"sigma": s} for s in (0.1, 0.2, 1.0)]
        + [{"distance_scale": d} for d in (0.03, 0.05, 0.2, 0.5)]
    )


EQUAL_CUE_SPACES: Mapping[str, list[dict]] = {
    name: _hypergraph_space() for name in ("tm", "hgm", "bcagm", "rrwhm", "maximin")
}
"""Tuning grids of the matchers whose equal-cue options add a kernel width; the others (SM, RRWM,
MOS) keep their own grids, which already search their metric width."""


def cues_read(name: str, options: Mapping[str, object]) -> frozenset[str]:
    """The cues matcher ``name`` reads with ``options`` (one of the paper's eight; KeyError else)."""
    cues = set(PUBLISHED_CUES[name])
    if options.get("appearance"):
        cues.add("appearance")
    if options.get("distance_scale") is not None:
        cues.add("distances")
    if options.get("pairwise") == "image":
        cues.discard("distances")  # image-space edge lengths: pixels, not metres
    return frozenset(cues)


def equal_cue_spec(base: MatcherSpec) -> MatcherSpec:
    """``base`` with the equal-cue options of its matcher (unchanged for matchers outside the
    paper's eight); ``base``'s own options win where both set one."""
    extra = EQUAL_CUE_OPTIONS.get(base.name)
    if not extra:
        return base
    return MatcherSpec.of(base.name, **(dict(extra) | dict(base.options)))


def search_space_of(base: MatcherSpec) -> list[dict] | None:
    """The equal-cue grid of ``base`` when it carries its matcher's equal-cue options, else None
    (the matcher's own grid applies)."""
    extra = EQUAL_CUE_OPTIONS.get(base.name)
    if not extra or base.name not in EQUAL_CUE_SPACES:
        return None
    options = dict(base.options)
    if any(options.get(key) != value for key, value in extra.items()):
        return None
    return [dict(config) for config in EQUAL_CUE_SPACES[base.name]]
