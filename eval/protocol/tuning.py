"""Equal tuning budget: each matcher's parameters picked on validation data from its own grid.

Every matcher declares a search grid (``matchers.core.registry.search_space``: 1 to 12 option dicts,
kernel widths relative to each problem's own scale, the defaults ``{}`` among them). For one
dataset, :func:`tune_entry` runs every configuration on the *validation* dataset with run seed 0
only, fits τ on those runs (:func:`eval.protocol.calibration.calibrate`) and scores each configuration by
the mean per-pair F1 at that τ — the quantity τ itself maximises. The best configuration wins;
exact ties go to the configuration whose canonical parameters JSON sorts first — a fixed rule
that does not look at which configuration is the default (``{}`` sorts after every other, so
the defaults never win a tie). Every tunable built-in matcher has the same budget,
``matchers.core.search_spaces.TUNING_BUDGET`` (8) configurations; a matcher whose grid is only
its defaults is run as it is and left out of ``tuning.csv``; a grid of another size (a matcher
of your own) is tuned as given, with a warning that the budgets differ. The test dataset is
never opened here. τ is then calibrated as usual, on every seed of the validation runs of the chosen
configuration (``eval.engine.protocol_run``).

Because configurations are matcher options, they are part of each run's cache key, and the
defaults' validation runs are the same runs the untuned table uses.
"""

from __future__ import annotations

import json
import logging
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

from eval.core.runner import Runner, requests_for
from eval.core.tasks import MatcherSpec
from eval.protocol import calibration

TUNING_SEED = 0
log = logging.getLogger(__name__)


@dataclass(frozen=True)
class Candidate:
    """One grid configuration of a matcher: its spec (base options + the configuration), the
    configuration alone, and its validation score (mean per-pair F1 at its own τ) and τ."""

    spec: MatcherSpec
    config: dict
    val_f1: float
    tau: float


@dataclass(frozen=True)
class TuningChoice:
    """The search for one matcher on one dataset: every candidate, in grid order, and which won."""

    dataset: str
    matcher: str  # the requested matcher's label (the table's row)
    candidates: tuple[Candidate, ...]
    chosen: int

    @property
    def spec(self) -> MatcherSpec:
        return self.candidates[self.chosen].spec

    @property
    def params(self) -> dict:
        """The chosen configuration's options (``{}``: the defaults)."""
        return dict(self.candidates[self.chosen].config)


def grid(name: str) -> list[dict]:
    """The tuning grid of registered matcher `name` (``matchers.core.registry.search_space``)."""
    from matchers.core.registry import search_space

    return search_space(name)


def candidates_of(base: MatcherSpec) -> list[tuple[MatcherSpec, dict]]:
    """(spec, configuration) for each configuration of `base`'s grid, in grid order: the
    configuration's options over `base`'s own; configurations giving the same spec are kept
    once. A spec carrying its matcher's equal-cue options searches the equal-cue grid
    (:mod:`eval.protocol.cues`)."""
    from eval.protocol.cues import search_space_of

    out: dict[MatcherSpec, dict] = {}
    space = search_space_of(base)
    for config in grid(base.name) if space is None else space:
        spec = MatcherSpec.of(base.name, **(dict(base.options) | dict(config)))
        out.setdefault(spec, dict(config))
    return list(out.items())


def tune_entry(
    entry,
    matchers: Sequence[MatcherSpec] | Mapping[str, MatcherSpec],
    runner: Runner,
    limit: int | None = None,
    localisation: tuple[float, float] | None = None,
) -> dict[str, TuningChoice]:
    """Pick each matcher's configuration on `entry`'s validation dataset (seed 0 runs only; its
    first `limit` frame pairs, None: all; with ``localisation`` = (position σ m, yaw σ °) the
    validation records' prior re-drawn at that error, as a sweep level sees it). `entry` is an
    ``eval.engine.splits.DatasetEntry``; `matchers` a list of specs (labelled by their own
    label) or {row label: spec}; returns {matcher label: choice}."""
    if entry.val_dir is None:
        raise ValueError(f"{entry.test_dir}: tuning needs a validation dataset")
    labelled = (
        matchers.items() if isinstance(matchers, Mapping) else [(m.label, m) for m in matchers]
    )
    grids = {label: candidates_of(m) for label, m in labelled}
    for _, m in labelled:
        check_budget(m.name, len(grid(m.name)))
    specs = [spec for options in grids.values() for spec, _ in options]
    runs = runner.run(
        requests_for(
            [(entry.val_dir, entry.val_checksum)],
            specs,
            [TUNING_SEED],
            limit=limit,
            localisation=localisation,
            sensor=getattr(entry, "sensor", None),
        ),
        desc=f"{entry.label} tuning",
    )
    by_spec = {run.spec.matcher: run for run in runs}
    choices = {}
    for label, options in grids.items():
        candidates = []
        for spec, config in options:
            fit = calibration.calibrate([by_spec[spec]])
            candidates.append(Candidate(spec, config, fit.val_f1, fit.tau))
        best = best_candidate(candidates)
        choices[label] = TuningChoice(entry.label, label, tuple(candidates), best)
    return choices


def best_candidate(candidates: Sequence[Candidate]) -> int:
    """Index of the highest validation F1; exact ties to the smallest canonical params JSON."""
    top = max(c.val_f1 for c in candidates)
    tied = [k for k, c in enumerate(candidates) if c.val_f1 == top]
    return min(tied, key=lambda k: params_json(candidates[k].config))


def check_budget(name: str, size: int) -> None:
    """Warn (once per matcher) when a tunable grid's size differs from the equal budget."""
    from matchers.core.search_spaces import TUNING_BUDGET

    if size > 1 and size != TUNING_BUDGET and name not in _WARNED:
        _WARNED.add(name)
        log.warning(
            "%s: a tuning grid of %d configurations, not the %d every built-in matcher gets; "
            "its tuned row is not on an equal footing",
            name,
            size,
            TUNING_BUDGET,
        )


_WARNED: set[str] = set()


def params_json(options: dict) -> str:
    """Options as canonical JSON (sorted keys): the ``params`` cell of the results tables."""
    return json.dumps(options, sort_keys=True, separators=(",", ":"))


def tuning_rows(choices: Sequence[TuningChoice]) -> list[dict]:
    """Rows of ``tuning.csv``: dataset, matcher, config (index in the grid), params (JSON),
    val_f1 (mean per-pair validation F1 at the configuration's own τ), tau, chosen."""
    return [
        {
            "dataset": c.dataset,
            "matcher": c.matcher,
            "config": k,
            "params": params_json(cand.config),
            "val_f1": cand.val_f1,
            "tau": cand.tau,
            "chosen": k == c.chosen,
        }
        for c in choices
        if len(c.candidates) > 1  # only its defaults: not tuned
        for k, cand in enumerate(c.candidates)
    ]
