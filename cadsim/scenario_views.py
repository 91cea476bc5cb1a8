"""How many views a scenario's records hold: its ``[observers]`` vehicles plus its roadside units.

Two (the default) gives today's frame-pair records; more gives N-view snapshot records
(DESIGN §12, docs/multi-agent.md). Kept apart from :mod:`cadsim.scenario` so that reading a
dataset needs no scenario parser.
"""

from __future__ import annotations

MULTI_VIEW_KEYS = (
    "count",
    "roadside_units",
    "roadside_height_m",
    "roadside_offset_m",
    "roadside_pitch_deg",
)
"""The ``[observers]`` keys of N-view snapshots (left out of a two-view dataset's configuration)."""


def view_count(observers: dict) -> int:
    """Views per record of a validated ``[observers]`` table: its vehicles plus its roadside
    units (2: frame pairs)."""
    return int(observers.get("count", 2)) + int(observers.get("roadside_units", 0))
