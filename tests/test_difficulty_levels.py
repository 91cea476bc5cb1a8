"""Difficulty factors (stored at generation, from the truth), the level rule fitted on validation
only, the per-level tables and the headline level chosen on validation (issue 56)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from cadsim.dataset.difficulty import FACTORS, LEVELS, LevelRule, difficulty_factors, level_counts
from eval.engine.difficulty_levels import headline_level, level_tables
from eval.engine.power_analysis import clusters_needed

ROOT = Path(__file__).resolve().parents[1]


def _factors(rng: np.random.Generator, n: int, shift: float = 0.0) -> list[dict]:
    return [
        {
            "noncovisible_share": float(np.clip(rng.uniform(0.1, 0.7) + shift, 0, 1)),
            "covisible": int(rng.integers(3, 12)),
            "yaw_change_deg": float(rng.uniform(0, 180)),
            "baseline_m": float(rng.uniform(5, 60)),
            "position_disagreement_m": float(rng.uniform(0.1, 2.0) + shift),
            "look_alike_share": float(rng.uniform(0, 0.5)),
        }
        for _ in range(n)
    ]


def test_factors_follow_their_definitions():
    # view 1: three objects, two of them cars 1 m apart (look-alikes); view 2 sees two of them
    p1 = np.array([[0.0, 0.0, 10.0], [1.0, 0.0, 10.0], [0.0, 0.0, 30.0]])
    p2 = np.array([[0.0, 0.0, 10.0], [1.0, 0.0, 10.0]])
    ahead, turn = np.eye(4), np.eye(4)
    ahead[:3, :3] = [[0, 0, 1], [-1, 0, 0], [0, -1, 0]]  # OpenCV camera looking along world x
    turn[:3, :3] = [[1, 0, 0], [0, 0, 1], [0, -1, 0]]  # … and one looking along world y
    turn[:3, 3] = [3.0, 4.0, 0.0]
    f = difficulty_factors(
        p1, p2, ["car", "car", "person"], ["car", "bus"], np.array([[0, 0], [1, 1]]),
        (ahead, turn),
    )  # fmt: skip
    assert f["noncovisible_share"] == pytest.approx(1 - 4 / 5)
    assert f["covisible"] == 2
    assert f["look_alike_share"] == pytest.approx(2 / 5)  # the two cars of view 1 only
    assert f["baseline_m"] == pytest.approx(5.0)
    assert f["yaw_change_deg"] == pytest.approx(90.0)
    assert f["position_disagreement_m"] > 0
    same = difficulty_factors(p1, p1, ["car"] * 3, ["car"] * 3, np.array([[0, 0]]), None)
    assert same["yaw_change_deg"] is None and same["position_disagreement_m"] is None


def test_the_rule_is_fitted_on_the_reference_alone_and_orders_levels_by_hardness():
    rng = np.random.default_rng(0)
    validation = _factors(rng, 60)
    rule = LevelRule.fit(validation)
    assert level_counts(rule.levels(validation)) == {"easy": 20, "medium": 20, "hard": 20}
    test = _factors(rng, 30)
    first = rule.levels(test)
    # changing the test pairs never moves the rule (it read validation only)
    assert LevelRule.fit(validation).cuts == rule.cuts
    harder = [
        f | {"covisible": 1, "noncovisible_share": 0.99, "look_alike_share": 0.9} for f in test
    ]
    assert all(
        LEVELS.index(h) >= LEVELS.index(e) for h, e in zip(rule.levels(harder), first, strict=True)
    )
    assert rule.levels([{k: None for k in FACTORS}]) == ["n/a"]
    with pytest.raises(ValueError, match="no pairs"):
        LevelRule.fit([])


def _per_pair(levels: list[str], f1: dict[str, list[float]], split: str = "test") -> pd.DataFrame:
    rows = [
        {
            "dataset": "CAD",
            "split": split,
            "matcher": m,
            "seed": 0,
            "pair": i,
            "episode": i,
            "f1": v,
        }
        for m, values in f1.items()
        for i, v in enumerate(values)
    ]
    return pd.DataFrame(rows)


def test_level_tables_report_the_ceiling_share_and_whether_the_top_is_separated():
    n = 30
    levels = pd.DataFrame({"dataset": "CAD", "pair": range(n), "level": ["hard"] * n})
    rng = np.random.default_rng(1)
    f1 = {
        "maximin": list(np.clip(0.6 + 0.05 * rng.normal(size=n), 0, 1)),
        "rrwm": list(np.clip(0.4 + 0.05 * rng.normal(size=n), 0, 1)),
        "sm": [1.0] * 5 + [0.2] * (n - 5),
    }
    rows, summary = level_tables(_per_pair(["hard"] * n, f1), levels, ["sm", "rrwm", "maximin"])
    row = summary.iloc[0]
    assert row["top"] == "maximin" and row["runner_up"] == "rrwm" and bool(row["separated"])
    assert row["top_perfect_share"] == 0.0
    assert row["rival"] == "rrwm" and row["maximin_minus_rival"] > 0.1
    assert set(rows["matcher"]) == {"sm", "rrwm", "maximin"} and (rows["pairs"] == n).all()
    assert row["mdd"] > 0 and row["clusters_for_mdd_5"] >= 2


def test_clusters_needed_grows_with_the_spread_of_the_differences():
    rng = np.random.default_rng(2)
    clusters = np.arange(50)
    narrow = clusters_needed(0.05 * rng.normal(size=50), clusters)
    wide = clusters_needed(0.3 * rng.normal(size=50), clusters)
    assert narrow < wide


def test_the_headline_level_is_chosen_on_validation_never_on_test():
    n = 9
    levels = pd.DataFrame(
        {"dataset": "CAD", "pair": range(n), "level": ["easy"] * 3 + ["medium"] * 3 + ["hard"] * 3}
    )
    # on validation the methods differ only on the hard pairs
    val = _per_pair([], {"sm": [1] * 6 + [0.1] * 3, "maximin": [1] * 9}, "validation")
    choice = headline_level(val, levels, ["sm", "maximin"])
    assert choice["level"] == "hard" and choice["chosen_on"] == "validation"
    assert choice["spread"]["easy"] == 0.0


def test_generated_records_store_their_factors_and_readers_recompute_the_same(tmp_path):
    from cadsim.dataset import Dataset
    from cadsim.generation.pipeline import generate_dataset
    from cadsim.scenario import load_scenario

    scenario = load_scenario(ROOT / "scenarios" / "mrc-arena.toml")
    generate_dataset(scenario, tmp_path / "mrc", pairs=2, workers=1, progress=False)
    for pair in Dataset(tmp_path / "mrc"):
        stored = json.loads((pair.path / "record.json").read_text())["difficulty"]
        assert set(stored) == set(FACTORS)
        v1, v2 = pair.view1, pair.view2
        recomputed = difficulty_factors(
            v1.positions, v2.positions, v1.true_classes, v2.true_classes, pair.gt_pairs,
            pair.camera_to_world,
        )  # fmt: skip
        assert recomputed == stored == pair.difficulty
        problem = pair.problem()
        assert not any("difficulty" in name for name in vars(problem))  # never a matcher's input


def test_the_headline_leaves_a_dataset_at_the_ceiling_out_in_one_line(tmp_path):
    from eval.engine.difficulty_levels import write_levels
    from eval.report import levels_part

    n = 12
    levels = pd.DataFrame(
        {"dataset": ["CAD"] * n + ["MRC"] * n, "pair": list(range(n)) * 2, "level": "hard"}
    )
    rng = np.random.default_rng(3)
    cad = _per_pair(
        [], {"maximin": list(rng.uniform(0.3, 0.9, n)), "rrwm": list(rng.uniform(0.2, 0.8, n))}
    )
    mrc = _per_pair([], {"maximin": [1.0] * n, "rrwm": [1.0] * (n - 1) + [0.5]}).assign(
        dataset="MRC"
    )
    choice = {
        "level": "hard",
        "criterion": "test rule",
        "spread": {"easy": 0, "medium": 0, "hard": 1},
    }
    write_levels(
        tmp_path, "table1", pd.concat([cad, mrc]), levels, ["rrwm", "maximin"], extra=choice
    )
    lines = levels_part.table1(tmp_path)
    rows = [line for line in lines if line.startswith("| CAD")]
    assert len(rows) == 1 and "MDD" in rows[0]
    assert not any(line.startswith("| MRC") for line in lines)
    assert lines[-1].startswith("Level **hard**, chosen on validation")
    assert "at the ceiling on it" in lines[-1] and "MRC (" in lines[-1] and "100.0 %" in lines[-1]
