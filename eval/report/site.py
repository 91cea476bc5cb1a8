"""The results report as one static HTML page (``results/index.html``), made from the report's
Markdown (``results/README.md``): the same headings, figures and tables, the tables sortable by
clicking a column header. Plain HTML, inline CSS and a few lines of vanilla JavaScript — nothing
is fetched at run time, so the page opens from disk (``file://``) with no network.

Only the Markdown subset the report uses is understood: ATX headings, pipe tables (with their
alignment row), a figure on a line of its own, ``- `` bullets, fenced code, paragraphs, and inline
code, links, images, ``**bold**`` and ``*emphasis*``. Heading ids follow GitHub's anchors
(:func:`slug`), so ``#table-i`` points at the same section in README.md and in index.html.

Link and image targets are data (a plug-in's name, a ``--label``, a run record's command can put
Markdown into the report): only a relative target, an anchor, or an ``http``/``https``/``mailto``
address becomes an ``href``/``src`` (:func:`safe_target`); any other scheme (``javascript:``,
``data:``, ``vbscript:``, ``file:``) is shown as its text, never made live. A table cell's
``\\|`` is a literal bar (:mod:`eval.report.markdown_cell` writes it).
"""

from __future__ import annotations

import html
import re
from pathlib import Path

from eval.core.result_files import write_text

_CODE = re.compile(r"`([^`]+)`")
_IMAGE = re.compile(r"!\[([^\]]*)\]\(([^)\s]+)\)")
_LINK = re.compile(r"\[([^\]]+)\]\(([^)\s]+)\)")
_BOLD = re.compile(r"\*\*(?=\S)(.+?)(?<=\S)\*\*")
_EMPHASIS = re.compile(r"(?<![*\w])\*(?=\S)([^*]+?)(?<=\S)\*(?![*\w])")
_HEADING = re.compile(r"^(#{1,6})\s+(.*?)\s*#*\s*$")
_FIGURE = re.compile(r"^!\[([^\]]*)\]\(([^)\s]+)\)\s*$")
_ALIGN = re.compile(r"^\s*\|?\s*:?-{3,}:?\s*(\|\s*:?-{3,}:?\s*)*\|?\s*$")
_SCHEME = re.compile(r"^([A-Za-z][A-Za-z0-9+.\-]*):")
_SAFE_SCHEMES = ("http", "https", "mailto")


def safe_target(url: str) -> bool:
    """Whether ``url`` (unescaped) may become a live link or image source: no scheme (a relative
    path, ``#anchor``, ``?query``) or http/https/mailto — read as a browser reads it (tabs and
    line breaks removed, leading controls and spaces stripped)."""
    cleaned = re.sub(r"[\t\n\r]", "", url).lstrip("".join(map(chr, range(33))))
    match = _SCHEME.match(cleaned)
    return match is None or match[1].lower() in _SAFE_SCHEMES


def slug(text: str) -> str:
    """GitHub's heading anchor: markup dropped, lower case, every character but letters, digits,
    ``_``, ``-`` and spaces removed, spaces turned into ``-``."""
    plain = _LINK.sub(r"\1", _CODE.sub(r"\1", text)).replace("**", "").replace("*", "")
    return re.sub(r"[^\w\- ]", "", plain.strip().lower()).replace(" ", "-")


def headings(markdown: str) -> list[tuple[str, str]]:
    """(text, anchor) of every heading of ``markdown``, in order (code blocks skipped), repeated
    anchors numbered as GitHub does (``x``, ``x-1``, ``x-2``)."""
    seen: dict[str, int] = {}
    out = []
    fenced = False
    for line in markdown.splitlines():
        if line.startswith("```"):
            fenced = not fenced
        match = None if fenced else _HEADING.match(line)
        if match:
            out.append((match.group(2), _unique(slug(match.group(2)), seen)))
    return out


def anchors(markdown: str) -> list[str]:
    """The anchors of every heading of ``markdown`` (:func:`headings`)."""
    return [anchor for _, anchor in headings(markdown)]


