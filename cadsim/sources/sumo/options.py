"""Which netgenerate and SUMO options a scenario may set: allowlists derived from the installed
tools' own option declarations (``TOOL --save-template stdout``: each option's category and type).

An option may pass only if its category is one that shapes the network or the traffic (grid,
defaults, traffic lights, junctions, pedestrians for netgenerate; time, processing, routing,
mesoscopic and random numbers for SUMO), its declared type is not a file, and its name does not
say it names one (``file``, ``output``, ``log``, ``prefix``, ``save``, ``dump`` as a word of the
name: SUMO declares ``device.ssm.file`` as a string). Nothing that writes a file, opens a
socket or loads another configuration can pass, whatever a scenario says.

A ``.sumocfg``'s options outside the allowlist are either dropped, when they cannot change the
traffic (outputs of any category, reports, GUI settings; the source reads the simulation through
libsumo and needs no output), or refused with the option named (e.g. a TraCI port, another
configuration file, a file-valued device option).
"""

from __future__ import annotations

import math
import re
import subprocess
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from functools import cache

from cadsim.sources.sumo.install import binary, sumo_env

NETGENERATE_CATEGORIES = frozenset(
    {
        "grid_network",
        "building_defaults",
        "tls_building",
        "junctions",
        "pedestrian",
        "bicycle",
        "unregulated_nodes",
        "processing",
    }
)
SUMO_CATEGORIES = frozenset({"time", "processing", "routing", "mesoscopic", "random_number"})
# sumocfg options of these categories cannot change the traffic the source samples: dropped.
SUMO_IGNORED_CATEGORIES = frozenset({"output", "report", "gui_only"})
# sumocfg input options the source itself resolves and passes (net, routes, additional files).
SUMO_INPUTS = frozenset({"net-file", "route-files", "additional-files"})
# Options the source sets itself (seed, logging, validation); a sumocfg's values are dropped.
SUMO_OWN = frozenset({"seed", "random", "end", "step-length", "ignore-route-errors"})

_PATH_WORD = re.compile(r"(^|[.-])(file|files|output|log|prefix|save|dump)([.-]|$)")


def sumo_time(value: str, name: str = "begin") -> float:
    """A SUMO time value in seconds: a number ("54000", "0.5") or SUMO's clock format
    "h:m:s" / "d:h:m:s" ("15:0:0" = 54000); :class:`OptionError` naming `name` otherwise."""
    parts = str(value).strip().split(":")
    try:
        numbers = [float(p) for p in parts]
    except ValueError:
        numbers = []
    if not numbers or len(numbers) == 2 or len(numbers) > 4 or not all(map(math.isfinite, numbers)):
        raise OptionError(
            f"{name}: expected seconds or SUMO's clock format h:m:s / d:h:m:s, got {value!r}"
        )
    return sum(n * unit for n, unit in zip(reversed(numbers), (1, 60, 3600, 86400), strict=False))


class OptionError(ValueError):
    """An option a scenario may not pass to netgenerate or SUMO. ``index``: its position in an
    argument list (None for a .sumocfg option)."""

    def __init__(self, message: str, index: int | None = None) -> None:
        super().__init__(message)
        self.index = index


@dataclass(frozen=True)
class ToolOption:
    """One option of a SUMO tool as its template declares it."""

    name: str
    category: str
    type: str


@cache
def tool_options(tool: str) -> dict[str, ToolOption]:
    """Every option of ``tool`` (``netgenerate``, ``sumo``), under its name and its synonyms."""
    proc = subprocess.run(
        [str(binary(tool)), "--save-template", "stdout"],
        capture_output=True,
        text=True,
        env=sumo_env(),
        stdin=subprocess.DEVNULL,
        timeout=60,
    )
    root = ET.fromstring(proc.stdout[proc.stdout.index("<") :])
    options: dict[str, ToolOption] = {}
    for category in root:
        for element in category:
            option = ToolOption(element.tag, category.tag, element.get("type", ""))
            for name in [element.tag, *(element.get("synonymes") or "").split()]:
                options.setdefault(name, option)
    return options


def names_a_file(option: ToolOption) -> bool:
    """Whether the option's value is (or may be) a path: its type, or a word of its name."""
    return option.type.startswith("FILE") or bool(_PATH_WORD.search(option.name))


def _is_output(option: ToolOption) -> bool:
    """A file a device writes (``device.rerouting.output``, ``device.taxi.….output``)."""
    return names_a_file(option) and "output" in option.name


def netgenerate_option_allowed(option: ToolOption) -> bool:
    return option.category in NETGENERATE_CATEGORIES and not names_a_file(option)


