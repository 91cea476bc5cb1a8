"""Every registered traffic source generates without writing anything outside ``--out``: not in the
working directory, not beside its scenario file. A new source needs a scenario in ``scenarios/``
to run here, so it cannot skip this test (issue 22)."""

from __future__ import annotations

import os
import shutil
import tomllib
from pathlib import Path

import pytest

from cadsim.cli import main
from cadsim.sources import source_kinds

ROOT = Path(__file__).resolve().parents[1]


def _scenario_of(kind: str) -> Path | None:
    """The first shipped scenario whose traffic source is `kind`."""
    for path in sorted((ROOT / "scenarios").glob("*.toml")):
        if tomllib.loads(path.read_text()).get("traffic", {}).get("source") == kind:
            return path
    return None


def _listing(folder: Path) -> list[str]:
    return sorted(str(p.relative_to(folder)) for p in folder.rglob("*"))


@pytest.mark.slow
@pytest.mark.parametrize("kind", source_kinds())
def test_a_source_writes_only_into_out(kind, tmp_path, monkeypatch):
    scenario = _scenario_of(kind)
    assert scenario is not None, f"source {kind!r}: add a scenario to scenarios/ that uses it"
    here = tmp_path / "scenario"
    here.mkdir()
    shutil.copy(scenario, here / scenario.name)
    for extra in scenario.parent.glob("*.xml"):  # files a shipped scenario refers to
        shutil.copy(extra, here / extra.name)
    cwd = tmp_path / "cwd"
    cwd.mkdir()
    monkeypatch.chdir(cwd)
    before = _listing(tmp_path)
    out = tmp_path / "out"
    assert main(["generate", str(here / scenario.name), "--pairs", "1", "--workers", "1",
                 "--no-progress", "--out", str(out)]) == 0  # fmt: skip
    after = [p for p in _listing(tmp_path) if not p.startswith("out")]
    assert after == before  # nothing beside the scenario, nothing in the working directory
    assert os.listdir(out) and (out / "manifest.json").is_file()
