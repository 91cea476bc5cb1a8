"""The generated report makes no comparative statement without a claim behind it: every "met /
not met / not shown", "ahead", "leader", "favours", "gain", "crossover" phrase of the report
(``results/README.md``) and of the README's results section, rendered from the committed
results, is the statement of a ``claims.csv`` row, and no claim was chosen on test."""

from pathlib import Path

import pytest

from eval.claims import build_claims, write_claims
from eval.claims.coverage import unbacked
from eval.protocol.claims import COLUMNS, VERDICTS, read_claims
from eval.protocol.goal_verdict import verdict
from eval.readme_results import report_markdown, summary_section

RESULTS = Path(__file__).resolve().parents[1] / "results"
needs_results = pytest.mark.skipif(
    not (RESULTS / "table1.csv").is_file(), reason="no committed results/ in this checkout"
)


@needs_results
def test_every_comparative_phrase_of_the_generated_report_is_a_claim():
    claims = build_claims(RESULTS)
    text = report_markdown(RESULTS, claims) + "\n" + summary_section(RESULTS, RESULTS.parent)
    assert unbacked(text, claims) == []
    assert len(claims) > 40  # every study of the committed run states some
    assert set(claims["verdict"]) <= set(VERDICTS)
    # chosen on test only for a point value that says so: Fig. 4's and the external leaders
    on_test = claims[claims["chosen_on"] == "test"]
    assert set(on_test["verdict"]) == {"point value"} and set(on_test["study"]) == {
        "fig4",
        "external",
    }
    assert on_test["statement"].str.contains("chosen on test|a point value").all()
    # every goal's bar is its declaration's: none read from a second number of its text
    goals = claims[claims["comparison"] == "goal"].set_index("metric")
    tracker = (
        "own tracker: ≥ 90 % of consecutive detections on one track for objects moving ≥ 10 m/s"
    )
    assert set(goals.loc[[tracker], "bar"]) == {90.0}
    assert goals["bar"].notna().all()
    # the findings: Table I's rival chosen on validation with its interval, Fig. 4's leaders
    # labelled point values, the image-only AUC's verdict read off its interval, timing goals
    # point measurements, DMGM's blocks not independent
    rivals = claims[(claims["study"] == "table1") & (claims["direction"] == "diff")]
    assert set(rivals["chosen_on"]) == {"validation"} and rivals["ci_low"].notna().all()
    assert set(claims.loc[claims["study"] == "fig4", "verdict"]) == {"point value"}
    image = claims[claims["metric"].str.contains("image-only AUC", regex=False)].iloc[0]
    assert image["ci_low"] <= image["value"] <= image["ci_high"]  # an episode interval, and
    assert image["verdict"] == verdict(image["ci_low"], image["ci_high"], image["bar"], False)
    timed = claims[claims["metric"] == "seconds (last cold run)"]
    assert len(timed) and set(timed["verdict"]) == {"point measurement"}
    dmgm = claims[(claims["study"] == "transfer") & claims["ci_low"].notna()]["clusters"]
    assert len(dmgm) and dmgm.str.contains("not independent").all()


@needs_results
def test_a_comparative_sentence_without_a_claim_is_caught():
    claims = build_claims(RESULTS)
    lines = [
        "- maximin is ahead of MOS on CAD.",
        "| Dataset | F1 leader at 0 |",
        "- image-only AUC 0.778 — within the ≤ 0.75 goal.",
        "- this table's stages ≤ 2 min cold: met — 42 s.",
    ]
    assert unbacked("\n".join(lines), claims) == lines
    labelled = "| Dataset | F1 leader at 0 (point value) | at 0.1 (point value) |"
    assert unbacked(labelled, claims) == []


def test_claims_csv_is_written_with_its_columns(tmp_path):
    (tmp_path / "noise_runs.csv").write_text(
        "dataset,matcher,noise_rate,seed,f1\nCAD,maximin,0.0,0,0.8\nCAD,mos,0.0,0,0.7\n"
        "CAD,maximin,0.1,0,0.2\nCAD,mos,0.1,0,0.3\n"
    )
    path = write_claims(tmp_path)
    claims = read_claims(path)
    assert list(claims.columns) == list(COLUMNS)
    assert list(claims["statement"]) == [
        "F1 leader at 0: Maximin 80.0 (point value, chosen on test)",
        "F1 leader at 0.1: MOS 30.0 (point value, chosen on test)",
    ]
    assert claims["ci_low"].isna().all() and set(claims["chosen_on"]) == {"test"}


def test_the_realism_goals_read_the_episode_interval_of_the_auc(tmp_path):
    from eval.studies.v2x.realism import realism_check, realism_claims

    (tmp_path / "regime.csv").write_text(
        "dataset,appearance_auc,image_auc,same_class_auc\nCAD-V2X,0.84,0.745,\n"
    )
    point = realism_check(tmp_path)
    assert all(": not shown — " in line and "(no interval)" in line for line in point)
    (tmp_path / "regime_auc_intervals.csv").write_text(
        "dataset,appearance_auc,appearance_auc_low,appearance_auc_high,image_auc,image_auc_low,"
        "image_auc_high,episodes\nCAD-V2X,0.84,0.81,0.87,0.745,0.696,0.792,13\n"
    )
    claims = realism_claims(tmp_path)
    assert [(c.bar, c.direction, c.chosen_on) for c in claims] == [
        (0.6, ">=", "fixed"), (0.8, "<=", "fixed"), (0.75, "<=", "fixed")
    ]  # fmt: skip
    whole_low, whole_high, image = (c.statement for c in claims)
    assert "AUC ≥ 0.60: met — 0.840 [0.810, 0.870]" in whole_low
    assert "AUC ≤ 0.80: not met — 0.840 [0.810, 0.870]" in whole_high
    # the point value 0.745 is within the goal, its interval is not: not shown
    assert "image-only AUC ≤ 0.75: not shown — 0.745 [0.696, 0.792]" in image
    assert "95 % interval over its 13 episodes" in image