def _unique(anchor: str, seen: dict[str, int]) -> str:
    count = seen.get(anchor, 0)
    seen[anchor] = count + 1
    return anchor if count == 0 else f"{anchor}-{count}"


def _plain(escaped: str) -> str:
    return html.unescape(escaped)


def _attr(escaped: str) -> str:
    """An attribute value from text already escaped for element content."""
    return html.escape(html.unescape(escaped))


_ESCAPABLE = "\\`*_[]<>()!#|"
"""Characters a backslash makes literal (CommonMark's backslash escapes, the ones the report's
cells use: :mod:`eval.report.markdown_cell`)."""
_HELD = {ch: chr(0xE000 + k) for k, ch in enumerate(_ESCAPABLE)}  # private-use stand-ins


def _hold_escapes(text: str) -> str:
    """``text`` with each backslash-escaped character replaced by a private-use stand-in, so
    that no code span, link, emphasis or tag starts from it."""
    return re.sub(r"\\([\\`*_\[\]<>()!#|])", lambda m: _HELD[m[1]], text)


def _release_escapes(html_text: str) -> str:
    """The stand-ins of :func:`_hold_escapes` back as (HTML-escaped) literal characters."""
    for ch, held in _HELD.items():
        html_text = html_text.replace(held, html.escape(ch))
    return html_text


def inline(text: str, links: dict[str, str] | None = None) -> str:
    """One line of Markdown as HTML (escaped; code spans kept literal; a backslash-escaped
    character shown as itself)."""
    return _release_escapes(_inline(_hold_escapes(text), links))


def _inline(text: str, links: dict[str, str] | None = None) -> str:
    links = links or {}
    parts = _CODE.split(text)  # even: text, odd: code
    out = []
    for k, part in enumerate(parts):
        if k % 2:
            out.append(f"<code>{html.escape(part)}</code>")
            continue
        escaped = html.escape(part, quote=False)
        escaped = _IMAGE.sub(_image, escaped)
        escaped = _LINK.sub(lambda m: _link(m, links), escaped)
        escaped = _BOLD.sub(r"<strong>\1</strong>", escaped)
        out.append(_EMPHASIS.sub(r"<em>\1</em>", escaped))
    return "".join(out)


def _live(escaped: str) -> bool:
    """Whether a target (escaped text) is safe however often it is unescaped: the attribute
    written is ``_attr(target)``, whose value the browser unescapes once more."""
    plain = _plain(escaped)
    return safe_target(plain) and safe_target(_plain(plain))


def _image(m: re.Match) -> str:
    if not _live(m[2]):
        return m[1]  # the alt text only
    return f'<img src="{_attr(m[2])}" alt="{_attr(m[1])}">'


def _link(m: re.Match, links: dict[str, str]) -> str:
    target = links.get(_plain(m[2]), _plain(m[2]))
    if not (_live(m[2]) and safe_target(target) and safe_target(_plain(target))):
        return m[1]  # the link's text only
    return f'<a href="{_attr(target)}">{m[1]}</a>'


def _cells(line: str) -> list[str]:
    line = line.strip()
    if line.startswith("|"):
        line = line[1:]
    if line.endswith("|") and not line.endswith("\\|"):
        line = line[:-1]
    return [c.strip().replace("\\|", "|") for c in re.split(r"(?<!\\)\|", line)]


def _table(lines: list[str], links: dict[str, str]) -> str:
    header = _cells(lines[0])
    body = lines[1:]
    aligns = [""] * len(header)
    if body and _ALIGN.match(body[0]):
        aligns = [
            "right"
            if c.endswith(":") and not c.startswith(":")
            else "center"
            if c.count(":") == 2
            else ""
            for c in _cells(body[0])
        ]
        body = body[1:]

    def style(k: int) -> str:
        return (
            f' class="{aligns[k]}"' if k < len(aligns) and aligns[k] in ("right", "center") else ""
        )

    head = "".join(f"<th{style(k)}>{inline(c, links)}</th>" for k, c in enumerate(header))
    rows = [
        "<tr>"
        + "".join(f"<td{style(k)}>{inline(c, links)}</td>" for k, c in enumerate(_cells(line)))
        + "</tr>"
        for line in body
    ]
    return (
        '<div class="scroll"><table class="sortable">\n<thead><tr>'
        + head
        + "</tr></thead>\n<tbody>\n"
        + "\n".join(rows)
        + "\n</tbody></table></div>"
    )


