"""The README is a first page (short, the two commands, links that resolve) and the results report
renders: results/README.md's links resolve, and results/index.html, written from the committed
results, loads in headless Chromium with every table and figure (skipped without Chromium;
`make test` installs it where it may)."""

from __future__ import annotations

import re
import shutil
import subprocess
from html.parser import HTMLParser
from pathlib import Path
from urllib.parse import unquote, urlsplit

import pytest

from eval.readme_results import write_report
from eval.report.site import anchors, slug, to_html

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"
RESULTS = ROOT / "results"
MAX_README_LINES = 150
LINK = re.compile(r"!?\[[^\]]*\]\(([^)\s]+)\)")
TABLE_RULE = re.compile(r"^\s*\|?\s*:?-{3,}:?\s*(\|\s*:?-{3,}:?\s*)*\|?\s*$")


def _links(path: Path) -> list[str]:
    """Relative link and image targets of a Markdown file (code blocks skipped)."""
    text = re.sub(r"```.*?```", "", path.read_text(), flags=re.DOTALL)
    text = re.sub(r"`[^`]*`", "", text)
    return [t for t in LINK.findall(text) if not urlsplit(t).scheme and not t.startswith("#")]


def _unresolved(source: Path) -> list[str]:
    """Links of ``source`` whose file is missing, or whose ``#anchor`` names no heading of the
    Markdown file (no element id of the HTML file) it points into."""
    bad = []
    for target in _links(source):
        parts = urlsplit(target)
        path = (source.parent / unquote(parts.path)).resolve()
        if not path.exists():
            bad.append(f"{target}: no such file")
            continue
        if parts.fragment:
            if path.suffix == ".md":
                known = anchors(path.read_text())
            elif path.suffix == ".html":
                known = re.findall(r'\bid="([^"]+)"', path.read_text())
            else:
                known = []
            if parts.fragment not in known:
                bad.append(f"{target}: no anchor #{parts.fragment} in {path.name}")
    return bad


def test_the_readme_is_a_first_page():
    lines = README.read_text().splitlines()
    assert len(lines) <= MAX_README_LINES, f"README.md has {len(lines)} lines"


def test_the_quick_start_is_the_two_make_commands():
    text = README.read_text()
    section = text.split("## Quick start", 1)[1].split("\n## ", 1)[0]
    block = section.split("```bash\n", 1)[1].split("```", 1)[0]
    commands = [line.split("#", 1)[0].strip() for line in block.splitlines() if line.strip()]
    assert commands == ["make reproduce", "make test"]


def test_every_readme_link_resolves_into_the_report():
    links = _links(README)
    assert any(t.startswith("results/README.md#") for t in links)
    assert "results/index.html" in links and "results/qualitative.png" in links
    assert _unresolved(README) == []


def test_every_report_link_resolves():
    assert _unresolved(RESULTS / "README.md") == []


def test_slugs_are_githubs_anchors():
    assert slug("Table I") == "table-i"
    assert slug("Fig. 4 — against depth noise (CAD, as in the paper, and MRC)") == (
        "fig-4--against-depth-noise-cad-as-in-the-paper-and-mrc"
    )
    assert slug("`table_v2x.md`") == "table_v2xmd"
    assert anchors("# A\n```\n# not a heading\n```\n## A\n") == ["a", "a-1"]


def test_markdown_subset_to_html():
    body = to_html(
        "### A & B\n\n| Name | F1 |\n|:---|---:|\n| `a*b` <x> | **1.0** |\n\n"
        "- one [link](./t.md)\n- *two*\n\n![cap](f.png)\n",
        links={"./t.md": "#t"},
    )
    assert '<h3 id="a--b">A &amp; B</h3>' in body
    assert (
        '<th class="right">F1</th>' in body
        and '<td class="right"><strong>1.0</strong></td>' in body
    )
    assert "<td><code>a*b</code> &lt;x&gt;</td>" in body
    assert '<li>one <a href="#t">link</a></li>' in body and "<li><em>two</em></li>" in body
    assert '<img src="f.png" alt="cap"' in body and "<figcaption>cap</figcaption>" in body


def _chromium() -> str | None:
    for name in ("chromium", "chromium-browser"):
        found = shutil.which(name)
        if found:
            return found
    return "/usr/bin/chromium" if Path("/usr/bin/chromium").is_file() else None


class _Page(HTMLParser):
    """Tables, image sources and the attributes of <html> in a dumped DOM."""

    def __init__(self) -> None:
        super().__init__()
        self.tables = 0
        self.images: list[str] = []
        self.root: dict[str, str | None] = {}

    def handle_starttag(self, tag, attrs):
        if tag == "table":
            self.tables += 1
        elif tag == "img":
            self.images.append(dict(attrs).get("src") or "")
        elif tag == "html":
            self.root = dict(attrs)


def _markdown_tables(text: str) -> int:
    return sum(1 for line in text.splitlines() if TABLE_RULE.match(line) and "|" in line)


def test_the_report_renders_in_headless_chromium(tmp_path):
    chromium = _chromium()
    if chromium is None:
        pytest.skip("chromium not found (make test installs it as root with apt: `chromium`)")
    # the report written from the committed results, in a folder of links to their files
    results = tmp_path / "results"
    results.mkdir()
    for entry in RESULTS.iterdir():
        if entry.name not in ("README.md", "index.html", "claims.csv"):  # what the report writes
            (results / entry.name).symlink_to(entry)
    report, site = write_report(results)
    markdown = report.read_text()
    for table in sorted(RESULTS.glob("*.md")):  # every table file of the run, in full
        if table.name != "README.md":
            assert table.read_text().strip() in markdown, table.name
    figures = sorted(p.relative_to(RESULTS).as_posix() for p in RESULTS.rglob("*.png"))
    assert figures and all(f"](./{f})" in markdown for f in figures)

    def chromium_run(*options: str) -> subprocess.CompletedProcess:
        flags = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking"]
        flags += ["--disable-component-update", "--disable-sync", "--no-first-run"]
        flags += [f"--user-data-dir={tmp_path / 'profile'}", "--virtual-time-budget=5000"]
        return subprocess.run(
            [chromium, *flags, *options, site.as_uri()],
            capture_output=True,
            text=True,
            timeout=60,
            stdin=subprocess.DEVNULL,
        )

    dom = chromium_run("--dump-dom")
    assert dom.returncode == 0, dom.stderr[-2000:]
    page = _Page()
    page.feed(dom.stdout)
    tables = _markdown_tables(markdown)
    assert tables > 0 and page.tables == tables
    assert page.root.get("data-sortable-tables") == str(tables)  # the page's script ran
    shown = [unquote(src).removeprefix("./") for src in page.images]
    assert sorted(set(shown)) == figures
    assert page.root.get("data-figures-loaded") == f"{len(shown)}/{len(shown)}"  # all decoded

    screenshot = tmp_path / "report.png"
    shot = chromium_run(
        "--hide-scrollbars", "--window-size=1280,2400", f"--screenshot={screenshot}"
    )
    assert shot.returncode == 0, shot.stderr[-2000:]
    assert screenshot.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
