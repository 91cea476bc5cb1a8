"""Writes the results section of README.md from a results directory, so that every number the
README shows comes from a run of ``make reproduce`` (called at its end for the default output
directory). The section sits between ``<!-- results:begin -->`` and ``<!-- results:end -->``."""

from __future__ import annotations

import json
import os
from pathlib import Path

BEGIN, END = "<!-- results:begin -->", "<!-- results:end -->"


def results_section(results: Path, readme_dir: Path) -> str:
    """Markdown: Table I, Fig. 4, the qualitative figure and the run's wall times."""
    results = Path(results)
    rel = Path(os.path.relpath(results, readme_dir)).as_posix()
    record = json.loads((results / "run_record.json").read_text())
    table = (results / "table1.md").read_text().strip()
    sweep = record.get("noise_sweep", {})
    wall = record.get("wall_s", {})
    git = record.get("git", {})
    times = ", ".join(f"{k.replace('_', ' ')} {v:.0f} s" for k, v in wall.items() if k != "total")
    runs = record.get("runs", {}).values()
    computed = sum(r.get("computed", 0) for r in runs)
    cached = sum(r.get("cached", 0) for r in runs)
    rates = ", ".join(f"{r:g}" for r in sweep.get("rates", []))
    return "\n".join(
        [
            f"Produced by `{record.get('command', 'make reproduce')}` on {record.get('created', '?')}"
            f" at commit `{str(git.get('commit', '?'))[:10]}`"
            + (" (with uncommitted changes)" if git.get("dirty") else "")
            + f"; wall time {wall.get('total', float('nan')):.0f} s ({times}; "
            f"{computed} matcher runs computed, {cached} taken from the result cache).",
            "",
            "### Table I",
            "",
            table,
            "",
            "τ is each matcher's acceptance threshold, calibrated on the validation datasets "
            "(other simulation seeds), never on the test pairs. AP: area under the precision–recall "
            "curve swept over τ.",
            "",
            "### Fig. 4 — CAD, against depth noise",
            "",
            f"![Fig. 4: accuracy, precision, recall against noise rate]({rel}/fig4.png)",
            "",
            f"noise_rate ∈ {{{rates}}} (σ = noise_rate · d²), {len(sweep.get('seeds', []))} runs, "
            f"first {sweep.get('pairs') or 'all'} test pairs; each rate re-applies noise to the "
            "stored clean depth and re-detects (no re-rendering).",
            "",
            "### Qualitative (the paper's Fig. 3 style)",
            "",
            f"![Qualitative: RRWHM, MOS, maximin on one MRC and one CAD pair]({rel}/qualitative.png)",
            "",
            "Green: correct match, red: wrong match, yellow dashed: missed (false negative).",
        ]
    )


def update_readme(readme: Path, results: Path) -> bool:
    """Replace the README's results section; False (README untouched) if it has no markers."""
    readme = Path(readme)
    text = readme.read_text()
    if BEGIN not in text or END not in text:
        return False
    head, rest = text.split(BEGIN, 1)
    _, tail = rest.split(END, 1)
    body = results_section(Path(results), readme.parent)
    readme.write_text(f"{head}{BEGIN}\n{body}\n{END}{tail}")
    return True
