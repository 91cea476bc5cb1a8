"""A newcomer's first hour (fresh clone, README only): what they tried, now answered by the
software — an import path that does not import says why and how to fix it; ``cadsim evaluate
--reference NAME`` compares against any matcher; the README's API example uses a second view in
its own frame; ``cadsim show --matcher`` draws one pair's declared matches; the help texts list
every import format and show the link gate in metres."""

from __future__ import annotations

import re
from pathlib import Path

import pandas as pd
import pytest

from cadsim.cli import main

ROOT = Path(__file__).resolve().parents[1]
DMGM = ROOT / "eval" / "data" / "dmgm-cad" / "val-070"


def _error_line(capsys, command: str) -> str:
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"cadsim {command}: error: "), lines
    return lines[0]


def test_an_import_path_that_does_not_import_says_why_and_how(tmp_path, capsys):
    from eval.engine.matcher_list import parse_matchers

    with pytest.raises(ValueError) as caught:
        parse_matchers("sm,no_such_module_for_newcomers:match")
    message = str(caught.value)
    assert "module 'no_such_module_for_newcomers' could not be imported" in message
    assert "ModuleNotFoundError" in message and "PYTHONPATH" in message and "install" in message
    assert "available:" not in message
    args = ["evaluate", str(DMGM), "--matchers", "mymod:fn", "--out", str(tmp_path / "o")]
    assert main([*args, "--cache", str(tmp_path / "c"), "--no-calibration"]) == 2
    assert "ModuleNotFoundError: No module named 'mymod'" in _error_line(capsys, "evaluate")


def test_evaluate_reference_writes_the_differences_against_it(tmp_path, capsys):
    out = tmp_path / "out"
    args = ["evaluate", str(DMGM), "--matchers", "sm,maximin,appearance", "--runs", "1"]
    args += ["--no-calibration", "--no-progress", "--workers", "1", "--out", str(out)]
    args += ["--cache", str(tmp_path / "cache")]
    assert main([*args, "--reference", "SM"]) == 0
    paired = pd.read_csv(out / "paired_differences.csv")
    assert set(paired["matcher_a"]) == {"sm"} and set(paired["matcher_b"]) == {
        "maximin",
        "appearance",
    }
    capsys.readouterr()
    assert main([*args, "--reference", "rrwm"]) == 2
    assert "--reference: 'rrwm' is not one of the matchers evaluated" in _error_line(
        capsys, "evaluate"
    )


def test_the_readme_api_example_runs_with_a_second_view_in_its_own_frame(monkeypatch):
    from matchers.core import registry

    # the example registers "mine": on copies, so no later test sees it in the registry
    monkeypatch.setattr(registry, "_registered", dict(registry._registered))
    monkeypatch.setattr(registry, "_registered_spaces", dict(registry._registered_spaces))
    text = (ROOT / "README.md").read_text()
    block = text.split("## Adding a matcher or a scenario")[1].split("```python")[1].split("```")[0]
    assert "0.01" not in block and "world1/world2" in block and ") @ " in block
    scope: dict = {}
    exec(compile(block, "README.md", "exec"), scope)  # noqa: S102 - the README's own example
    assert sorted(map(tuple, scope["m"].pairs.tolist())) == [(0, 2), (1, 1), (3, 0), (5, 4), (7, 3)]


def test_show_matcher_draws_one_pairs_declared_matches(tmp_path, capsys):
    out = tmp_path / "pair.png"
    assert main(["show", str(DMGM), "--pair", "3", "--matcher", "maximin", "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    found = re.search(r"maximin: (\d+) correct, (\d+) wrong, (\d+) missed of (\d+) true", printed)
    assert found and out.stat().st_size > 0
    correct, _, missed, true = map(int, found.groups())
    assert correct + missed == true
    args = ["show", str(DMGM), "--threshold", "0.5", "--out", str(tmp_path / "x.png")]
    assert main(args) == 2
    assert "--threshold: needs --matcher" in _error_line(capsys, "show")


def test_import_help_lists_every_format_and_the_link_gate_in_metres(capsys):
    with pytest.raises(SystemExit):
        main(["import", "--help"])
    text = capsys.readouterr().out
    for name in ("dmgm", "v2x-seq", "opv2v", "v2v4real", "dair-v2x"):
        assert f"cadsim import {name} " in text, name
    assert "V2V4Real" in text and "DAIR-V2X" in text
    with pytest.raises(SystemExit):
        main(["import", "dair-v2x", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert "(default: 1.0 m)" in text and "LINK_GATE_M" not in text
