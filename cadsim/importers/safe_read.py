"""Reading a foreign dataset's text files without trusting them: the importers' one reader of
JSON and YAML, and of the paths those files name.

- YAML through PyYAML's safe loader only (no ``!!python/...`` tag constructs anything; a key
  given twice in one mapping refused, :mod:`~cadsim.importers.strict_yaml`; libyaml's parser
  where PyYAML has it), after walking its events: nesting deeper than :data:`MAX_DEPTH`,
  more than :data:`MAX_ALIASES` aliases, or more than :data:`MAX_YAML_NODES` nodes once every
  alias is expanded (an "alias bomb": anchors and aliases themselves are legal) is refused
  before anything is built; a YAML file is at most :data:`MAX_YAML_BYTES` (the parser builds
  about 1 MiB a second);
- JSON with the standard parser, ``NaN`` / ``Infinity`` refused, nesting deeper than
  :data:`MAX_DEPTH` refused before parsing;
- every file at most :data:`MAX_BYTES`, a regular file (no FIFO or device), and every number an importer uses finite and within
  :data:`MAX_MAGNITUDE` (:func:`number`);
- every path confined to the folder given on the command line (:func:`confined`): no absolute
  path, no ``..``, no link that leads outside.

Every refusal is an :class:`~cadsim.importers.ImportFormatError`: one line naming the file and
the key, showing at most a few dozen characters of the value (:func:`shown`, which never
formats more of a value than it shows). Imports only numpy and PyYAML.
"""

from __future__ import annotations

import json
import math
import os
import reprlib
import stat
from pathlib import Path, PurePosixPath

import numpy as np

from cadsim.importers import ImportFormatError
from cadsim.importers.numpy_yaml import NumpyTagLoader
from cadsim.importers.strict_yaml import UniqueKeyLoader

MAX_BYTES = 64 * 2**20
MAX_YAML_BYTES = 4 * 2**20
MAX_YAML_NODES = 1_000_000
MAX_DEPTH = 32
MAX_ALIASES = 1000
_SHOWN = reprlib.Repr()
_SHOWN.maxlevel = 3
_SHOWN.maxlist = _SHOWN.maxtuple = _SHOWN.maxdict = _SHOWN.maxset = 6
_SHOWN.maxstring = _SHOWN.maxlong = _SHOWN.maxother = 40
MAX_MAGNITUDE = 1e7
"""Largest coordinate, size or angle an importer accepts (metres or degrees): Earth-scale."""


def shown(value, width: int = 60) -> str:
    """At most ``width`` characters showing ``value`` (strings unquoted); the work is bounded
    whatever the value's size (a nested list, an expanded YAML alias)."""
    text = value if isinstance(value, str) else _SHOWN.repr(value)
    return text[:width]


def confined(root: Path, relative: str, where: Path | None = None, key: str = "") -> Path:
    """``root / relative`` if it names a file inside ``root`` (no absolute path, no ``..``,
    no backslash, no link out); ``where``/``key`` name the file and key that gave the path."""
    source = where if where is not None else root
    named = f"{key}: " if key else ""
    if not isinstance(relative, str) or not relative or "\\" in relative or "\0" in relative:
        raise ImportFormatError(source, f"{named}expected a relative path, got {shown(relative)!r}")
    pure = PurePosixPath(relative)
    if pure.is_absolute() or ".." in pure.parts:
        raise ImportFormatError(source, f"{named}path {relative[:60]!r} leaves {root}")
    path = Path(root, *pure.parts)
    try:
        inside = path.resolve().is_relative_to(Path(root).resolve())
    except (OSError, RuntimeError):
        inside = False
    if not inside:
        raise ImportFormatError(source, f"{named}path {relative[:60]!r} leads outside {root}")
    return path


def read_bytes(path: Path, limit: int = MAX_BYTES) -> bytes:
    """The bytes of the regular file ``path`` (a link is followed), at most ``limit``: a FIFO,
    device or folder is refused before it is read, and no more than ``limit`` + 1 bytes are."""
    try:
        info = path.stat()
        if not stat.S_ISREG(info.st_mode):
            raise ImportFormatError(path, "missing file" if not path.exists() else "not a file")
        if info.st_size > limit:
            raise ImportFormatError(path, f"larger than {limit / 2**20:g} MiB")
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK)
        with os.fdopen(fd, "rb") as handle:
            data = handle.read(limit + 1)
    except FileNotFoundError:
        raise ImportFormatError(path, "missing file") from None
    except OSError as exc:
        raise ImportFormatError(path, f"unreadable ({exc.strerror})") from None
    if len(data) > limit:  # grew since stat
        raise ImportFormatError(path, f"larger than {limit / 2**20:g} MiB")
    return data


