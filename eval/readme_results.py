"""Writes the results report and the README's results section from a results directory, so that
every number either shows comes from a run of ``make reproduce`` (called at its end). Run alone,
``python -m eval.readme_results`` (``make report``) rewrites both from the files already there,
recomputing nothing.

- The report: ``<results>/README.md`` and the same page as ``<results>/index.html`` (figures,
  sortable tables; :mod:`eval.report.site`), then every table and figure of the folder not
  shown in full above them.
- ``power_analysis.csv`` and ``.md``: the test clusters each study's covered comparisons would
  need (:mod:`eval.engine.power_analysis`), computed from the per-pair files in under a second.
- The README's section, between ``<!-- results:begin -->`` and ``<!-- results:end -->``: one
  compact table per study (:mod:`eval.report.summary`) with links into the report.

The report holds the run's stage times, the regime cards beside Table I (tuned, calibrated), the paired differences with their
intervals, the dataset spread, the paper-protocol table, the regime sweep, Fig. 4, the qualitative
figure, the ranking agreement with external data, the external benchmark (DMGM CAD pairs), the
localisation sweep and "Where we agree with the paper, and where not" — statements computed from those tables
(ranks, differences and whether their intervals exclude 0, crossovers), never typed in by hand.
Every part is optional: a results directory without a file leaves its part out, and a part whose
files this code cannot read (another version's format) is replaced by a line saying so and the
study's table as the run wrote it — the report is always written.
"""

from __future__ import annotations

import argparse
import logging
import os
from pathlib import Path

import pandas as pd

from eval.claims import build_claims
from eval.core.result_files import write_csv, write_text
from eval.engine.power_analysis import read_csv, write_power_analysis
from eval.engine.study import ReportContext
from eval.protocol.claims import FILE as CLAIMS
from eval.protocol.claims import to_frame
from eval.report.appendix import REPORT, SITE, appendix
from eval.report.guarded import guarded
from eval.report.power_table import FILE as POWER_TABLE
from eval.report.power_table import power_markdown
from eval.report.run_part import (
    cold_time,
    is_cold,
    read_record,
    run_part,
    stage_table,
    stage_table_names,
    study_seconds,
)
from eval.report.site import headings, write_site
from eval.report.summary_captions import SUMMARIES
from eval.studies import power_checks, studies

BEGIN, END = "<!-- results:begin -->", "<!-- results:end -->"
__all__ = [
    "cold_time",
    "report_markdown",
    "stage_table",
    "stage_table_names",
    "summary_section",
    "update_readme",
    "write_report",
]
COLD_BEGIN, COLD_END = "<!-- cold-run:begin -->", "<!-- cold-run:end -->"
"""README.md's stated cold time (:func:`cold_time`) sits between these."""
ROOT = Path(__file__).resolve().parents[1]
SELF_LINK = f"The same page with sortable tables: [{SITE}](./{SITE})."
SITE_SELF_LINK = f"The same report as Markdown: [{REPORT}](./{REPORT})."
log = logging.getLogger(__name__)


def claims_of(results: Path) -> pd.DataFrame:
    """The claims the report on ``results`` renders (:func:`eval.claims.build_claims`); an empty
    table (every claim's part then says nothing comparative) when the files cannot be read."""
    try:
        return build_claims(results)
    except Exception as error:  # any file format this code does not read
        log.warning("claims left out: %s: %s", type(error).__name__, error)
        return to_frame([])


def results_section(results: Path, readme_dir: Path) -> str:
    """Markdown: the run and its stage times, regime cards, Table I and its companions, figures,
    the agreement summary and the studies (V2X, multi-agent, transfer), links relative to
    ``readme_dir``."""
    results = Path(results)
    return "\n".join(_sections(results, Path(readme_dir), claims_of(results))).strip()


GROUPS = (
    "The paper's benchmark",
    "External data",
    "Localisation and V2X",
    "Multi-agent",
    "Temporal",
    "Transfer",
)
"""The report's groups of study parts, in order (``Part.group``; a group no study names is left
out, a new one goes after these); within a group the parts come in the studies' order."""


def _sections(
    results: Path, readme_dir: Path, claims: pd.DataFrame, groups: bool = False
) -> list[str]:
    """The report's lines; ``groups`` adds a ``##`` heading above each group of parts."""
    rel = Path(os.path.relpath(results, readme_dir)).as_posix()
    record = read_record(results)
    # "≤ N min cold" goals: the last cold run's times
    context = ReportContext(results, rel, record, study_seconds(results, record), claims)
    parts = [part for study in studies() for part in study.parts]
    plan = [("The run", [guarded("run", lambda: run_part(results, record), results)])]
    for title in dict.fromkeys([*GROUPS, *(part.group for part in parts)]):
        built = [
            guarded(p.name, lambda p=p: p.build(context), results, p.heading, p.table)
            for p in parts
            if p.group == title
        ]
        plan.append((title, built))
    out: list[str] = []
    for title, parts in plan:
        lines = [line for p in parts for line in p]
        if lines:
            out += ([f"## {title}", ""] if groups else []) + lines
    return out


def report_markdown(results: Path, claims: pd.DataFrame | None = None) -> str:
    """The whole report, ``<results>/README.md``: links relative to ``results``; ``claims``:
    the folder's claims (built from its files when not given)."""
    results = Path(results)
    claims = claims_of(results) if claims is None else claims
    docs = Path(os.path.relpath(ROOT / "docs", results)).as_posix()
    body = _sections(results, results, claims, groups=True)
    text = "\n".join(body)
    lines = [
        "# cadsim results",
        "",
        "Written by `make reproduce` from the files in this folder — every number below is "
        "read from them, none typed by hand, and every comparative statement is a row of "
        f"[{CLAIMS}](./{CLAIMS}); `make report` (`python -m eval.readme_results`) "
        f"writes this page again from the same files without recomputing anything. {SELF_LINK} "
        f"How to read the numbers, and what they cannot say: "
        f"[docs/evaluation.md]({docs}/evaluation.md#reading-the-results).",
        "",
        *body,
        *appendix(results, text, "."),
    ]
    return "\n".join(lines).rstrip() + "\n"


