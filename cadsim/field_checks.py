"""Predicates for ``cadsim.scenario.Field(check=...)`` shared by the source schemas."""

from __future__ import annotations

import re

_HEX = re.compile(r"^#[0-9a-fA-F]{6}$")


def hex_color_list(values: list) -> bool:
    """A non-empty list of colours written '#rrggbb'."""
    return bool(values) and all(_HEX.match(v) for v in values)


def positive_range(values: list) -> bool:
    """``[min, max]`` with 0 < min <= max."""
    return len(values) == 2 and 0 < values[0] <= values[1]
