"""The report's appendix: every table and figure of the folder not shown in full above, and
its data files."""

from __future__ import annotations

from pathlib import Path

REPORT, SITE = "README.md", "index.html"


# Figures a results folder may hold that no part above shows, and what they show.
FIGURE_CAPTIONS = {
    "pr_curves.png": "Pooled precision–recall curves per dataset and matcher (test pairs)",
    "fig_localisation_presets.png": "CAD-V2X: F1 and the pose metrics against the localisation "
    "preset's error scale and latency",
}


def appendix(results: Path, body: str, rel: str) -> list[str]:
    """Every Markdown table and PNG figure of ``results`` that ``body`` does not show in full,
    then a list of the folder's data files."""
    tables = []
    for path in sorted(results.glob("*.md")):
        text = path.read_text().strip() if path.name != REPORT else ""
        if text and text not in body:
            tables += [f"### {path.name}", "", text, ""]
    figures = []
    for path in sorted(results.rglob("*.png")):
        name = path.relative_to(results).as_posix()
        if f"]({rel}/{name})" not in body:
            caption = FIGURE_CAPTIONS.get(name, name)
            figures += [f"### {name}", "", f"![{caption}]({rel}/{name})", ""]
    files = [
        f"[{p.name}]({rel}/{p.name})"
        for p in sorted(results.iterdir())
        if p.is_file() and p.suffix in (".csv", ".json", ".tex", ".pdf") and p.name != SITE
    ]
    folders = [f"`{p.name}/`" for p in sorted(results.iterdir()) if p.is_dir()]
    out = []
    if tables or figures:
        out += [
            "## Every other table and figure",
            "",
            "Written by the same run, not shown in full above.",
            "",
        ]
        out += tables + figures
    if files or folders:
        out += ["## Files", ""]
        out += [f"Data: {', '.join(files)}." if files else ""]
        out += (
            ["", f"Per-study folders (evaluation files of each part): {', '.join(folders)}."]
            if folders
            else []
        )
        out += [""]
    return out
