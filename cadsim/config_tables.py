"""Frozen config dataclasses built from scenario-file tables, with messages that name the table."""

from __future__ import annotations

import difflib
from collections.abc import Mapping
from dataclasses import fields
from numbers import Real
from typing import TypeVar

T = TypeVar("T")


def config_from_table(cls: type[T], table: Mapping, where: str, section: str) -> T:
    """``cls(**table)``; unknown keys and bad values raise with ``where`` (e.g. "x.toml [noise]").
    ``section`` is the tag the class's own messages start with (e.g. "[noise]")."""
    if not isinstance(table, Mapping):
        raise TypeError(f"{where} must be a table, got {type(table).__name__}")
    known = {f.name for f in fields(cls)}
    unknown = sorted(set(table) - known)
    if unknown:
        close = difflib.get_close_matches(unknown[0], sorted(known), n=1)
        hint = f" (did you mean {close[0]!r}?)" if close else ""
        raise ValueError(
            f"{where}: unknown key(s) {', '.join(unknown)}{hint}; expected some of "
            f"{', '.join(sorted(known))}"
        )
    try:
        return cls(**dict(table))
    except (TypeError, ValueError) as exc:
        msg = str(exc)
        if msg.startswith(section):
            msg = where + msg[len(section) :] if where.endswith(section) else f"{where}: {msg}"
        elif not msg.startswith(where):
            msg = f"{where}: {msg}"
        raise type(exc)(msg) from exc


def check_number(
    where: str,
    name: str,
    value,
    *,
    minimum: float | None = None,
    maximum: float | None = None,
    integer: bool = False,
) -> None:
    """Raise TypeError/ValueError unless ``value`` is a finite real (an int if ``integer``) within
    [minimum, maximum]."""
    if isinstance(value, bool) or not isinstance(value, Real) or (integer and int(value) != value):
        kind = "an integer" if integer else "a number"
        raise TypeError(f"{where} {name} must be {kind}, got {value!r}")
    if value != value or value in (float("inf"), float("-inf")):
        raise ValueError(f"{where} {name} must be finite, got {value!r}")
    if minimum is not None and value < minimum:
        raise ValueError(f"{where} {name} must be >= {minimum}, got {value!r}")
    if maximum is not None and value > maximum:
        raise ValueError(f"{where} {name} must be <= {maximum}, got {value!r}")