def _text(path: Path, limit: int = MAX_BYTES) -> str:
    try:
        return read_bytes(path, limit).decode("utf-8")
    except UnicodeDecodeError:
        raise ImportFormatError(path, "not UTF-8 text") from None


def _json_depth(text: str) -> int:
    """Largest bracket nesting of ``text`` (brackets inside strings count too: an upper bound)."""
    codes = np.frombuffer(text.encode("utf-8"), dtype=np.uint8)
    step = np.isin(codes, (91, 123)).astype(np.int64) - np.isin(codes, (93, 125))
    return int(np.cumsum(step).max(initial=0))


def _refuse_constant(name: str):
    raise ValueError(f"non-finite number {name}")


def read_json(path: Path, limit: int = MAX_BYTES):
    """The parsed JSON file at ``path`` (limits of the module docstring; at most ``limit``
    bytes)."""
    text = _text(path, limit)
    if _json_depth(text) > MAX_DEPTH:
        raise ImportFormatError(path, f"nested deeper than {MAX_DEPTH} levels")
    try:
        return json.loads(text, parse_constant=_refuse_constant)
    except (ValueError, RecursionError) as exc:
        raise ImportFormatError(path, f"not valid JSON ({str(exc).splitlines()[0][:80]})") from None


def read_yaml(path: Path, numpy_tags: bool = False):
    """The parsed YAML file at ``path`` through the safe loader (limits of the docstring);
    ``numpy_tags``: also the numpy scalars, dtypes and arrays PyYAML's default dumper writes
    (:mod:`~cadsim.importers.numpy_yaml`, V2V4Real's files), rebuilt as plain numbers."""
    import yaml

    loader = getattr(yaml, "CSafeLoader", yaml.SafeLoader)
    text = _text(path, MAX_YAML_BYTES)
    try:
        _check_yaml_events(yaml.parse(text, Loader=loader), path)
        strict = NumpyTagLoader if numpy_tags else UniqueKeyLoader
        return yaml.load(text, Loader=strict)  # noqa: S506 (a safe loader)
    except yaml.YAMLError as exc:
        problem = str(getattr(exc, "problem", None) or exc).splitlines()[0][:80]
        raise ImportFormatError(path, f"not safe YAML ({problem})") from None
    except RecursionError:
        raise ImportFormatError(path, f"nested deeper than {MAX_DEPTH} levels") from None
    except ImportFormatError:
        raise
    except ValueError as exc:  # a value a constructor could not take: still name the file
        raise ImportFormatError(path, f"not safe YAML ({str(exc).splitlines()[0][:80]})") from None


def _check_yaml_events(events, path: Path) -> None:
    """Refuse a YAML event stream nested deeper than MAX_DEPTH, with more than MAX_ALIASES
    aliases, or of more than MAX_YAML_NODES nodes with every alias expanded (each alias counts
    the nodes of what its anchor names)."""
    import yaml

    depth = aliases = nodes = 0
    sizes: dict[str, int] = {}  # anchor -> nodes of its value, expanded
    open_at: list[tuple[str | None, int]] = []  # per open collection: (anchor, nodes before it)
    for event in events:
        if isinstance(event, yaml.CollectionStartEvent):
            depth += 1
            if depth > MAX_DEPTH:
                raise ImportFormatError(path, f"nested deeper than {MAX_DEPTH} levels")
            open_at.append((event.anchor, nodes))
            nodes += 1
        elif isinstance(event, yaml.CollectionEndEvent):
            depth -= 1
            anchor, before = open_at.pop()
            if anchor is not None:
                sizes[anchor] = nodes - before
        elif isinstance(event, yaml.ScalarEvent):
            nodes += 1
            if event.anchor is not None:
                sizes[event.anchor] = 1
        elif isinstance(event, yaml.AliasEvent):
            aliases += 1
            if aliases > MAX_ALIASES:
                raise ImportFormatError(path, f"more than {MAX_ALIASES} aliases")
            nodes += sizes.get(event.anchor, 1)  # an unknown anchor: the composer refuses it
        if nodes > MAX_YAML_NODES:
            raise ImportFormatError(
                path, f"more than {MAX_YAML_NODES:,} values with its aliases expanded"
            )


