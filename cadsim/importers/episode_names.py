"""Episode numbers of a source's recording names (a V2X-Seq sequence id, a DAIR-V2X ``batch_id``).

A name of at most nine ASCII digits is its own number (``"0010"`` → 10), so records keep the
numbering the source uses. Every other name (``"abc"``, ``"²"``, ``"1a"``, ten digits or more)
is numbered after the largest such number, in sorted name order: ``{"1", "abc"}`` → 1 and 2,
never two names on one episode. The numbering depends only on the set of names, not on the
order the frames are listed in; importing a subset of the names can renumber the non-digit
ones. Imports nothing from cadsim.
"""

from __future__ import annotations

from collections.abc import Iterable

MAX_DIGITS = 9
"""Longest digit name kept as its own number."""


def plain_number(name: str) -> int | None:
    """``int(name)`` when ``name`` is 1 to :data:`MAX_DIGITS` ASCII digits, else None."""
    if name.isascii() and name.isdigit() and len(name) <= MAX_DIGITS:
        return int(name)
    return None


def episode_numbers(names: Iterable[str]) -> dict[str, int]:
    """{name: episode} for distinct ``names`` (module docstring); two digit names of one number
    (``"1"`` and ``"01"``) raise ``ValueError`` naming both.

    >>> episode_numbers(["0010", "abc", "3"])
    {'0010': 10, '3': 3, 'abc': 11}
    """
    out: dict[str, int] = {}
    owner: dict[int, str] = {}
    others = []
    for name in sorted(set(names)):
        number = plain_number(name)
        if number is None:
            others.append(name)
            continue
        if number in owner:
            raise ValueError(f"{owner[number]!r} and {name!r} are both episode {number}")
        owner[number] = name
        out[name] = number
    first = max(owner, default=-1) + 1
    out |= {name: first + k for k, name in enumerate(others)}
    return dict(sorted(out.items()))


__all__ = ["MAX_DIGITS", "episode_numbers", "plain_number"]
