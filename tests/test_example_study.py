"""The worked example study (examples/dense_arena/) runs as documented on a tiny dataset: its
stages generate and evaluate, its table, claim and report part come out, and the docs' example is
this file."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pandas as pd

from eval.protocol.claims import read_claims

ROOT = Path(__file__).resolve().parents[1]
EXAMPLE = ROOT / "examples" / "dense_arena" / "study.py"


def test_the_example_study_runs_alone_and_reports_its_claim(tmp_path):
    options = ["--pairs", "2", "--val-pairs", "2", "--matchers", "sm,maximin", "--runs", "1"]
    options += ["--no-tune", "--workers", "1", "--no-progress"]
    options += ["--out", "out", "--data", "data", "--cache", "cache"]
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    proc = subprocess.run(
        [sys.executable, str(EXAMPLE), *options], capture_output=True, text=True, timeout=600,
        cwd=tmp_path, env=env,
    )  # fmt: skip
    assert proc.returncode == 0, proc.stderr[-3000:]
    table = pd.read_csv(tmp_path / "out" / "table_dense_arena.csv")
    assert list(table["matcher"]) == ["sm", "maximin"]
    assert ((table["f1_low"] <= table["f1_mean"]) & (table["f1_mean"] <= table["f1_high"])).all()
    claims = read_claims(tmp_path / "out" / "claims.csv")
    mine = claims[claims["study"] == "dense_arena"].iloc[0]
    best = table.loc[table["val_f1"].idxmax(), "matcher"]
    assert (mine["subject"], mine["bar"], mine["direction"]) == (best, 50.0, ">=")
    assert mine["chosen_on"] == "validation" and mine["source"] == "table_dense_arena.csv"
    report = (tmp_path / "out" / "README.md").read_text()
    assert "### Dense arena" in report and mine["statement"] in report
    assert sorted(p.name for p in (tmp_path / "data").iterdir()) == ["dense_arena", "dense_arena-val"]  # fmt: skip
    again = subprocess.run(
        [sys.executable, str(EXAMPLE), *options], capture_output=True, text=True, timeout=600,
        cwd=tmp_path, env=env,
    )  # fmt: skip
    assert again.returncode == 0 and "(0 new)" in again.stderr  # datasets resumed, not redone


def test_the_docs_example_is_the_file_the_test_runs():
    doc = (ROOT / "docs" / "architecture.md").read_text()
    blocks = re.findall(r"```python\n# examples/dense_arena/study\.py\n(.*?)```", doc, re.S)
    assert blocks, "docs/architecture.md shows examples/dense_arena/study.py"
    source = EXAMPLE.read_text()
    for block in blocks:
        for line in block.splitlines():
            if line.strip() and line.strip() != "...":
                assert line in source, f"docs/architecture.md: {line!r} is not in {EXAMPLE.name}"
