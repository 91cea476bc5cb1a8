"""The temporal study under one preset (:func:`evaluate_preset`, one executor task): the oracle,
the own tracker's continuity, every (method, W) tuned on validation and scored on test, and the
preset's gain rows."""

from __future__ import annotations

import logging
from dataclasses import dataclass
from pathlib import Path

import pandas as pd

from eval.core.abstention import NO_NUMBER
from eval.protocol.tuning import params_json, tuning_rows
from eval.studies.temporal.gain import gain_rows
from eval.studies.temporal.runs import run_method, tune_windows
from eval.studies.temporal.scores import continuity_rows, oracle_scores, score_test, summarise
from eval.studies.temporal.sequences import load_split
from eval.studies.temporal.table import LONG, ORACLE_ROW, SHORT, abstains

log = logging.getLogger(__name__)


@dataclass
class PresetOutcome:
    """One preset's part of the study: its table rows (the oracle's last), its gain rows (none
    without a W = 10 / W = 1 pair), its per-frame tables and its tuning candidates."""

    rows: list[dict]
    gain: list[dict]
    per_frame: list[pd.DataFrame]
    tuned: list[dict]
    continuity: list[dict]


def evaluate_preset(task: tuple) -> PresetOutcome:
    """The study under one preset: ``task`` = (test folder, validation folder, preset, methods,
    run seeds, tune). Module-level and picklable: one task of the executor per preset."""
    test_dir, val_dir, preset, methods, seeds, tune = task
    test = load_split(Path(test_dir), preset, seeds)
    val = load_split(Path(val_dir), preset, seeds)
    oracle_row, oracle_frames = oracle_scores(test, preset)
    continuity = continuity_rows(test, preset)
    rows, tuned = [], []
    per_frame_all = [oracle_frames.assign(method=ORACLE_ROW, window=0, preset=preset)]
    frames_by: dict[tuple[str, int], pd.DataFrame] = {}
    for method, windows in methods:
        if abstains(method, preset):  # no number: not run, not tuned, in no comparison
            rows += [
                {"method": method, "window": w, "preset": preset, "params": ""} for w in windows
            ]
            log.info("[temporal] %s %s: %s", preset, method, NO_NUMBER)
            continue
        choices = tune_windows(method, windows, val, preset, tune)
        for window in windows:
            choice = choices[window]
            chosen = choice.candidates[choice.chosen]
            tau, val_f1, options = chosen.tau, chosen.val_f1, choice.params
            tuned += [r | {"preset": preset, "window": window} for r in tuning_rows([choice])]
            per_frame, temporal, seconds = [], [], 0.0
            for seed, item in test:
                frames, took = run_method(method, window, item, seed, preset, options)
                seconds += took
                r, s = score_test(item, frames, tau, seed)
                per_frame += r
                temporal.append(s)
            table = pd.DataFrame(per_frame)
            frames_by[(method, window)] = table
            per_frame_all.append(table.assign(method=method, window=window, preset=preset))
            row = {"method": method, "window": window, "preset": preset}
            row |= {"tau": tau, "val_f1": val_f1, "params": params_json(options)}
            row |= summarise(table, temporal)
            row["ms_per_frame"] = 1000 * seconds / max(len(table), 1)
            rows.append(row)
            if window == LONG and SHORT in windows:  # W = 1 at W = 10's parameters and τ
                fixed = []
                for seed, item in test:
                    frames, _ = run_method(method, SHORT, item, seed, preset, options)
                    fixed += score_test(item, frames, tau, seed)[0]
                frames_by[(method, "fixed")] = pd.DataFrame(fixed)
            log.info(
                "[temporal] %s %s W=%d %s: τ %.3f, val F1 %.3f, test F1 %.3f",
                preset,
                method,
                window,
                row["params"],
                tau,
                val_f1,
                row["f1_mean"],
            )
    rows.append(oracle_row)
    return PresetOutcome(rows, gain_rows(preset, rows, frames_by), per_frame_all, tuned, continuity)