def _site_links(markdown: str, rel: str = ".") -> dict[str, str]:
    """On the HTML page, a link to a Markdown table shown on it points at its section."""
    return {
        f"{rel}/{text}": f"#{anchor}" for text, anchor in headings(markdown) if text.endswith(".md")
    }


def write_report(results: Path) -> tuple[Path, Path]:
    """Write ``<results>/power_analysis.csv`` (the clusters each study's covered comparisons
    would need, :mod:`eval.engine.power_analysis`) with its Markdown table and
    ``<results>/claims.csv``, then ``<results>/README.md`` and ``<results>/index.html``
    rendered from those claims and the folder's files."""
    results = Path(results)
    try:
        power = write_power_analysis(results, power_checks())
        if power is not None:  # shown in full in the report's appendix
            write_text(results / POWER_TABLE, power_markdown(read_csv(power)))
    except Exception as error:  # a file format this code does not read: the report goes on
        log.warning("power_analysis.csv left out: %s: %s", type(error).__name__, error)
    claims = claims_of(results)
    write_csv(claims, results / CLAIMS)
    markdown = report_markdown(results, claims)
    report = write_text(results / REPORT, markdown)
    page = markdown.replace(SELF_LINK, SITE_SELF_LINK, 1)  # the page names the other form
    site = write_site(page, results, "cadsim results", _site_links(page))
    return report, site


def _anchor(report: str, prefix: str) -> str:
    """``#anchor`` of the report's first heading that starts with ``prefix`` ("" if none)."""
    return next((f"#{a}" for text, a in headings(report) if text.startswith(prefix)), "")


def summary_section(results: Path, readme_dir: Path) -> str:
    """The README's section: the run in one line, links to the report, one compact table per
    study (those whose files are there), each with a link to its full section."""
    results = Path(results)
    rel = Path(os.path.relpath(results, readme_dir)).as_posix()
    record = read_record(results)
    claims = claims_of(results)
    report_path = results / REPORT
    report = report_path.read_text() if report_path.is_file() else report_markdown(results, claims)
    git, wall = record.get("git", {}), record.get("wall_s", {})
    run = f"From the files in `{rel}/`"
    if record:
        run += (
            f": {'a cold' if is_cold(record) else 'a warm'} run at commit "
            f"`{str(git.get('commit', '?'))[:10]}` on {str(record.get('created', '?'))[:10]}, "
            f"{wall.get('total', float('nan')):.0f} s"
        )
        if wall:
            run += f" ([stage times]({rel}/{REPORT}{_anchor(report, 'Stage times')}))"
    run += (
        f". The full report — every table, figure, interval and verdict — is "
        f"[{rel}/{REPORT}]({rel}/{REPORT}); [{rel}/{SITE}]({rel}/{SITE}) is the same page with "
        "sortable tables (open it in a browser)."
    )
    out = [run, ""]
    for lead, build, heading, caption in SUMMARIES:
        table = guarded(lead, lambda build=build: build(results, claims), results)
        if not table:
            continue
        link = f"{rel}/{REPORT}{_anchor(report, heading)}"
        out += [f"**{lead}** ([full]({link})). {caption}", "", *table, ""]
    return "\n".join(out).strip()


def update_readme(readme: Path, results: Path) -> bool:
    """Replace the README's results section and its stated cold time (between
    :data:`COLD_BEGIN` and :data:`COLD_END`, when there); False (README untouched) if it has no
    results markers."""
    readme = Path(readme)
    text = readme.read_text()
    if BEGIN not in text or END not in text:
        return False
    head, rest = text.split(BEGIN, 1)
    _, tail = rest.split(END, 1)
    body = summary_section(Path(results), readme.parent)
    text = f"{head}{BEGIN}\n{body}\n{END}{tail}"
    stated = cold_time(Path(results), readme.parent)
    if stated is not None and COLD_BEGIN in text and COLD_END in text:
        before, rest = text.split(COLD_BEGIN, 1)
        text = f"{before}{COLD_BEGIN}{stated}{COLD_END}{rest.split(COLD_END, 1)[1]}"
    write_text(readme, text)
    return True


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m eval.readme_results",
        description="Write the results report (README.md, index.html) and the README's results "
        "section again from a results folder's files, recomputing nothing.",
    )
    parser.add_argument("--results", type=Path, default=ROOT / "results", help="default: results/")
    parser.add_argument(
        "--readme",
        type=Path,
        default=None,
        help="README whose results section to rewrite (default: the repository's README.md "
        "when --results is the repository's results/, else none)",
    )
    args = parser.parse_args(argv)
    if not args.results.is_dir():
        parser.error(f"{args.results}: no such folder")
    for path in write_report(args.results):
        print(f"wrote {path}")
    readme = args.readme
    if readme is None and args.results.resolve() == (ROOT / "results").resolve():
        readme = ROOT / "README.md"
    if readme is not None:
        if update_readme(readme, args.results):
            print(f"rewrote the results section of {readme}")
        else:
            print(f"{readme}: no {BEGIN} … {END} markers; left alone")
    return 0


if __name__ == "__main__":
    logging.basicConfig(level=logging.WARNING, format="%(levelname)s: %(message)s")
    raise SystemExit(main())
