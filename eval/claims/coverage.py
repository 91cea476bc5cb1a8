"""Which comparative phrases of a rendered report have no claim behind them.

A report line may carry a comparative word ("met", "not shown", "ahead", "behind", "leader",
"favours", "gain", "crossover", …) only inside the statement of a claim of ``claims.csv``, inside
a definition of a term (:data:`DEFINITIONS`: how a verdict is read, what a column holds), in a
file name or link, or in a table header that labels its column a point value. :func:`unbacked` lists the rest; the report
test requires it to be empty.
"""

from __future__ import annotations

import re

import pandas as pd

COMPARATIVE = re.compile(
    r"\b(not met|not shown|met|ahead|behind|leaders?|leads|trails|overtakes|favours|gains?|"
    r"crossovers?|beats|outperforms?|ranks? \d+ of|unlike the paper|"
    r"(?:within|inside|outside|above|below) the [^;|]{0,30}?goal)\b",
    re.IGNORECASE,
)

# Phrases that define a term or say how a verdict is read; they state no comparison.
DEFINITIONS = (
    "a crossover is stated only where its interval, episodes and thinning draws resampled, "
    'excludes "no crossing"',
    "Written by the same run, not shown in full above.",
    "F1 gain: pooled F1 minus `independent`'s (same matcher, preset and N)",
    "over the table's 84 gains",
    "a gain is shown at the 5 % level when its adjusted p ≤ 0.05",
    "F1 gain (Holm-adjusted p",
    "a sensor favours the family only where the difference stays beyond 0 after Holm's adjustment",
    "the goals and their verdicts in the report",
    "its interval the largest ends",
    "Crossovers:",  # points at crossovers.csv, whose rows are claims above
)
_FILES = re.compile(r"\[[^\]]*\]\([^)]*\)|`?[\w./-]+\.(?:csv|md|json|png|pdf|tex)`?")


def unbacked(text: str, claims: pd.DataFrame) -> list[str]:
    """The lines of ``text`` (Markdown) that still hold a comparative word once every claim
    statement of ``claims`` and every definition is taken out of them."""
    said = sorted({str(s) for s in claims["statement"] if str(s)}, key=len, reverse=True)
    out = []
    for line in text.splitlines():
        rest = line
        for phrase in (*said, *DEFINITIONS):
            if phrase in rest:
                rest = rest.replace(phrase, " ")
        rest = _FILES.sub(" ", rest)  # file names and links name no comparison
        if line.startswith("|"):  # a header may name a comparison it labels a point value
            rest = re.sub(r"[^|]*\(point values?\)[^|]*", " ", rest)
        if COMPARATIVE.search(rest):
            out.append(line)
    return out
