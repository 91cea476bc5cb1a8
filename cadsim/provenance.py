"""Provenance recorded in dataset manifests and run records: package versions and git state."""

from __future__ import annotations

import os
import platform
import subprocess
from collections.abc import Iterable
from importlib import metadata
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
# What `make reproduce` itself rewrites: not counted as a dirty checkout.
GENERATED = ("results", "README.md")


def package_versions(names: Iterable[str]) -> dict[str, str | None]:
    """{"python": version} plus the installed version of each distribution (None if absent).
    Reads package metadata only; nothing is imported."""
    versions: dict[str, str | None] = {"python": platform.python_version()}
    for name in names:
        try:
            versions[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            versions[name] = None
    return versions


def git_state(repo: str | Path = REPO) -> dict[str, str | bool | None]:
    """{"commit": HEAD hash, "dirty": whether any file — tracked or untracked, not ignored, other
    than the outputs in GENERATED — differs from it} for the checkout at ``repo``; both None when
    git or the checkout is absent. Read-only: ``GIT_OPTIONAL_LOCKS=0`` stops ``git status`` from
    refreshing the index (which takes ``.git/index.lock`` and would collide with the user's own
    git commands), so nothing in the checkout is created or modified."""
    env = {**os.environ, "GIT_OPTIONAL_LOCKS": "0"}

    def git(*args: str) -> str | None:
        try:
            out = subprocess.run(
                ["git", "-C", str(repo), *args],
                capture_output=True,
                text=True,
                timeout=10,
                env=env,
                stdin=subprocess.DEVNULL,
            )
        except (OSError, subprocess.SubprocessError):
            return None
        return out.stdout.strip() if out.returncode == 0 else None

    commit = git("rev-parse", "HEAD")
    excluded = [f":(exclude){p}" for p in GENERATED]
    status = git("status", "--porcelain", "--", ".", *excluded) if commit else None
    return {"commit": commit, "dirty": None if status is None else bool(status)}
