"""Figures drawn once per input: a figure writer whose inputs, drawing code and outputs are all as
they were when it last drew is not run again (a fully cached ``make reproduce`` drew the same
eight figures every time, ≈ 12 s, and rewrote each PDF with a new creation date).

A stamp per output folder (:mod:`eval.core.folder_stamps`, kind ``figures``) holds, per writer, the key it drew
under and the SHA-256 of every file it wrote. The key (:func:`figure_key`) is a SHA-256 over the
writer's name, matplotlib's version, the drawing sources (``eval/report/*.py``,
``cadsim/*_drawing.py``) and the bytes of each input file (a missing one counts as missing). The
writer is skipped only when the key matches and every output it wrote is still there with the
same bytes; anything else — another input, an edited or deleted figure, a foreign or unreadable
stamp — draws again. A stamp is a speed-up, never a result: a folder that cannot be written only
costs the next run the drawing.
"""

from __future__ import annotations

import functools
import hashlib
from collections.abc import Callable, Iterable
from pathlib import Path

from eval.core.folder_stamps import read_stamp, write_stamp

_ROOT = Path(__file__).resolve().parents[2]
_SOURCES = ("eval/report/*.py", "cadsim/*_drawing.py")
KIND = "figures"


def _digest(path: Path) -> str | None:
    try:
        return hashlib.sha256(path.read_bytes()).hexdigest()
    except OSError:
        return None


@functools.cache
def _code_version() -> str:
    import matplotlib

    h = hashlib.sha256(f"matplotlib {matplotlib.__version__}\0".encode())
    for pattern in _SOURCES:
        for path in sorted(_ROOT.glob(pattern)):
            h.update(path.relative_to(_ROOT).as_posix().encode() + b"\0")
            h.update(path.read_bytes())
    return h.hexdigest()


def figure_key(writer: str, inputs: Iterable[Path]) -> str:
    """Hex SHA-256 of what writer `writer` draws from (module docstring)."""
    h = hashlib.sha256(f"{writer}\0{_code_version()}\0".encode())
    for path in inputs:
        h.update(f"{Path(path).name}\0{_digest(Path(path))}\0".encode())
    return h.hexdigest()


def _stamps(out_dir: Path) -> dict:
    stored = read_stamp(KIND, out_dir) or {}
    return stored["writers"] if isinstance(stored.get("writers"), dict) else {}


def _current(out_dir: Path, writer: str, key: str) -> list[Path] | None:
    """The outputs `writer` wrote under `key`, if they are all still as written; else None."""
    entry = _stamps(out_dir).get(writer)
    if not isinstance(entry, dict) or entry.get("key") != key:
        return None
    outputs = entry.get("outputs")
    if not isinstance(outputs, dict):
        return None
    paths = [out_dir / name for name in outputs]
    if any(_digest(p) != d for p, d in zip(paths, outputs.values(), strict=True)):
        return None
    return paths


def _record(out_dir: Path, writer: str, key: str, paths: list[Path]) -> None:
    writers = _stamps(out_dir)
    outputs = {
        Path(p).resolve().relative_to(out_dir.resolve()).as_posix(): _digest(Path(p)) for p in paths
    }
    writers[writer] = {"key": key, "outputs": outputs}
    write_stamp(KIND, out_dir, {"writers": writers})


def drawn_once(inputs: Callable[[Path], Iterable[Path]]):
    """Decorate a figure writer ``writer(out_dir) -> list[Path]``: skipped, its earlier outputs
    returned, when ``inputs(out_dir)`` (the files it reads), the drawing code and its outputs
    are as they were when it last drew (module docstring)."""

    def decorate(writer: Callable[[str | Path], list[Path]]):
        @functools.wraps(writer)
        def draw(out_dir: str | Path) -> list[Path]:
            out_dir = Path(out_dir)
            key = figure_key(writer.__name__, inputs(out_dir))
            done = _current(out_dir, writer.__name__, key)
            if done is not None:
                return done
            paths = writer(out_dir)
            _record(out_dir, writer.__name__, key, paths)
            return paths

        return draw

    return decorate
