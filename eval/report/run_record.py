"""The run record: a JSON file saying how a results directory was produced — scenario files, seeds,
τ values, matcher options, package versions, git commit, machine and wall time per stage."""

from __future__ import annotations

import hashlib
import json
import os
import platform
import sys
import time
from collections.abc import Iterator
from contextlib import contextmanager
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from cadsim.provenance import git_state, package_versions
from eval.core.result_files import write_text

PACKAGES = (
    "cadsim",
    "numpy",
    "scipy",
    "pandas",
    "matplotlib",
    "opencv-python-headless",
    "Pillow",
    "trimesh",
    "pyrender-maintained",
    "PyOpenGL",
    "libsumo",
    "eclipse-sumo",
    "highway-env",
    "dask",
    "lightgbm",
)


class StageTimer:
    """Wall time per named stage, seconds (``with timer.stage("evaluate"): ...``)."""

    def __init__(self) -> None:
        self.seconds: dict[str, float] = {}

    @contextmanager
    def stage(self, name: str) -> Iterator[None]:
        start = time.perf_counter()
        try:
            yield
        finally:
            self.seconds[name] = self.seconds.get(name, 0.0) + time.perf_counter() - start

    @property
    def total(self) -> float:
        return sum(self.seconds.values())


def scenario_file(path: str | Path) -> dict[str, str]:
    """A scenario file's path, SHA-256 and text."""
    data = Path(path).read_bytes()
    return {"path": str(path), "sha256": hashlib.sha256(data).hexdigest(), "text": data.decode()}


def simd() -> dict[str, Any]:
    """numpy's SIMD targets on this machine, as ``np.show_runtime()`` reports them: the compiled
    baseline, the dispatch targets found and not found, and those ``NPY_DISABLE_CPU_FEATURES``
    switched off. The results do not depend on them (``../shared/DESIGN.md`` §10); they are
    recorded so that a reader can see which code paths produced a run."""
    from numpy._core import _multiarray_umath as core

    found = core.__cpu_features__
    return {
        "baseline": list(core.__cpu_baseline__),
        "found": [f for f in core.__cpu_dispatch__ if found.get(f)],
        "not_found": [f for f in core.__cpu_dispatch__ if not found.get(f)],
        "disabled": os.environ.get("NPY_DISABLE_CPU_FEATURES", "").split(),
    }


def machine() -> dict[str, Any]:
    return {
        "python": sys.version.split()[0],
        "platform": platform.platform(),
        "cpus": os.cpu_count(),
        "numpy_simd": simd(),
    }


def write_run_record(path: str | Path, timer: StageTimer, **content: Any) -> Path:
    """Write the record (given `content` plus versions, git state, machine and stage times)."""
    record = {
        "created": datetime.now(UTC).isoformat(timespec="seconds"),
        **content,
        "git": git_state(),
        "packages": package_versions(PACKAGES),
        "machine": machine(),
        "wall_s": {name: round(s, 2) for name, s in timer.seconds.items()}
        | {"total": round(timer.total, 2)},
    }
    path = Path(path)
    write_text(path, json.dumps(record, indent=1, default=str) + "\n")
    return path


COLD_RECORD = "cold_run.json"
"""The stage times of the last run that started cold, beside the run record: a later warm run
(datasets or runs cached) leaves it as it is, so a "≤ N min cold" goal is always read off a cold
measurement, which names its commit."""


def keep_cold_record(results: str | Path, record: dict) -> Path | None:
    """Write ``results/cold_run.json`` from ``record`` (a run record) when that run started cold;
    leave it otherwise. Returns the path written, or None."""
    if not record.get("cold_start", {}).get("cold"):
        return None
    keys = (
        "created",
        "command",
        "scale",
        "executor",
        "git",
        "machine",
        "wall_s",
        "budget_s",
        "runs",
    )
    keys += ("cold_start", "code_version")
    path = Path(results) / COLD_RECORD
    write_text(path, json.dumps({k: record.get(k) for k in keys}, indent=1, default=str) + "\n")
    return path


def cold_record(results: str | Path) -> dict | None:
    """The last cold run's record (:data:`COLD_RECORD`), or None when there is none."""
    path = Path(results) / COLD_RECORD
    return json.loads(path.read_text()) if path.is_file() else None
