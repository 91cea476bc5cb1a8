"""The user documentation reads as documentation of the suite, not of its development: no issue
numbers, work rounds, design-card sections or paths outside the repository in README.md or docs/
(history lives in CHANGELOG.md)."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
FORBIDDEN = re.compile(
    r"issue \d+|this round|(first|second|third|fourth) round|DESIGN §|\.\./shared", re.IGNORECASE
)
DOCS = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]


@pytest.mark.parametrize("path", DOCS, ids=lambda p: p.name)
def test_no_development_history_in_user_docs(path):
    found = [
        f"{path.name}:{n}: {line.strip()[:100]}"
        for n, line in enumerate(path.read_text().splitlines(), 1)
        if FORBIDDEN.search(line)
    ]
    assert not found, "\n".join(found)


def test_the_changelog_and_citation_exist():
    assert (ROOT / "CHANGELOG.md").read_text().startswith("# Changelog")
    citation = (ROOT / "CITATION.cff").read_text()
    assert "cff-version:" in citation and "Maximin Hypergraph Matching" in citation