def field(mapping, key: str, path: Path, where: str = ""):
    """``mapping[key]``, or a one-line error naming ``path`` and the dotted key."""
    dotted = f"{where}.{key}" if where else key
    if not isinstance(mapping, dict):
        raise ImportFormatError(path, f"{where or 'top level'}: expected a mapping")
    if key not in mapping:
        raise ImportFormatError(path, f"{dotted}: missing")
    return mapping[key]


def number(value, path: Path, key: str, limit: float = MAX_MAGNITUDE) -> float:
    """``value`` as a float if it is a finite number (not a bool, not a string) of magnitude
    at most ``limit``."""
    ok = isinstance(value, int | float) and not isinstance(value, bool)
    if ok:
        try:
            value = float(value)
        except OverflowError:
            ok = False
    if not ok or not math.isfinite(value) or abs(value) > limit:
        raise ImportFormatError(
            path, f"{key}: expected a finite number within ±{limit:g}, got {shown(value, 40)}"
        )
    return value


def numbers(values, path: Path, key: str, count: int, limit: float = MAX_MAGNITUDE) -> list[float]:
    """A list of exactly ``count`` numbers (:func:`number` each)."""
    if not isinstance(values, list | tuple) or len(values) != count:
        raise ImportFormatError(
            path, f"{key}: expected a list of {count} numbers, got {shown(values)}"
        )
    return [number(v, path, f"{key}[{k}]", limit) for k, v in enumerate(values)]


def matrix(values, path: Path, key: str, rows: int, columns: int) -> np.ndarray:
    """A rows × columns nested list of numbers (a column vector may be nested or flat)."""
    flat = values
    if isinstance(values, list | tuple) and all(isinstance(r, list | tuple) for r in values):
        flat = [v for r in values for v in r]
    return np.array(numbers(flat, path, key, rows * columns)).reshape(rows, columns)


__all__ = [
    "MAX_BYTES", "MAX_DEPTH", "MAX_MAGNITUDE", "MAX_YAML_BYTES", "MAX_YAML_NODES", "confined",
    "field", "matrix", "number", "numbers", "read_bytes", "read_json", "read_yaml", "shown",
]  # fmt: skip


ORTHONORMAL_ATOL = 1e-9
"""A rotation whose R·Rᵀ is within this of I (elementwise) is used as given."""
POLAR_ATOL = 0.05
"""A rotation whose R·Rᵀ is off I by more than :data:`ORTHONORMAL_ATOL` but at most this
(elementwise) is replaced by its nearest rotation, the orthogonal factor of its polar
decomposition (U·Vᵀ of its SVD), as UniV2X and CoopTrack do for DAIR-V2X's released
calibrations (some are not orthonormal to 1e-3); beyond it, refused."""


def rigid(rotation, translation, path: Path, key: str) -> np.ndarray:
    """4×4 transform of a 3×3 ``rotation`` (nested list) and a 3-vector ``translation`` (flat
    or a column); the rotation re-orthonormalised (polar decomposition) when R·Rᵀ is within
    :data:`POLAR_ATOL` of I, refused beyond it or with determinant ≤ 0."""
    r = matrix(rotation, path, f"{key}.rotation", 3, 3)
    t = matrix(translation, path, f"{key}.translation", 3, 1).ravel()
    deviation = float(np.abs(r @ r.T - np.eye(3)).max())
    if deviation > POLAR_ATOL or np.linalg.det(r) <= 0:
        raise ImportFormatError(
            path,
            f"{key}.rotation: not a rotation matrix (R·Rᵀ off I by {deviation:.3g}, "
            f"at most {POLAR_ATOL:g} is re-orthonormalised)",
        )
    if deviation > ORTHONORMAL_ATOL:
        u, _, vt = np.linalg.svd(r)
        r = u @ vt
    out = np.eye(4)
    out[:3, :3], out[:3, 3] = r, t
    return out
