"""The two evaluation protocols and the files each writes.

- ``calibrated`` (Table I proper): pairwise terms on 3-D positions, τ calibrated on validation
  data, parameters optionally tuned there (``--tune``; the untuned result is the ``untuned``
  variant).
- ``equal_cues`` (Table I's headline): every matcher handed the same cues — metric geometry and
  appearance — each in its family's natural form (:mod:`eval.protocol.cues`), tuned with the
  same budget and τ calibrated on validation. ``calibrated`` is then the "as published" table.
- ``paper``: the matchers as the paper describes its baselines — SM, RRWM and MOS's second-order
  term compare edge lengths between box centres in the image (``pairwise="image"``), every
  matcher reports its full Hungarian assignment (no τ), no tuning.

A variant's files carry its suffix: ``metrics_per_pair.csv`` (calibrated, tuned when tuning
ran), ``metrics_per_pair_untuned.csv``, ``metrics_per_pair_paper_protocol.csv``,
``metrics_per_pair_equal_cues.csv``, and likewise
for thresholds, average precision, the evaluation record and Table I.
"""

from __future__ import annotations

from pathlib import Path

from eval.core.tasks import MatcherSpec

PROTOCOLS = ("calibrated", "paper", "equal_cues")
MAIN, UNTUNED, PAPER, EQUAL = "", "untuned", "paper_protocol", "equal_cues"
VARIANTS = (MAIN, UNTUNED, PAPER, EQUAL)

# Options that make a matcher follow the paper's protocol; matchers not listed run as they are.
PAPER_OPTIONS: dict[str, dict] = {
    "sm": {"pairwise": "image"},
    "rrwm": {"pairwise": "image"},
    "mos": {"pairwise": "image"},
}


def check_protocol(protocol: str) -> str:
    if protocol not in PROTOCOLS:
        raise ValueError(f"--protocol: expected one of {', '.join(PROTOCOLS)}, got {protocol!r}")
    return protocol


def paper_spec(base: MatcherSpec) -> MatcherSpec:
    """`base` with the paper protocol's options (image-space pairwise terms where they apply)."""
    extra = PAPER_OPTIONS.get(base.name)
    if not extra:
        return base
    return MatcherSpec.of(base.name, **(dict(base.options) | extra))


def variant_path(out_dir: str | Path, stem: str, variant: str, suffix: str) -> Path:
    """``out_dir/stem[_variant]suffix``: e.g. (``table1``, ``untuned``, ``.md``) ->
    ``table1_untuned.md``."""
    if variant not in VARIANTS:
        raise ValueError(f"variant: expected one of {VARIANTS}, got {variant!r}")
    name = stem + (f"_{variant}" if variant else "") + suffix
    return Path(out_dir) / name
