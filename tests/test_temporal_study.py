"""The temporal table (issue 41's study, ``eval/studies/temporal/evaluation.py``) on a tiny fake sequence
dataset (the fake stages of tests/test_generate_fakes.py: no SUMO, no OpenGL): the table and its
columns, W = 1 rows equal to the two-view matcher's per-frame outcome, τ from validation only,
goal lines through goal_verdict, the README part; a prior reader under ``denied`` gets no number
and pooled F1 is the headline."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest
import test_sequences as seqs

from cadsim.dataset import Dataset
from eval.engine import goal
from eval.protocol import goal_verdict
from eval.protocol.metrics import pair_metrics
from eval.studies.temporal import evaluation as temporal
from eval.studies.temporal import runs as temporal_runs
from matchers.core.registry import get

METHODS = (("windowed:consistency", (1, 3, 10)), ("temporal_pose", (1, 10)))
PRESETS = ("gnss-urban", "denied")


@pytest.fixture(scope="module")
def dirs(tmp_path_factory):
    root = tmp_path_factory.mktemp("temporal")
    scenario = seqs._scenario(frames=4)
    seqs._generate(root / "test", scenario, pairs=4)
    seqs._generate(root / "val", scenario, pairs=2, seed=99)
    seqs._generate(root / "other", scenario, pairs=2, seed=7)
    return root


@pytest.fixture(scope="module")
def study(dirs):
    out = dirs / "out"
    table = temporal.evaluate_temporal(dirs / "test", dirs / "val", out, METHODS, PRESETS)
    return out, table


def test_the_study_writes_the_table_with_its_columns(study):
    out, table = study
    csv = pd.read_csv(out / "table_temporal.csv")
    assert list(csv.columns) == list(temporal.COLUMNS)
    runs = sum(len(w) for _, w in METHODS)
    assert len(csv) == len(PRESETS) * (runs + 1)  # + the oracle row per preset
    assert set(csv["preset"]) == set(PRESETS)
    oracle = csv[csv["method"] == temporal.ORACLE_ROW]
    assert (oracle["f1_mean"] == 1.0).all()
    md = (out / "table_temporal.md").read_text()
    assert "| Preset | Method | W |" in md and "What accumulation buys" in md
    gain = pd.read_csv(out / "table_temporal_gain.csv")
    assert list(gain.columns) == list(temporal.GAIN_COLUMNS)
    assert list(gain["preset"]) == [p for p in PRESETS for _ in range(2)]
    assert list(gain["parameters"]) == [temporal.TUNED, temporal.FIXED] * len(PRESETS)
    continuity = pd.read_csv(out / temporal.CONTINUITY_FILE)
    assert list(continuity.columns) == list(temporal.CONTINUITY_COLUMNS)
    assert list(continuity["band"]) == ["static", "slow", "fast"] * len(PRESETS)
    assert (continuity["kept"] <= continuity["links"]).all()
    assert continuity["links"].sum() > 0
    ran = csv.dropna(subset=["f1_pooled"])  # all but the prior reader under denied
    assert len(ran) == len(csv) - 2
    assert (ran["frames"] == 16).all() and (ran["sequences"] == 4).all()


def test_a_prior_reader_under_denied_gets_no_number(study):
    """Abstention is not a score (DESIGN §3): no F1 of the empty-frame convention, empty CSV
    cells, "n/a (needs a prior)" in the Markdown and the README part, in no "best"."""
    from eval.core.abstention import NO_NUMBER

    out, table = study
    csv = pd.read_csv(out / "table_temporal.csv")
    rows = csv[(csv["method"] == "temporal_pose") & (csv["preset"] == "denied")]
    assert len(rows) == 2
    metrics = [c for c in temporal.COLUMNS if c not in ("method", "window", "preset", "params")]
    assert rows[metrics].isna().all().all(), rows[metrics]
    raw = (out / "table_temporal.csv").read_text().splitlines()
    assert all(",,,," in line for line in raw if line.startswith("temporal_pose,1,denied"))
    ran = csv[(csv["method"] == "temporal_pose") & (csv["preset"] == "gnss-urban")]
    assert ran["f1_pooled"].notna().all()  # the same method where the prior is given
    md = (out / "table_temporal.md").read_text()
    assert f"| `denied` | `temporal_pose` | 10 | n/a | n/a | {NO_NUMBER} |" in md
    assert temporal.best_long(table, "denied") == "windowed:consistency"
    gain = pd.read_csv(out / "table_temporal_gain.csv").set_index("preset")
    assert set(gain.loc["denied", "method"]) == {"windowed:consistency"}
    per_frame = pd.read_csv(out / "temporal" / "per_frame.csv")
    assert not ((per_frame["method"] == "temporal_pose") & (per_frame["preset"] == "denied")).any()
    part = "\n".join(temporal.readme_part(out, "results"))
    assert f"`denied`: `temporal_pose` — {NO_NUMBER}; in no comparison" in part


def test_f1_pooled_is_the_headline_and_sums_counts_over_frames(study):
    out, table = study
    csv = pd.read_csv(out / "table_temporal.csv")
    per_frame = pd.read_csv(out / "temporal" / "per_frame.csv")
    for row in csv.dropna(subset=["f1_pooled"]).itertuples(index=False):
        mine = per_frame[
            (per_frame["method"] == row.method)
            & (per_frame["window"] == row.window)
            & (per_frame["preset"] == row.preset)
        ]
        tp, declared, true = mine["tp"].sum(), mine["n_pred"].sum(), mine["n_gt"].sum()
        assert row.f1_pooled == pytest.approx(2 * tp / (declared + true), abs=1e-6)
        assert row.f1_pooled_low <= row.f1_pooled <= row.f1_pooled_high
    md = (out / "table_temporal.md").read_text()
    assert "| F1 pooled [95 % CI] | F1 per frame [95 % CI] |" in md  # pooled first


def test_pooled_f1_on_a_planted_case_is_not_the_per_frame_mean():
    """Three frames: 2 of 3 declared right with 4 true pairs, an empty frame (no truth, nothing
    declared: F1 1 by the per-frame convention) and 1 of 1: pooled 2·3 / (4 + 5) = 2/3, where the
    per-frame mean is (4/7 + 1 + 1) / 3."""
    frames = pd.DataFrame(
        {"seed": 0, "episode": [0, 0, 1], "tp": [2, 0, 1], "n_pred": [3, 0, 1], "n_gt": [4, 0, 1]}
    )
    frames["f1"] = [2 * (2 / 3) * 0.5 / (2 / 3 + 0.5), 1.0, 1.0]
    point, low, high = temporal.pooled_f1(frames)
    assert point == pytest.approx(2 / 3)
    assert frames["f1"].mean() == pytest.approx((4 / 7 + 2) / 3)
    assert low <= point <= high
    nothing = frames.assign(tp=0, n_pred=0)  # declares nothing where there are true pairs
    assert temporal.pooled_f1(nothing)[0] == 0.0 and nothing["f1"].mean() > 0


def test_w1_rows_equal_the_two_view_matchers_per_frame_outcome(dirs, study):
    out, table = study
    per_frame = pd.read_csv(out / "temporal" / "per_frame.csv")
    ds = Dataset(str(dirs / "test"))
    base = get("consistency")
    for preset in PRESETS:
        row = table[
            (table["method"] == "windowed:consistency")
            & (table["window"] == 1)
            & (table["preset"] == preset)
        ].iloc[0]
        options = json.loads(row.params)  # the configuration chosen on validation
        got = per_frame[
            (per_frame["method"] == "windowed:consistency")
            & (per_frame["window"] == 1)
            & (per_frame["preset"] == preset)
        ].sort_values(["sequence", "frame"])
        expected = []
        for k in range(ds.sequences):
            for pair in ds.sequence(k):
                local = pair.localise_preset(preset, seed=0)
                problem = local.problem()
                m = base(problem, seed=0, threshold=None, **options)
                pairs = np.asarray(m.pairs, dtype=np.int64).reshape(-1, 2)
                kept = pairs[m.scores[pairs[:, 0], pairs[:, 1]] >= row.tau]
                expected.append(pair_metrics(kept, local.gt_pairs, problem.n1, problem.n2).f1)
        np.testing.assert_allclose(got["f1"].to_numpy(), expected, atol=1e-6)


def test_tau_comes_from_validation_only(dirs, study):
    out, table = study
    # the same validation split with another test split: every τ unchanged
    other = temporal.evaluate_temporal(
        dirs / "other", dirs / "val", dirs / "out-other", METHODS, PRESETS
    )
    key = ["method", "window", "preset"]
    left = table[table["method"] != temporal.ORACLE_ROW].set_index(key)["tau"]
    right = other[other["method"] != temporal.ORACLE_ROW].set_index(key)["tau"]
    pd.testing.assert_series_equal(left.sort_index(), right.sort_index())
    params = other[other["method"] != temporal.ORACLE_ROW].set_index(key)["params"]
    chosen = table[table["method"] != temporal.ORACLE_ROW].set_index(key)["params"]
    pd.testing.assert_series_equal(chosen.sort_index(), params.sort_index())
    # and each τ is the calibration of the validation outcomes alone
    for preset in PRESETS:
        val = temporal.load_split(dirs / "val", preset, temporal.RUNS)
        options = json.loads(table.set_index(key).loc[("windowed:consistency", 3, preset)].params)
        outcomes = [
            (item, temporal.run_method("windowed:consistency", 3, item, s, preset, options)[0])
            for s, item in val
        ]
        tau, val_f1 = temporal.calibrate_tau(outcomes)
        row = table.set_index(key).loc[("windowed:consistency", 3, preset)]
        assert row["tau"] == pytest.approx(tau, abs=1e-6)
        assert row["val_f1"] == pytest.approx(val_f1, abs=1e-6)


def test_a_planted_validation_threshold_is_the_one_applied(monkeypatch, dirs):
    """Plant the τ calibration: the test F1 is then the F1 at the planted τ, whatever the test
    split would prefer."""
    monkeypatch.setattr(temporal_runs, "calibrate_tau", lambda outcomes: (1e9, 0.5))  # every config
    table = temporal.evaluate_temporal(
        dirs / "test", dirs / "val", dirs / "out-planted", METHODS[:1], PRESETS[:1]
    )
    rows = table[table["method"] != temporal.ORACLE_ROW]
    assert (rows["tau"] == 1e9).all() and (rows["f1_mean"] == 0).all()


def _table(f1_low: float, f1_high: float) -> pd.DataFrame:
    rows = []
    for preset in ("gnss-urban", "denied"):
        for window in (1, 10):
            rows.append(
                dict.fromkeys(temporal.COLUMNS, np.nan)
                | {"method": "m", "window": window, "preset": preset, "val_f1": 0.5}
                | {"f1_mean": 0.85, "f1_low": f1_low, "f1_high": f1_high}
                | {"f1_pooled": 0.85, "f1_pooled_low": f1_low, "f1_pooled_high": f1_high}
                | {"success_1m_2deg": 0.7, "success_low": 0.65, "success_high": 0.75}
                | {"partner_changes_per_100": 0.5, "partner_changes_low": 0.2}
                | {"partner_changes_high": 0.9}
                | {"share_of_oracle": 0.9}
            )
    return pd.DataFrame(rows)


def test_goal_lines_go_through_goal_verdict(monkeypatch, tmp_path):
    calls = []
    real = goal_verdict.goal_line

    def spy(*args, **kwargs):
        calls.append((args, kwargs))
        return real(*args, **kwargs)

    monkeypatch.setattr(goal, "goal_line", spy)  # every goal is declared (eval.engine.goal)
    lines = temporal.goals(_table(0.81, 0.9), tmp_path)
    assert len(lines) == len(calls) == 3  # no per-frame or gain files: those goals left out
    assert lines[0].startswith("`denied`, W = 10: best pooled F1 ≥ 80: met")
    assert ": met" in lines[1]  # success [65, 75] ≥ 60
    assert ": met" in lines[2]  # partner changes [0.2, 0.9] ≤ 1
    crossing = temporal.goals(_table(0.79, 0.9), tmp_path)
    assert crossing[0].startswith("`denied`, W = 10: best pooled F1 ≥ 80: not shown")


def test_readme_part_is_compact_and_states_the_goals(study):
    out, _ = study
    lines = temporal.readme_part(out, "results", seconds=42.0)
    assert lines[0] == "### The temporal table"
    rows = [line for line in lines if line.startswith("| `")]
    assert 0 < len(rows) <= 6
    text = "\n".join(lines)
    assert "W = 10 beats W = 1" in text and "42 s" in text
    assert temporal.readme_part(out / "missing", "results") == []


def test_every_method_gets_the_equal_budget_and_the_best_validation_f1_wins(study):
    from matchers.core.search_spaces import TUNING_BUDGET

    out, table = study
    tuning = pd.read_csv(out / "temporal" / "tuning.csv", keep_default_na=False)
    assert list(tuning.columns) == list(temporal.TUNING_COLUMNS)
    sizes = tuning.groupby(["preset", "matcher", "window"]).size()
    assert (sizes == TUNING_BUDGET).all(), sizes
    # a prior reader under denied cannot run: not tuned, no candidates
    assert not ((tuning["preset"] == "denied") & (tuning["matcher"] == "temporal_pose")).any()
    assert "window" not in "".join(tuning["params"])  # W is the table's axis, never tuned
    # the partner hysteresis has no memory at W = 1: its configurations read as without it
    assert "margin" in "".join(tuning[tuning["window"] == 10]["params"])
    assert "margin" not in "".join(tuning[tuning["window"] == 1]["params"])
    for (preset, method, window), rows in tuning.groupby(["preset", "matcher", "window"]):
        won = rows[rows["chosen"].astype(str) == "True"]
        assert len(won) == 1
        assert won["val_f1"].iloc[0] == rows["val_f1"].max()
        row = table[
            (table["method"] == method) & (table["window"] == window) & (table["preset"] == preset)
        ].iloc[0]
        assert row.params == won["params"].iloc[0]
        assert row.val_f1 == pytest.approx(won["val_f1"].iloc[0], abs=1e-6)
        assert row.tau == pytest.approx(won["tau"].iloc[0], abs=1e-6)
    md = (out / "table_temporal.md").read_text()
    assert "| parameters |" in md


def test_every_temporal_method_of_the_table_has_the_equal_budget_and_no_window_in_it(monkeypatch):
    from matchers.core import temporal_registry
    from matchers.core.search_spaces import TUNING_BUDGET
    from matchers.core.temporal_registry import register_temporal, temporal_search_space

    for method, _ in temporal.METHODS:
        grid = temporal_search_space(method)
        assert len(grid) == TUNING_BUDGET and {} in grid, method
        assert not any("window" in config for config in grid), method

    def fake(seq, seed=0, threshold=None, window=1):
        return []

    fake.search_space = [{}, {"window": 3}]
    monkeypatch.setattr(temporal_registry, "_registered", {})
    register_temporal("fake_windowed_grid", fake)
    with pytest.raises(ValueError, match="window"):
        temporal_search_space("fake_windowed_grid")


def test_the_study_reads_each_runs_own_odometry_not_the_stored_one(dirs):
    from cadsim.dataset.sequence_odometry import redraw_odometry

    ds = Dataset(str(dirs / "val"))
    for seed in (0, 1):
        items = temporal.load_split(dirs / "val", "gnss-urban", (seed,))
        for k, (_, item) in enumerate(items):
            run = redraw_odometry(ds.sequence(k), seed)
            for view, odometry in ((0, item.seq.odometry1), (1, item.seq.odometry2)):
                expected = [
                    [f.odometry[view].x, f.odometry[view].y, f.odometry[view].yaw] for f in run
                ]
                stored = [
                    [f.odometry[view].x, f.odometry[view].y, f.odometry[view].yaw]
                    for f in ds.sequence(k)
                ]
                np.testing.assert_array_equal(odometry, expected)
                assert not np.array_equal(odometry, stored)


def test_the_run_record_states_every_rows_chosen_parameters(study):
    _, table = study
    record = temporal.temporal_tuning_record(table)
    rows = table[table["method"] != temporal.ORACLE_ROW]
    assert sum(len(w) for m in record.values() for w in m.values()) == len(rows)
    for row in rows.itertuples(index=False):
        entry = record[row.preset][row.method][str(row.window)]
        if temporal.abstains(row.method, row.preset):  # no number: nothing was chosen
            assert entry == {"params": None, "tau": None, "val_f1": None}
            continue
        assert entry["params"] == json.loads(row.params)
        assert (entry["tau"] is None) == (not np.isfinite(row.tau))
    json.dumps(record)  # goes into run_record.json as it is


def test_one_task_per_preset_on_the_executor_gives_the_same_files(dirs, study):
    from eval.core.executor import LocalProcessExecutor

    out, _ = study
    with LocalProcessExecutor(2) as executor:
        temporal.evaluate_temporal(
            dirs / "test", dirs / "val", dirs / "out-pool", METHODS, PRESETS, executor=executor
        )
    for name in ("table_temporal.csv", "table_temporal_gain.csv", "temporal/per_frame.csv"):
        serial = pd.read_csv(out / name)
        pooled = pd.read_csv(dirs / "out-pool" / name)
        keep = [c for c in serial.columns if c != "ms_per_frame"]
        pd.testing.assert_frame_equal(pooled[keep], serial[keep], obj=name)
    assert (out / "temporal" / "tuning.csv").read_bytes() == (
        dirs / "out-pool" / "temporal" / "tuning.csv"
    ).read_bytes()
