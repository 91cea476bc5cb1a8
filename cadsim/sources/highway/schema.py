"""The ``[traffic]`` table of ``source = "highway-env"`` (documented in docs/highway-env.md).

Checked at load time with ``cadsim.scenario``'s validator; the keys of ``[traffic.env]`` (the
environment's own config) are checked against the environment when the source starts, since
that needs highway-env imported (``cadsim.sources.highway.config.check_env_overrides``).
"""

from __future__ import annotations

from cadsim.field_checks import hex_color_list, positive_range
from cadsim.scenario import Field, ScenarioContext, Table, register_source_schema

HEX_COLORS = "a non-empty list of colours written '#rrggbb'"
KIND_KEYS = {"cls": str, "shape": str, "weight": (int, float), "size": list}

DEFAULT_KINDS = [
    {"cls": "car", "weight": 0.6, "size": [4.5, 1.8, 1.5]},
    {"cls": "van", "weight": 0.2, "size": [5.2, 2.0, 2.2]},
    {"cls": "bus", "weight": 0.1, "size": [10.0, 2.5, 3.2]},
    {"cls": "truck", "weight": 0.1, "size": [8.5, 2.5, 3.4]},
]


def _weights(values: list) -> bool:
    return len(values) == 3 and min(values) >= 0 and sum(values) > 0


def _is_num(v) -> bool:
    return isinstance(v, int | float) and not isinstance(v, bool)


SCENE = Table(
    {
        "building_depth": Field(
            list, [14.0, 26.0], "building footprint side, metres, drawn per side", item=float,
            check=positive_range, expect="[min, max] with 0 < min <= max (metres)",
        ),
        "building_heights": Field(
            list, [6.0, 16.0], "building height, metres, drawn per building", item=float,
            check=positive_range, expect="[min, max] with 0 < min <= max (metres)",
        ),
        "building_setback": Field(float, 4.0, "gap between the curb and a building, metres", ge=0),
        "building_colors": Field(
            list, ["#9e9484", "#8c8c94", "#b3a38c"], "facade colours", item=str,
            check=hex_color_list, expect=HEX_COLORS,
        ),
        "curb_offset": Field(float, 1.0, "lights and signs stand this far beyond the curb, metres", ge=0),
        "sign_distance": Field(float, 12.0, "a sign stands this far before the stop line, metres", ge=0),
    }
)  # fmt: skip

TRAFFIC = Table(
    {
        "env_id": Field(
            str, "intersection-v2", "a registered highway-env intersection environment",
            check=lambda v: (
                v.startswith("intersection-") and "multi-agent" not in v and v != "intersection-v0"
            ),
            expect="a single-agent intersection environment id such as 'intersection-v2' "
            "(not the deprecated intersection-v0)",
        ),
        "env": Field(dict, {}, "overrides of the environment's config (checked against it at start)"),
        "policy_weights": Field(
            list, [0.25, 0.5, 0.25], "probabilities of the controlled vehicle's SLOWER, IDLE, FASTER",
            item=float, check=_weights, expect="three numbers >= 0 with a positive sum",
        ),
        "max_snapshots": Field(
            int, 300, "snapshots offered before the source stops", ge=1, le=100_000,
        ),
        "max_candidates": Field(
            int, 4, "observer pairs proposed per snapshot, best first", ge=1, le=100,
        ),
        "vehicle_colors": Field(
            list, ["#f0f0f0", "#b4b4b8", "#1e1e1e", "#a01e1e", "#1e3c8c"], "vehicle body colours",
            item=str, check=hex_color_list, expect=HEX_COLORS,
        ),
        "kinds": Field(
            list, DEFAULT_KINDS, "vehicle kinds: cls, shape (default: cls), weight, size [l, w, h]",
            item=dict,
        ),
        "scene": SCENE,
    },
    check=lambda t, ctx, prefix: check_kinds(t, ctx, prefix),
)  # fmt: skip


def check_kinds(t: dict, ctx: ScenarioContext, prefix: str) -> None:
    """Each ``[[traffic.kinds]]`` entry: known keys, cls and size required, size three positive
    numbers, weight > 0."""
    if not t["kinds"]:
        raise ctx.error(f"{prefix}.kinds", "is empty", "one or more [[traffic.kinds]] tables")
    for i, kind in enumerate(t["kinds"]):
        key = f"{prefix}.kinds[{i}]"
        for name in kind:
            if name not in KIND_KEYS:
                raise ctx.unknown_key(f"{key}.{name}", KIND_KEYS)
        for name in ("cls", "size"):
            if name not in kind:
                raise ctx.error(f"{key}.{name}", "missing", "a value")
        for name in ("cls", "shape"):
            if name in kind and not (isinstance(kind[name], str) and kind[name]):
                raise ctx.error(f"{key}.{name}", f"is {kind[name]!r}", "a non-empty string")
        size = kind["size"]
        if not (
            isinstance(size, list) and len(size) == 3 and all(_is_num(v) and v > 0 for v in size)
        ):
            raise ctx.error(
                f"{key}.size", f"is {size!r}", "[length, width, height], numbers > 0 (metres)"
            )
        weight = kind.get("weight", 1.0)
        if not (_is_num(weight) and weight > 0):
            raise ctx.error(f"{key}.weight", f"is {weight!r}", "a number > 0")


register_source_schema("highway-env", TRAFFIC)
