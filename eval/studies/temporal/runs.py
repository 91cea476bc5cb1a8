"""The temporal study's runs: a method over a sequence at one or more windows W (no threshold,
canonical scores), τ calibrated on validation outcomes, and the equal-budget tuning of a method
per (W, preset) on the validation split."""

from __future__ import annotations

import time
from collections.abc import Sequence

import numpy as np

from eval.core.tasks import MatcherSpec
from eval.protocol.calibration import calibrate_ranked
from eval.protocol.metrics import RankedAssignments
from eval.protocol.tuning import Candidate, TuningChoice, best_candidate, check_budget
from eval.studies.temporal.sequences import Sequenced
from eval.studies.temporal.table import LABEL, abstains


def run_method(
    method: str,
    window: int,
    item: Sequenced,
    seed: int,
    preset: str,
    options: dict | None = None,
):
    """Per frame (assigned (k, 2), assigned scores (k,)) of ``method`` at ``window`` with its
    ``options`` (None: defaults) and no threshold; nothing declared where it cannot run (a prior
    reader under ``denied``, :func:`abstains`). Plus the seconds it took."""
    return run_windows(method, (window,), item, seed, preset, options)[window]


def run_windows(
    method: str,
    windows: Sequence[int],
    item: Sequenced,
    seed: int,
    preset: str,
    options: dict | None = None,
) -> dict[int, tuple[list, float]]:
    """{W: :func:`run_method`'s (frames, seconds)} for every W of ``windows``: one call of the
    method's ``over_windows`` where it has one (``windowed:<m>``: the base matcher run once for
    every W; seconds then shared out evenly), else one call per W."""
    from matchers.core.temporal_registry import get_temporal

    empty = [(np.zeros((0, 2), np.int64), np.zeros(0)) for _ in item.seq.frames]
    if abstains(method, preset):
        return {w: (empty, 0.0) for w in windows}
    fn = get_temporal(method)
    options = dict(options or {})
    many = getattr(fn, "over_windows", None)
    if many is not None and len(windows) > 1:
        started = time.perf_counter()
        outs = many(item.seq, list(windows), seed=seed, threshold=None, **options)
        seconds = (time.perf_counter() - started) / len(windows)
        return {w: (_assigned(outs[w]), seconds) for w in windows}
    found = {}
    for w in windows:
        started = time.perf_counter()
        out = fn(item.seq, seed=seed, threshold=None, window=w, **options)
        found[w] = (_assigned(out), time.perf_counter() - started)
    return found


def _assigned(matchings) -> list[tuple[np.ndarray, np.ndarray]]:
    """Per frame (assigned pairs (k, 2), their canonical scores (k,))."""
    from matchers.core.discretise import canonical_scores

    frames = []
    for m in matchings:
        pairs = np.asarray(m.pairs, dtype=np.int64).reshape(-1, 2)
        # canonical (grid) scores, as the two-view runner uses: τ sees the same values on every CPU
        scores = canonical_scores(np.asarray(m.scores, dtype=float))
        frames.append((pairs, scores[pairs[:, 0], pairs[:, 1]] if len(pairs) else np.zeros(0)))
    return frames


def calibrate_tau(outcomes: list[tuple[Sequenced, list]]) -> tuple[float, float]:
    """(τ, mean validation F1) of one (method, W, preset) from its validation outcomes."""
    rows = [
        (pairs, scores, item.gt[t], item.seq.frames[t].n1, item.seq.frames[t].n2)
        for item, frames in outcomes
        for t, (pairs, scores) in enumerate(frames)
    ]
    tau, f1, _, _ = calibrate_ranked(RankedAssignments.from_frames(rows))
    return tau, f1


def tune_method(
    method: str,
    window: int,
    val: list[tuple[int, Sequenced]],
    preset: str,
    tune: bool = True,
) -> TuningChoice:
    """Every configuration of ``method``'s grid (only its defaults when ``tune`` is False or a
    prior reader under ``denied``) at ``window`` on the validation items ``val``: each with its
    own τ and validation F1 (:func:`calibrate_tau`), the best chosen
    (:func:`eval.protocol.tuning.best_candidate`)."""
    return tune_windows(method, (window,), val, preset, tune)[window]


def tune_windows(
    method: str,
    windows: Sequence[int],
    val: list[tuple[int, Sequenced]],
    preset: str,
    tune: bool = True,
) -> dict[int, TuningChoice]:
    """{W: :func:`tune_method`'s choice at W} for every W of ``windows``, each configuration
    run once for all of them (:func:`run_windows`); every W chooses on its own."""
    from matchers.core.temporal_registry import temporal_search_space

    declares_nothing = abstains(method, preset)
    configs = temporal_search_space(method) if tune and not declares_nothing else [{}]
    if len(configs) > 1:
        check_budget(method, len(configs))
    candidates: dict[int, list[Candidate]] = {w: [] for w in windows}
    for config in configs:
        runs = [
            (item, run_windows(method, windows, item, seed, preset, config)) for seed, item in val
        ]
        for w in windows:
            tau, val_f1 = calibrate_tau([(item, found[w][0]) for item, found in runs])
            if declares_nothing:
                tau = float("nan")  # declares nothing: no τ to calibrate
            # the partner hysteresis (``margin``) has no memory to keep at W = 1 (the matchers
            # ignore it there): such a configuration is reported as the one without it
            shown = {k: v for k, v in config.items() if not (w == 1 and k == "margin")}
            spec = MatcherSpec.of(method, **shown)
            candidates[w].append(Candidate(spec, shown, val_f1, tau))
    return {
        w: TuningChoice(f"{LABEL} {preset} W={w}", method, tuple(c), best_candidate(c))
        for w, c in candidates.items()
    }
