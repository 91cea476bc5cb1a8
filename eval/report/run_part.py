"""The report's first part: how the run was made (commit, cold or warm, wall time) and the stage
times of the last cold run, and the stage seconds each study's part states — all read from the
run record (``run_record.json``) and the last cold run's (``cold_run.json``)."""

from __future__ import annotations

import json
import os
from pathlib import Path

from eval.claims.budget import budget_claims
from eval.report.run_record import COLD_RECORD, cold_record


def read_record(results: Path) -> dict:
    """The run record, or {} when it is missing or unreadable."""
    try:
        record = json.loads((Path(results) / "run_record.json").read_text())
    except (OSError, ValueError):
        return {}
    return record if isinstance(record, dict) else {}


def is_cold(record: dict) -> bool:
    """Whether the run record's run started cold (:func:`eval.reproduce.cold_start`)."""
    return bool(record.get("cold_start", {}).get("cold"))


def last_cold(results: Path, record: dict) -> dict | None:
    """The last cold run's record (``cold_run.json``; this run's if it was cold), or None."""
    return cold_record(results) or (record if is_cold(record) else None)


def study_seconds(results: Path, record: dict) -> dict[str, float | int | None]:
    """Seconds (wall, last cold run) of the stages each study states against its time goal, and
    the transfer study's computed runs; None where no cold run timed them."""
    cold = last_cold(results, record) or {}
    stages = cold.get("wall_s", {})

    def total(*names: str) -> float | None:
        return sum(stages.get(k, 0.0) for k in names) or None

    return {
        "multiagent": total("multiagent_generate", "multiagent"),
        "transfer": total("transfer_generate", "transfer"),
        "transfer_runs": cold.get("runs", {}).get("transfer", {}).get("computed"),
        "temporal": total("temporal_generate", "temporal"),
        "temporal_lidar": total("temporal_lidar_generate", "temporal_lidar"),
        "v2x_boxes": stages.get("v2x_boxes"),
    }


def header(record: dict) -> str:
    """One sentence: command, date, commit, cold or warm, wall time, runs computed and cached."""
    wall = record.get("wall_s", {})
    git = record.get("git", {})
    runs = record.get("runs", {}).values()
    computed = sum(r.get("computed", 0) for r in runs)
    cached = sum(r.get("cached", 0) for r in runs)
    cold = is_cold(record)
    return (
        f"Produced by `{record.get('command', 'make reproduce')}` on {record.get('created', '?')}"
        f" at commit `{str(git.get('commit', '?'))[:10]}`"
        + (" (with uncommitted changes)" if git.get("dirty") else "")
        + f"; {'a cold run (no dataset, model or cached run at its start)' if cold else 'a warm run (datasets, models or runs cached at its start: its times are not cold times)'}"
        + (f"; every split × {record['scale']} (`--scale`)" if record.get("scale", 1) != 1 else "")
        + f"; wall time {wall.get('total', float('nan')):.0f} s ({computed} matcher runs computed, "
        f"{cached} taken from the result cache)."
    )


def stage_table(record: dict) -> list[str]:
    """A run's stage times as a Markdown table (seconds, runs computed and cached): the last cold
    run's (``cold_run.json``) when one is given, else this run's."""
    wall = record.get("wall_s", {})
    runs = record.get("runs", {})
    commit = str(record.get("git", {}).get("commit", "?"))[:10]
    where = "`cold_run.json`" if is_cold(record) else "`run_record.json`"
    budget = record.get("budget_s") or {}  # the stages' cold budgets, in records that have them
    scale = record.get("scale") or 1
    lines = [
        f"Stage times of {'the last cold' if is_cold(record) else 'this warm'} run (commit "
        f"`{commit}`, {record.get('created', '?')}; seconds; {where}"
        + (f"; every split × {scale}" if scale != 1 else "")
        + "):",
        "",
        "| Stage | s | runs computed | runs cached |" + (" cold budget s |" if budget else ""),
        "|:---|---:|---:|---:|" + ("---:|" if budget else ""),
    ]
    for name, seconds in wall.items():
        if name == "total":
            continue
        r = runs.get(name, {})
        lines.append(
            f"| {name.replace('_', ' ')} | {seconds:.0f} | {r.get('computed', '')} "
            f"| {r.get('cached', '')} |" + (f" {budget.get(name, '')} |" if budget else "")
        )
    total = f"| **total** | **{wall.get('total', float('nan')):.0f}** | | |"
    lines.append(total + (f" **{sum(budget.values()):g}** |" if budget else ""))
    return lines + [""]


def stage_table_names(report: str) -> list[str]:
    """The stage names (underscored, as the run record keys them) of the stage table in a
    report's Markdown (:func:`stage_table`), in order; empty without one."""
    _, found, rest = report.partition("| Stage | s |")
    rows = rest.split("\n\n", 1)[0].splitlines()[2:] if found else []
    names = [row.split("|")[1].strip().replace(" ", "_") for row in rows]
    return [n for n in names if n != "**total**"]


def cold_time(results: Path, readme_dir: Path) -> str | None:
    """README.md's stated cold time, read from the last cold run's ``cold_run.json`` (None
    without one): 'a cold `make reproduce` took 11 min 44 s (704 s, …, commit `880e86d`)'."""
    cold = cold_record(results)
    if not cold or "total" not in cold.get("wall_s", {}):
        return None
    total = cold["wall_s"]["total"]
    minutes, seconds = divmod(round(total), 60)
    scale = cold.get("scale") or 1
    rel = Path(os.path.relpath(results, readme_dir)).as_posix()
    return (
        f"a cold `make reproduce{f' SCALE={scale}' if scale != 1 else ''}` took {minutes} min "
        f"{seconds} s ({total:.0f} s, `{rel}/{COLD_RECORD}`, commit "
        f"`{str(cold.get('git', {}).get('commit', '?'))[:7]}`)"
    )


def run_part(results: Path, record: dict) -> list[str]:
    """The report's run part: :func:`header` and the stage times."""
    if not record:
        return []
    out = [header(record), ""]
    timed = last_cold(results, record) or record
    if timed.get("wall_s"):
        out += ["### Stage times", "", *stage_table(timed)]
        budget = [c.statement for c in budget_claims(results)]
        if budget:
            out += [
                "Per added table (and each study of several tables, whole), the sum of its stages "
                'against its share of the cold-run budget (docs/evaluation.md, "The cold-run budget"):',
                "",
            ]
            out += [f"- {line}" for line in budget] + [""]
    return out