def to_html(markdown: str, links: dict[str, str] | None = None) -> str:
    """The body HTML of ``markdown`` (the subset in the module's docstring). ``links`` maps a
    link target to the one the page uses instead (e.g. a Markdown file shown on the page to its
    section)."""
    links = links or {}
    lines = markdown.splitlines()
    out: list[str] = []
    seen: dict[str, int] = {}
    paragraph: list[str] = []

    def flush() -> None:
        if paragraph:
            out.append("<p>" + inline(" ".join(paragraph), links) + "</p>")
            paragraph.clear()

    k = 0
    while k < len(lines):
        line = lines[k]
        stripped = line.strip()
        if stripped.startswith("```"):
            flush()
            end = k + 1
            while end < len(lines) and not lines[end].strip().startswith("```"):
                end += 1
            out.append("<pre><code>" + html.escape("\n".join(lines[k + 1 : end])) + "</code></pre>")
            k = end + 1
            continue
        if not stripped:
            flush()
            k += 1
            continue
        heading = _HEADING.match(line)
        if heading:
            flush()
            level, text = len(heading.group(1)), heading.group(2)
            anchor = _unique(slug(text), seen)
            out.append(f'<h{level} id="{html.escape(anchor)}">{inline(text, links)}</h{level}>')
            k += 1
            continue
        figure = _FIGURE.match(stripped)
        if figure and _live(figure.group(2)):
            flush()
            alt, src = figure.group(1), html.escape(figure.group(2))
            out.append(
                f'<figure><a href="{src}"><img src="{src}" alt="{html.escape(alt)}" '
                f'loading="eager"></a><figcaption>{inline(alt, links)}</figcaption></figure>'
            )
            k += 1
            continue
        if stripped.startswith("|"):
            flush()
            end = k
            while end < len(lines) and lines[end].strip().startswith("|"):
                end += 1
            out.append(_table(lines[k:end], links))
            k = end
            continue
        if stripped.startswith("- "):
            flush()
            items: list[str] = []
            while k < len(lines) and lines[k].strip():
                if lines[k].strip().startswith("- "):
                    items.append(lines[k].strip()[2:])
                elif items:  # a continuation line of the item above
                    items[-1] += " " + lines[k].strip()
                else:
                    break
                k += 1
            out.append(
                "<ul>\n" + "\n".join(f"<li>{inline(i, links)}</li>" for i in items) + "\n</ul>"
            )
            continue
        paragraph.append(stripped)
        k += 1
    flush()
    return "\n".join(out)


_STYLE = """
body { font: 15px/1.5 system-ui, -apple-system, "Segoe UI", Roboto, sans-serif; color: #1f2328;
  margin: 0; }
main { max-width: 1600px; margin: 0 auto; padding: 1em 2em 4em; }
nav { background: #f6f8fa; border-bottom: 1px solid #d0d7de; padding: .5em 2em; }
nav ul { margin: 0; padding: 0; list-style: none; display: flex; flex-wrap: wrap; gap: .2em 1.2em; }
h1, h2, h3 { line-height: 1.25; } h2 { border-bottom: 1px solid #d0d7de; padding-bottom: .2em; }
h3 { margin-top: 2em; }
code { background: #f6f8fa; padding: 0 .25em; border-radius: 4px; font-size: 90%; }
.scroll { overflow-x: auto; margin: 1em 0; }
table { border-collapse: collapse; font-size: 13px; }
th, td { border: 1px solid #d0d7de; padding: .25em .6em; white-space: nowrap; }
th { background: #f6f8fa; cursor: pointer; user-select: none; position: sticky; top: 0;
  white-space: normal; min-width: 4em; }
th[aria-sort="ascending"]::after { content: " \\25B2"; }
th[aria-sort="descending"]::after { content: " \\25BC"; }
tbody tr:nth-child(even) { background: #fafbfc; }
td.right, th.right { text-align: right; } td.center, th.center { text-align: center; }
figure { margin: 1em 0; } figure img { max-width: 100%; border: 1px solid #d0d7de; }
figcaption { color: #59636e; font-size: 13px; }
"""

