"""The README's one-minute tutorial runs as written (its commands, in a fresh folder)."""

from __future__ import annotations

import shlex
from pathlib import Path

import pytest

from cadsim.cli import main

ROOT = Path(__file__).resolve().parents[1]


def tutorial_commands() -> list[list[str]]:
    text = (ROOT / "README.md").read_text()
    block = text.split("<!-- tutorial:begin -->")[1].split("<!-- tutorial:end -->")[0]
    commands = []
    for line in block.splitlines():
        if line.startswith(".venv/bin/cadsim "):
            argv = shlex.split(line, comments=True)[1:]
            commands.append([str(ROOT / a) if a.startswith("scenarios/") else a for a in argv])
    return commands


@pytest.mark.slow
def test_the_readme_tutorial_runs(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    commands = tutorial_commands()
    assert [c[0] for c in commands] == ["generate", "generate", "evaluate", "show"]
    for argv in commands:
        assert main(argv) == 0, argv
    out = capsys.readouterr().out
    assert "| Maximin |" in out and "| SM |" in out
    assert "one run: every ± 0.0 is no spread measured" in out  # what ± 0.0 means
    assert "from the paper's own data and protocol, not these pairs" in out
    assert (tmp_path / "tutorial" / "pair0.png").stat().st_size > 0
    assert (tmp_path / "tutorial" / "results" / "metrics_per_pair.csv").is_file()
