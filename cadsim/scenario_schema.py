"""The JSON Schema of scenario files, generated from the declarations :mod:`cadsim.scenario`
validates with (``Table``/``Field`` schemas, the per-source ``[traffic]`` tables, the
``NoiseConfig``/``DetectionConfig`` dataclasses): one source of truth, never written twice.

Editors that understand JSON Schema (with a TOML plug-in such as Taplo or Even Better TOML) can
then complete keys and check types and ranges while a scenario is written. ``load_scenario``
stays the authority: predicates (``Field.check``), cross-key rules and file existence cannot be
expressed here and appear only as descriptions.
"""

from __future__ import annotations

import dataclasses
import types
import typing
from typing import Any

from cadsim.scenario import (
    CAMERA,
    OBSERVERS,
    REQUIRED,
    SAMPLING,
    SEQUENCE,
    TOP_LEVEL,
    Field,
    Table,
    _config_class,
    _describe_hint,
    known_source_kinds,
    source_schema,
)

DIALECT = "https://json-schema.org/draft/2020-12/schema"
_JSON_TYPES = {
    int: "integer",
    float: "number",
    str: "string",
    bool: "boolean",
    list: "array",
    dict: "object",
}


def _types(accepted: type | tuple[type, ...]) -> list[str]:
    accepted = accepted if isinstance(accepted, tuple) else (accepted,)
    return [_JSON_TYPES[t] for t in accepted if t in _JSON_TYPES]


def field_schema(spec: Field) -> dict:
    """One key: its JSON type(s), bounds, choices, default and description."""
    out: dict[str, Any] = {}
    names = _types(spec.types)
    if len(names) == 1:
        out["type"] = names[0]
    elif names:
        out["type"] = names
    if spec.item is not None and spec.item in _JSON_TYPES:
        out["items"] = {"type": _JSON_TYPES[spec.item]}
    if spec.gt is not None:
        out["exclusiveMinimum"] = spec.gt
    if spec.ge is not None:
        out["minimum"] = spec.ge
    if spec.le is not None:
        out["maximum"] = spec.le
    if spec.choices:
        out["enum"] = list(spec.choices)
    if spec.default is not REQUIRED and spec.default is not None:
        out["default"] = spec.default
    text = spec.doc
    if spec.check is not None or spec.path or spec.expect:
        text = f"{text}. Expected: {spec.expectation()}" if text else spec.expectation()
    if text:
        out["description"] = text
    return out


def table_schema(table: Table) -> dict:
    """A table: its keys, none other allowed, the required ones listed."""
    properties = {
        key: table_schema(spec) if isinstance(spec, Table) else field_schema(spec)
        for key, spec in table.fields.items()
    }
    required = [
        key
        for key, spec in table.fields.items()
        if isinstance(spec, Field) and spec.default is REQUIRED
    ]
    out: dict[str, Any] = {
        "type": "object",
        "properties": properties,
        "additionalProperties": False,
    }
    if required:
        out["required"] = required
    if table.doc:
        out["description"] = table.doc
    return out


def _hint_schema(hint: Any) -> dict:
    origin, args = typing.get_origin(hint), typing.get_args(hint)
    if hint in _JSON_TYPES:
        return {"type": _JSON_TYPES[hint]}
    if origin in (typing.Union, types.UnionType):
        return {"anyOf": [_hint_schema(a) for a in args]}
    if hint is type(None):
        return {"type": "null"}
    if origin is typing.Literal:
        return {"enum": list(args)}
    if origin in (list, tuple) or hint in (list, tuple):
        return {"type": "array"}
    return {}


def dataclass_schema(cls: type) -> dict:
    """A table whose keys are the init fields of dataclass ``cls`` (``[noise]``, ``[detection]``,
    ``[localisation]``, ``[appearance]``)."""
    hints = typing.get_type_hints(cls)
    properties = {}
    for f in dataclasses.fields(cls):
        if not f.init:
            continue
        prop = _hint_schema(hints.get(f.name, Any))
        prop["description"] = f"{_describe_hint(hints.get(f.name, Any))} ({cls.__name__}.{f.name})"
        if f.default is not dataclasses.MISSING:
            prop["default"] = f.default
        properties[f.name] = prop
    return {"type": "object", "properties": properties, "additionalProperties": False}


def traffic_schema() -> dict:
    """``[traffic]``: one variant per registered source kind, selected by ``source``."""
    variants = []
    for kind in known_source_kinds():
        table = source_schema(kind)
        if table is None:
            continue
        schema = table_schema(table)
        schema["properties"] = {"source": {"const": kind}, **schema["properties"]}
        schema["required"] = ["source", *schema.get("required", [])]
        schema["title"] = f'source = "{kind}"'
        variants.append(schema)
    return {"type": "object", "required": ["source"], "oneOf": variants}


def scenario_json_schema() -> dict:
    """The JSON Schema (draft 2020-12) of a scenario file, as parsed from TOML."""
    properties: dict[str, Any] = {key: field_schema(spec) for key, spec in TOP_LEVEL.items()}
    properties["traffic"] = traffic_schema()
    for name, table in (
        ("camera", CAMERA), ("observers", OBSERVERS), ("sampling", SAMPLING),
        ("sequence", SEQUENCE),
    ):  # fmt: skip
        properties[name] = table_schema(table)
    for name in ("noise", "detection", "localisation", "appearance", "lidar"):
        cls = _config_class(name)
        properties[name] = dataclass_schema(cls) if cls is not None else {"type": "object"}
    return {
        "$schema": DIALECT,
        "title": "cadsim scenario file",
        "description": "A scenario for `cadsim generate` (TOML); every key: docs/scenarios.md.",
        "type": "object",
        "properties": properties,
        "required": ["traffic"],
        "additionalProperties": False,
    }
