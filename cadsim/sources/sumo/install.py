"""Where the SUMO binaries and tools are: those of the installed eclipse-sumo wheel."""

from __future__ import annotations

import os
from pathlib import Path


def sumo_home() -> Path:
    """SUMO_HOME of the eclipse-sumo wheel (bin/ and tools/ inside)."""
    import sumo

    return Path(sumo.SUMO_HOME)


def sumo_version() -> str:
    from importlib.metadata import version

    return version("eclipse-sumo")


def sumo_env() -> dict[str, str]:
    """This process's environment with SUMO_HOME set to the wheel's."""
    return {**os.environ, "SUMO_HOME": str(sumo_home())}


def binary(name: str) -> Path:
    """A SUMO program (``netgenerate``, ``sumo``, …) of the wheel."""
    return sumo_home() / "bin" / name
