"""The published-benchmark harness (eval.validation.synthetic) on small but real runs."""

from __future__ import annotations

import argparse

import numpy as np
import pandas as pd
import pytest

from cadsim.cli import main as cadsim_main
from eval.validation import synthetic


def _args(**overrides) -> argparse.Namespace:
    parser = argparse.ArgumentParser()
    synthetic.add_arguments(parser)
    args = parser.parse_args(["--jobs", "1", "--no-progress"])
    for key, value in overrides.items():
        setattr(args, key, value)
    return args


def test_deformation_noise_free_is_solved_exactly():
    args = _args(matchers=["tm", "rrwhm", "bcagm"], trials=5, values=[0.0])
    trials = synthetic.run_protocol("deformation", args, progress=False)
    assert len(trials) == 5 * 3
    assert (trials["accuracy"] == 1.0).all(), trials
    table = synthetic.compare("deformation", trials, synthetic.PUBLISHED_ROWS)
    assert table["published"].tolist() == [1.0, 1.0, 1.0]
    assert (table["verdict"] == "ok").all()


def test_outlier_protocol_is_scale_invariant_and_compared():
    # 10 inliers scaled by 1.5 plus 10 outliers: the published RRWHM gets 0.988 here
    args = _args(matchers=["rrwhm"], trials=3, values=[10.0])
    trials = synthetic.run_protocol("outliers", args, progress=False)
    assert trials["accuracy"].mean() >= 0.9
    table = synthetic.compare("outliers", trials, synthetic.PUBLISHED_ROWS)
    assert table["published"].iloc[0] == pytest.approx(0.988)


def test_trials_are_seeded():
    setting = synthetic.PROTOCOLS["outliers"].settings(_args(values=[20.0]))[0]
    a = synthetic.make_trial(setting, 3, seed=5)
    b = synthetic.make_trial(setting, 3, seed=5)
    c = synthetic.make_trial(setting, 4, seed=5)
    np.testing.assert_array_equal(a.points2, b.points2)
    assert a.points2.shape == (30, 2) and not np.array_equal(a.points2, c.points2)
    np.testing.assert_allclose(a.points2[a.truth], 1.5 * a.points1, atol=0.2)  # sigma 0.03


def test_house_short_baseline_matches_published(tmp_path):
    out = tmp_path / "house.csv"
    code = synthetic.main(
        ["--protocol", "house", "--house-n1", "30", "--values", "10", "--house-pairs", "2"]
        + ["--matchers", "rrwhm", "--jobs", "1", "--no-progress", "--out", str(out)]
    )
    assert code == 0
    table = pd.read_csv(out)
    row = table.iloc[0]
    assert (row["group"], row["value"], row["n"]) == ("30 vs 30", 10.0, 2)
    assert row["ours"] == 1.0 and row["published"] == 1.0


def test_cadsim_subcommand_writes_markdown(tmp_path, capsys):
    out = tmp_path / "t.md"
    code = cadsim_main(
        ["synthetic", "--protocol", "deformation", "--values", "0.05", "--trials", "2"]
        + ["--matchers", "rrwhm", "sm", "--jobs", "1", "--no-progress", "--out", str(out)]
    )
    assert code == 0
    text = out.read_text()
    assert "| 0.05 |" in text and "RRWHM (pub)" in text and "0.984" in text
    assert "sm" in capsys.readouterr().out


def test_bad_setting_is_named():
    with pytest.raises(ValueError, match="0.33 is not a sigma setting"):
        synthetic.PROTOCOLS["deformation"].settings(_args(values=[0.33]))
