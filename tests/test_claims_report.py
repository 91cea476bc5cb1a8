"""The generated report makes no comparative statement without a claim behind it: every "met /
not met / not shown", "ahead", "leader", "favours", "gain", "crossover" phrase of the report
(``results/README.md``) and of the README's results section, rendered from the committed
results, is the statement of a ``claims.csv`` row, and no claim was chosen on test."""

from pathlib import Path

import pytest

from eval.claims import build_claims, write_claims
from eval.claims.coverage import unbacked
from eval.protocol.claims import COLUMNS, VERDICTS, read_claims
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
    assert "test" not in set(claims["chosen_on"])
    # the findings: Table I's rival chosen on validation with its interval, Fig. 4's leaders
    # labelled point values, the image-only AUC without an interval "not shown", timing goals
    # point measurements, DMGM's blocks not independent
    rivals = claims[(claims["study"] == "table1") & (claims["direction"] == "diff")]
    assert set(rivals["chosen_on"]) == {"validation"} and rivals["ci_low"].notna().all()
    assert set(claims.loc[claims["study"] == "fig4", "verdict"]) == {"point value"}
    image = claims[claims["metric"].str.contains("image-only AUC", regex=False)]
    assert list(image["verdict"]) == ["not shown"]
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
        "F1 leader at 0: Maximin 80.0 (point value)",
        "F1 leader at 0.1: MOS 30.0 (point value)",
    ]
    assert claims["ci_low"].isna().all() and set(claims["chosen_on"]) == {"fixed"}
