"""The example scripts run as documented (docs/api.md)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pandas as pd

ROOT = Path(__file__).resolve().parents[1]


def test_the_api_tour_runs_and_writes_table1(tmp_path):
    env_out = tmp_path / "tour"
    proc = subprocess.run(
        [sys.executable, str(ROOT / "examples" / "api_tour.py"), str(env_out)],
        capture_output=True, text=True, timeout=600, cwd=tmp_path,
        env={**__import__("os").environ, "CADSIM_CACHE_DIR": str(tmp_path / "cache")},
    )  # fmt: skip
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert "maximin on pair 0: precision" in proc.stdout
    table = pd.read_csv(env_out / "table1.csv")
    assert set(table["matcher"]) == {"sm", "maximin", "nearest_appearance"}
    assert (table["f1_mean"] >= 0).all()


def test_a_matcher_named_by_import_path_is_evaluated():
    from eval.engine.matcher_list import parse_matchers
    from matchers import get

    assert [m.name for m in parse_matchers("matchers.rrwm:rrwm")] == ["matchers.rrwm:rrwm"]
    assert get("matchers.rrwm:rrwm") is get("rrwm")
    from matchers import available

    assert "matchers.rrwm:rrwm" not in available()  # an import path is not registered