def sumo_option_allowed(option: ToolOption) -> bool:
    return option.category in SUMO_CATEGORIES and not names_a_file(option)


def check_netgenerate_args(args: list[str]) -> None:
    """Raise :class:`OptionError` (``index``: the offending element) unless
    ``args`` is ``--name[=value]`` / ``--name value`` items of allowlisted netgenerate options.
    A value may start with a single dash (``-1``); short option names are refused."""
    options = tool_options("netgenerate")
    pending: ToolOption | None = None  # the option whose value comes next
    for i, arg in enumerate(args):
        if arg.startswith("--"):
            name, has_value, value = arg[2:].partition("=")
            option = options.get(name)
            if option is None:
                raise OptionError(f"{arg!r} is not a netgenerate option", i)
            if not netgenerate_option_allowed(option):
                raise OptionError(
                    f"--{option.name} ({option.category.replace('_', ' ')}) may not be set from "
                    "a scenario; allowed: non-file options of the categories "
                    + ", ".join(sorted(NETGENERATE_CATEGORIES)),
                    i,
                )
            if has_value:
                _checked(option, value, arg, i)
            pending = None if has_value or option.type == "BOOL" else option
        elif arg.startswith("-") and not _is_number(arg):
            raise OptionError(f"{arg!r}: write options as --name (short names are refused)", i)
        elif pending is not None:
            _checked(pending, arg, f"--{pending.name}", i)
            pending = None
        elif not _is_bool(arg):
            raise OptionError(f"{arg!r} is a value with no option before it", i)


def _checked(option: ToolOption, value: str, where: str, index: int) -> None:
    try:
        check_value(option, value, where)
    except OptionError as exc:
        raise OptionError(str(exc), index) from None


@dataclass(frozen=True)
class SumocfgOptions:
    """A .sumocfg's options sorted out. passed: {name: value} given to SUMO as they are; own:
    the options the source sets itself (seed, end, step length…) with the config's values;
    dropped: names of options that cannot change the traffic (outputs, reports, GUI)."""

    passed: dict[str, str]
    own: dict[str, str]
    dropped: list[str]


def check_value(option: ToolOption, value: str, where: str) -> str:
    """`value` if it is data of `option`'s type, else :class:`OptionError` naming `where`: a
    BOOL must be a boolean word, INT/FLOAT numbers, TIME seconds or SUMO's clock format, lists
    those element by element; no value may start with "-" unless it is a number. Values are
    passed as ``--name=value`` as well, so even an unforeseen type cannot become an option."""
    text = str(value).strip()
    kind = option.type.removesuffix("[]")
    items = split_values(text) if option.type.endswith("[]") else [text]
    for item in items:
        if kind == "BOOL":
            ok = _is_bool(item)
        elif kind in ("INT", "FLOAT"):
            ok = _is_number(item)
        elif kind == "TIME":
            try:
                sumo_time(item, where)
                ok = True
            except OptionError:
                ok = False
        else:
            ok = not item.startswith("-") or _is_number(item)
        if not ok:
            raise OptionError(
                f"{where}: {value!r} is not a valid {option.type} value"
                + (" (a value may not start with '-')" if item.startswith("-") else "")
            )
    return text


def split_values(text: str) -> list[str]:
    """A SUMO list value's items (separated by commas or spaces)."""
    return [v for v in re.split(r"[,\s]+", text) if v]


def sumocfg_options(options: dict[str, str]) -> SumocfgOptions:
    """Sort a .sumocfg's options (names as written, synonyms allowed) by canonical name; the
    inputs (net, routes, additional files) are left to the caller. :class:`OptionError` names
    the first option refused."""
    known = tool_options("sumo")
    out = SumocfgOptions({}, {}, [])
    for name, value in options.items():
        option = known.get(name)
        if option is None:
            raise OptionError(f"<{name}> is not a SUMO option")
        if option.name in SUMO_INPUTS:
            continue
        if option.name in SUMO_OWN:
            out.own[option.name] = check_value(option, value, f"<{name}>")
        elif option.category in SUMO_IGNORED_CATEGORIES or _is_output(option):
            out.dropped.append(option.name)
        elif sumo_option_allowed(option):
            out.passed[option.name] = check_value(option, value, f"<{name}>")
        else:
            raise OptionError(
                f"<{name}> ({option.category.replace('_', ' ')}) is not supported: a scenario "
                "may set non-file options of the categories " + ", ".join(sorted(SUMO_CATEGORIES))
            )
    return out


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def _is_bool(text: str) -> bool:
    return text.lower() in ("true", "false", "on", "off", "yes", "no", "1", "0")