# Click a header to sort by that column (numbers by value, the rest as text; cells without a
# number go last); click again to reverse. The page records on <html> how many tables it made
# sortable and how many of its figures loaded (read by tests/test_report_site.py).
_SCRIPT = """
(function () {
  function key(text) {
    var m = text.replace(/\\u2212/g, "-").match(/^[^\\d+\\-.]*([+\\-]?\\d+(?:\\.\\d+)?)/);
    return m ? parseFloat(m[1]) : null;
  }
  function sortBy(table, col, th) {
    var body = table.tBodies[0], rows = Array.prototype.slice.call(body.rows);
    var dir = th.getAttribute("aria-sort") === "ascending" ? -1 : 1;
    Array.prototype.forEach.call(table.tHead.rows[0].cells, function (h) {
      h.removeAttribute("aria-sort");
    });
    th.setAttribute("aria-sort", dir === 1 ? "ascending" : "descending");
    rows.sort(function (a, b) {
      var x = a.cells[col] ? a.cells[col].textContent.trim() : "";
      var y = b.cells[col] ? b.cells[col].textContent.trim() : "";
      var p = key(x), q = key(y);
      if (p !== null && q !== null) return dir * (p - q);
      if (p !== null) return -1;
      if (q !== null) return 1;
      return dir * x.localeCompare(y);
    });
    rows.forEach(function (r) { body.appendChild(r); });
  }
  var tables = document.querySelectorAll("table.sortable");
  Array.prototype.forEach.call(tables, function (table) {
    Array.prototype.forEach.call(table.tHead.rows[0].cells, function (th, col) {
      th.tabIndex = 0;
      th.title = "sort by this column";
      th.addEventListener("click", function () { sortBy(table, col, th); });
      th.addEventListener("keydown", function (e) {
        if (e.key === "Enter") sortBy(table, col, th);
      });
    });
  });
  document.documentElement.setAttribute("data-sortable-tables", String(tables.length));
  window.addEventListener("load", function () {
    var images = document.querySelectorAll("main img"), loaded = 0;
    Array.prototype.forEach.call(images, function (img) {
      if (img.complete && img.naturalWidth > 0) loaded += 1;
    });
    document.documentElement.setAttribute("data-figures-loaded", loaded + "/" + images.length);
  });
})();
"""


def page(markdown: str, title: str, links: dict[str, str] | None = None) -> str:
    """The whole HTML page: a bar of links to the ``##`` sections, then the report."""
    body = to_html(markdown, links)
    sections = re.findall(r'<h2 id="([^"]*)">(.*?)</h2>', body)
    nav = "".join(f'<li><a href="#{a}">{t}</a></li>' for a, t in sections)
    return (
        "<!DOCTYPE html>\n"
        '<html lang="en">\n<head>\n<meta charset="utf-8">\n'
        '<meta name="viewport" content="width=device-width, initial-scale=1">\n'
        f"<title>{html.escape(title)}</title>\n<style>{_STYLE}</style>\n</head>\n<body>\n"
        + (f"<nav><ul>{nav}</ul></nav>\n" if nav else "")
        + f"<main>\n{body}\n</main>\n<script>{_SCRIPT}</script>\n</body>\n</html>\n"
    )


def write_site(
    markdown: str, out_dir: str | Path, title: str, links: dict[str, str] | None = None
) -> Path:
    """Write ``out_dir/index.html`` from the report's Markdown (links relative to ``out_dir``)."""
    return write_text(Path(out_dir) / "index.html", page(markdown, title, links))
