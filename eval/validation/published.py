"""Published BCAGM benchmark results, parsed from the copies shipped in ``eval/data/published``.

The two text files are dumps of the BCAGM authors' saved ``.mat`` results (Nguyen, Tudisco,
Gautier, Hein, T-PAMI 2017): mean accuracy (and time, matching score) per algorithm and setting.
See ``eval/data/published/README.md`` for provenance.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

DATA_DIR = Path(__file__).resolve().parents[1] / "data" / "published"
SYNTHETIC_FILE = DATA_DIR / "bcagm-synthetic-published.txt"
HOUSE_FILE = DATA_DIR / "bcagm-house-published.txt"

# Section headings inside one synthetic block -> our key.
_SYNTHETIC_SECTIONS = {
    "mean acc": "accuracy",
    "mean time": "time_s",
    "mean score / best": "score_ratio",
}
_BLOCK_RE = re.compile(r"^=====\s+(\S+?)\.mat\b")
_ROW_RE = re.compile(r"^(\S+)\s+\[([^\]]*)\]")
_HOUSE_ROW_RE = re.compile(r"^(\S+)\s+acc\s+\[([^\]]*)\]\s+mean time\[s\]\s+(\S+)")
_HOUSE_BLOCK_RE = re.compile(r"^=====\s+res_house_(\d+)vs30\.mat")


@dataclass(frozen=True)
class PublishedSynthetic:
    """One synthetic protocol's published results: ``table[section][algorithm]`` is an array with
    one mean over 100 trials per setting (accuracy in [0, 1], time in seconds, score / best)."""

    block: str
    table: dict[str, dict[str, np.ndarray]]

    def accuracy(self, algorithm: str) -> np.ndarray:
        return self._get("accuracy", algorithm)

    def time_s(self, algorithm: str) -> np.ndarray:
        return self._get("time_s", algorithm)

    def _get(self, section: str, algorithm: str) -> np.ndarray:
        rows = self.table.get(section, {})
        if algorithm not in rows:
            raise KeyError(
                f"{self.block}: no published {section} for algorithm {algorithm!r}; "
                f"known: {sorted(rows)}"
            )
        return rows[algorithm]


@dataclass(frozen=True)
class PublishedHouse:
    """CMU House results for one N1 (landmarks of the first frame, against 30): accuracy per
    baseline 10, 20, ..., 100 and mean time per pair in seconds, per algorithm."""

    n1: int
    accuracy: dict[str, np.ndarray]
    time_s: dict[str, float]


def _numbers(text: str, where: str) -> np.ndarray:
    try:
        return np.array([float(tok) for tok in text.split()], dtype=float)
    except ValueError as exc:
        raise ValueError(f"{where}: cannot parse numbers from {text!r}") from exc


def _joined_lines(path: Path) -> list[tuple[int, str]]:
    """Lines of ``path`` with a bracketed list that wraps over several lines joined into one."""
    out: list[tuple[int, str]] = []
    pending = ""
    start = 0
    for lineno, line in enumerate(path.read_text().splitlines(), start=1):
        if pending:
            pending += " " + line.strip()
            if "]" in line:
                out.append((start, pending))
                pending = ""
            continue
        if "[" in line and "]" not in line and not line.startswith("====="):
            pending, start = line.rstrip(), lineno
            continue
        out.append((lineno, line.rstrip()))
    if pending:
        raise ValueError(f"{path}:{start}: unterminated '[' list")
    return out


def load_synthetic(path: Path | str = SYNTHETIC_FILE) -> dict[str, PublishedSynthetic]:
    """Parse the synthetic results file: block name (e.g. ``"def_20inlier"``,
    ``"out_003def_15scale"``) -> :class:`PublishedSynthetic`."""
    path = Path(path)
    blocks: dict[str, dict[str, dict[str, np.ndarray]]] = {}
    block: str | None = None
    section: str | None = None
    for lineno, line in _joined_lines(path):
        if m := _BLOCK_RE.match(line):
            block, section = m.group(1), None
            blocks[block] = {}
            continue
        heading = next((k for k in _SYNTHETIC_SECTIONS if line.startswith(k)), None)
        if heading is not None:
            if block is None:
                raise ValueError(f"{path}:{lineno}: section {heading!r} before any ===== block")
            section = _SYNTHETIC_SECTIONS[heading]
            blocks[block][section] = {}
            continue
        if section is None or block is None:
            continue
        if m := _ROW_RE.match(line):
            blocks[block][section][m.group(1)] = _numbers(m.group(2), f"{path}:{lineno}")
    if not blocks:
        raise ValueError(f"{path}: no '===== NAME.mat' blocks found")
    for name, sections in blocks.items():
        if "accuracy" not in sections or not sections["accuracy"]:
            raise ValueError(f"{path}: block {name!r} has no 'mean acc' rows")
    return {name: PublishedSynthetic(name, sections) for name, sections in blocks.items()}


def load_house(path: Path | str = HOUSE_FILE) -> dict[int, PublishedHouse]:
    """Parse the CMU House results file: N1 (5, 10, 15, 20, 30) -> :class:`PublishedHouse`."""
    path = Path(path)
    acc: dict[int, dict[str, np.ndarray]] = {}
    times: dict[int, dict[str, float]] = {}
    n1: int | None = None
    for lineno, line in _joined_lines(path):
        if m := _HOUSE_BLOCK_RE.match(line):
            n1 = int(m.group(1))
            acc[n1], times[n1] = {}, {}
            continue
        if n1 is not None and (m := _HOUSE_ROW_RE.match(line)):
            values = _numbers(m.group(2), f"{path}:{lineno}")
            if values.size != 10:
                raise ValueError(f"{path}:{lineno}: expected 10 baselines, got {values.size}")
            acc[n1][m.group(1)] = values
            times[n1][m.group(1)] = float(m.group(3))
    if not acc:
        raise ValueError(f"{path}: no '===== res_house_Nvs30.mat' blocks found")
    return {k: PublishedHouse(k, acc[k], times[k]) for k in acc}
