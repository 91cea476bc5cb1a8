"""Opening SUMO's XML inputs, plain or gzip-compressed, as SUMO does.

SUMO reads ``.xml.gz`` networks, routes and additional files natively, and most published SUMO
scenarios ship them compressed. Every place that reads a SUMO XML file here opens it through
:func:`open_xml`, which recognises gzip by its magic bytes (not by the name) and stops with
:class:`XmlSizeError` once the decompressed stream passes :data:`MAX_XML_BYTES` — a gzip bomb is a
clear error, never an exhausted memory or disk.
"""

from __future__ import annotations

import gzip
import io
import xml.etree.ElementTree as ET
import zlib
from pathlib import Path

GZIP_MAGIC = b"\x1f\x8b"
# The largest decompressed XML file read (SUMO's biggest published scenarios, e.g. TAPASCologne's
# routes, are a few hundred MB uncompressed).
MAX_XML_BYTES = 4 * 2**30


class XmlSizeError(OSError):
    """A (decompressed) XML file is larger than :data:`MAX_XML_BYTES`."""


class _Limited(io.RawIOBase):
    """A binary reader that raises :class:`XmlSizeError` past `limit` bytes."""

    def __init__(self, raw, path: Path, limit: int) -> None:
        self._raw, self._path, self._limit, self._read = raw, path, limit, 0

    def readable(self) -> bool:
        return True

    def readinto(self, buffer) -> int:
        try:
            n = self._raw.readinto(buffer)
        except (EOFError, zlib.error) as exc:  # truncated or corrupt gzip
            raise OSError(f"{self._path}: not a readable gzip file ({exc})") from None
        self._read += n or 0
        if self._read > self._limit:
            raise XmlSizeError(
                f"{self._path}: more than {self._limit / 2**20:.0f} MiB of XML when decompressed "
                "(a gzip bomb, or a file too large to read)"
            )
        return n

    def close(self) -> None:
        self._raw.close()
        super().close()


def is_gzip(path: str | Path) -> bool:
    """Whether the file at `path` starts with gzip's magic bytes."""
    with open(path, "rb") as f:
        return f.read(2) == GZIP_MAGIC


def open_xml(path: str | Path, limit: int | None = None) -> io.BufferedReader:
    """The bytes of the XML file `path`, decompressed when it is gzip, at most `limit` of them
    (default :data:`MAX_XML_BYTES`; :class:`XmlSizeError` past that); ``OSError`` as ``open``
    raises it."""
    path = Path(path)
    limit = MAX_XML_BYTES if limit is None else limit
    raw = gzip.open(path, "rb") if is_gzip(path) else open(path, "rb")
    return io.BufferedReader(_Limited(raw, path, limit))


def parse_xml(path: str | Path, limit: int | None = None) -> ET.ElementTree:
    """``ElementTree.parse`` of a plain or gzip-compressed XML file (see :func:`open_xml`);
    ``ET.ParseError`` for bad XML, ``OSError`` (gzip's ``BadGzipFile`` and :class:`XmlSizeError`
    among them) when it cannot be read."""
    with open_xml(path, limit) as f:
        return ET.parse(f)


def check_size(path: str | Path, limit: int | None = None) -> None:
    """Read a gzip-compressed file through to its end (in 1 MiB chunks, nothing kept) so that a
    bomb is refused before a library that reads it whole (sumolib) sees it; a plain file is
    checked by its size."""
    path = Path(path)
    limit = MAX_XML_BYTES if limit is None else limit
    if not is_gzip(path):
        if path.stat().st_size > limit:
            raise XmlSizeError(f"{path}: more than {limit / 2**20:.0f} MiB of XML")
        return
    with open_xml(path, limit) as f:
        while f.read(2**20):
            pass
