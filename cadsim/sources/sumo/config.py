"""Reading a SUMO configuration file (``.sumocfg``) without running SUMO.

SUMO resolves a relative path in a config against the config's folder; the reader resolves the
inputs the same way. SUMO itself is never given the config: its options pass through an
allowlist (:mod:`cadsim.sources.sumo.options`) and its outputs are not passed at all
(:mod:`cadsim.sources.sumo.command`), so an externally written scenario runs unedited without
anything written into its folder or elsewhere.
"""

from __future__ import annotations

import re
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from pathlib import Path

from cadsim.sources.sumo.xml_files import parse_xml

# SUMO's option names and their synonyms for the inputs the source needs to know.
NET_OPTIONS = ("net-file", "n", "net")
ROUTE_OPTIONS = ("route-files", "r", "routes")
ADDITIONAL_OPTIONS = ("additional-files", "a", "additional")
# Output options whose names do not end in "-output".
_OTHER_OUTPUTS = {
    "netstate-dump",
    "netstate",
    "ndump",
    "log",
    "l",
    "log-file",
    "message-log",
    "error-log",
}


class SumoConfigError(ValueError):
    """A .sumocfg file cannot be read or lacks a network."""


@dataclass(frozen=True)
class SumoConfig:
    """Options of a .sumocfg. options: name -> value as written. net/routes/additional: absolute
    paths of the input files. outputs: output option name -> value as written (for
    information: none of them is passed to SUMO)."""

    path: Path
    options: dict[str, str]
    net: Path | None
    routes: list[Path] = field(default_factory=list)
    additional: list[Path] = field(default_factory=list)
    outputs: dict[str, str] = field(default_factory=dict)


def read_sumocfg(path: str | Path) -> SumoConfig:
    """Parse ``path``; raise :class:`SumoConfigError` if it is not XML or names no network."""
    path = Path(path).resolve()
    try:
        root = parse_xml(path).getroot()
    except (ET.ParseError, OSError) as exc:
        raise SumoConfigError(f"{path}: not a readable SUMO config ({exc})") from None
    options: dict[str, str] = {}
    for element in root.iter():
        if element is not root and "value" in element.attrib:
            options[element.tag] = element.attrib["value"]

    def files(names: tuple[str, ...]) -> list[Path]:
        value = next((options[n] for n in names if n in options), "")
        return [_resolve(path.parent, v) for v in split_file_list(value)]

    nets = files(NET_OPTIONS)
    outputs = {
        name: value
        for name, value in options.items()
        if (name.endswith("-output") or name in _OTHER_OUTPUTS)
        and value.strip().lower() not in ("", "true", "false")
    }
    return SumoConfig(
        path=path,
        options=options,
        net=nets[0] if nets else None,
        routes=files(ROUTE_OPTIONS),
        additional=files(ADDITIONAL_OPTIONS),
        outputs=outputs,
    )


def split_file_list(value: str) -> list[str]:
    """SUMO file lists are separated by commas (and tolerate spaces)."""
    return [v for v in re.split(r"[,\s]+", value.strip()) if v]


def _resolve(base: Path, value: str) -> Path:
    p = Path(value).expanduser()
    return (p if p.is_absolute() else base / p).resolve()
