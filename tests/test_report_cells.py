"""Report cells hold data, never markup: a dataset label or matcher name with ``|``, ``<``,
``>``, ``[``, ``]`` or a backtick stays in its cell and reads as itself in README.md and
index.html; a text field beginning with ``=``, ``+``, ``-`` or ``@`` is written to our CSVs so
that a spreadsheet shows it as text instead of running it, and reads back unchanged."""

from __future__ import annotations

import pandas as pd
import pytest

from eval.core.result_files import write_csv
from eval.core.spreadsheet_safe import neutralise_text, restore, restore_text
from eval.protocol.claims import read_claims
from eval.report.markdown_cell import cell, row
from eval.report.site import _cells, inline

HOSTILE = [
    "cad|x",
    "<script>alert(1)</script>",
    "[x](javascript:alert(1))",
    "![i](http://example.com/i.png)",
    "`rm -rf`",
    "a\\|b",
    "two\nlines",
]


@pytest.mark.parametrize("label", HOSTILE)
def test_a_hostile_label_stays_one_cell_of_plain_text(label):
    line = row([label, "58.2"])
    assert len(_cells(line)) == 2  # the bar did not split the row
    html = inline(_cells(line)[0])
    assert "<script" not in html and "<a " not in html and "<img" not in html
    assert "<code>" not in html
    shown = " ".join(label.replace("\\|", "|").splitlines())
    assert html == inline(cell(shown)) and "\\" not in html.replace("\\\\", "")


def test_escaped_characters_read_back_as_themselves_in_the_site():
    assert cell("<b>[1]`x`") == "\\<b\\>\\[1\\]\\`x\\`"
    assert inline(cell("<b>[1]`x`")) == "&lt;b&gt;[1]`x`"
    assert cell(cell("a|b<c")) == cell("a|b<c")  # idempotent
    assert row(["+4.0 [-3.7, +11.6]"]) == "| +4.0 [-3.7, +11.6] |"  # the code's intervals


def test_the_report_modules_escape_dataset_labels():
    from eval.report.benchmark_parts import paired_markdown
    from eval.studies.external.agreement import to_markdown as agreement_markdown

    table = pd.DataFrame(
        [{"dataset": "cad|<x>", "reference": "[r](javascript:1)", "matchers": "sm;rrwm",
          "rho": 0.5, "ci_low": 0.1, "ci_high": 0.9}]
    )  # fmt: skip
    body = agreement_markdown(table).splitlines()[2]
    assert body.startswith("| cad\\|\\<x\\> | \\[r\\](javascript:1) | 2 |")
    paired = pd.DataFrame(
        [{"dataset": "cad|<x>", "matcher_b": "`sm`", "metric": m, "diff": 0.01, "ci_low": 0.0,
          "ci_high": 0.02, "mdd": 0.03, "episodes": 5} for m in ("f1", "recall")]
    )  # fmt: skip
    (line,) = [x for x in paired_markdown(paired).splitlines() if x.startswith("| cad")]
    assert line.startswith("| cad\\|\\<x\\> | \\`sm\\` | ") and len(_cells(line)) == 7


@pytest.mark.parametrize(
    "text, written",
    [
        ('=HYPERLINK("http://x","y")', '\'=HYPERLINK("http://x","y")'),
        ("+4.0 [-3.7, +11.6]", "'+4.0 [-3.7, +11.6]"),
        ("-cmd|' /C calc'!A0", "'-cmd|' /C calc'!A0"),
        ("@SUM(1)", "'@SUM(1)"),
        ("\t=1", "'\t=1"),
        ("'quoted", "''quoted"),
        ("-0.5", "-0.5"),
        ("+3", "+3"),
        ("maximin", "maximin"),
    ],
)
def test_formula_text_is_neutralised_and_restored(text, written):
    assert neutralise_text(text) == written
    assert restore_text(written) == text


def test_claims_csv_neutralises_and_reads_back(tmp_path):
    from eval.protocol.claims import COLUMNS

    claim = {c: "" for c in COLUMNS} | {
        "statement": '=HYPERLINK("http://evil","click")',
        "subject": "@cad",
    }
    frame = pd.DataFrame([claim], columns=list(COLUMNS))
    path = write_csv(frame, tmp_path / "claims.csv")
    raw = path.read_text()
    assert "'=HYPERLINK" in raw and "'@cad" in raw
    assert ",=HYPERLINK" not in raw and ",@cad" not in raw
    back = read_claims(path)
    assert back.loc[0, "statement"] == claim["statement"] and back.loc[0, "subject"] == "@cad"
    numbers = pd.DataFrame({"x": [-1.5, 2.0], "name": ["-", "a"]})
    assert restore(pd.read_csv(write_csv(numbers, tmp_path / "n.csv"))).equals(numbers)
