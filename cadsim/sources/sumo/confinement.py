"""SUMO XML inputs (additional and route files) made safe to load: every output they declare is
rewritten into the simulation's run folder.

Additional files may declare outputs (``<edgeData file=…>``, detectors, ``<timedEvent dest=…>``,
``<calibrator output=…>``, device parameters such as ``<param key="device.ssm.file" …>``), with
absolute or ``../`` paths. Rather than recognising dangerous paths, the rule is by construction:
every attribute that names a path (its name is ``file``/``dest``/``output``/``href`` or contains
"file" or "output"; a ``<param>`` whose key does) is an output unless it is one of the few known
inputs below, and is replaced by ``OUTPUTS/<k>-<base name>``. Known inputs (a rerouter's or
variable speed sign's definition file, a mean-data edge list, image and 3-D model files) are
made absolute so the copy reads the same files. The attribute names are those of SUMO's
``data/xsd/additional_file.xsd``. ``<include>`` is refused. A file that needs no change is passed through a
symbolic link in the run folder, so that even a relative output this module did not foresee
would resolve there, never next to the original.
"""

from __future__ import annotations

import re
import xml.etree.ElementTree as ET
from pathlib import Path

# (element, attribute) that name files SUMO reads; "*": any element.
INPUT_ATTRIBUTES = frozenset(
    {
        ("rerouter", "file"),
        ("variableSpeedSign", "file"),
        ("*", "edgesFile"),  # edgeData/laneData: the edges to report on
        ("*", "imgFile"),
        ("*", "osgFile"),
    }
)
_PATH_ATTRIBUTE = re.compile(r"^(file|dest|output|href)$|file|output", re.IGNORECASE)
_PATH_PARAM = re.compile(r"file|output|(^|\.)log$", re.IGNORECASE)


class ConfinementError(ValueError):
    """A SUMO XML file that cannot be loaded without writing outside the run folder."""


def _is_input(tag: str, attribute: str) -> bool:
    return (tag, attribute) in INPUT_ATTRIBUTES or ("*", attribute) in INPUT_ATTRIBUTES


def _output_name(value: str, k: int) -> str:
    base = Path(value.replace("\\", "/")).name
    return f"{k}-{base}" if base not in ("", ".", "..") else f"{k}-output.xml"


def confine(path: Path, outputs: Path) -> tuple[ET.ElementTree | None, list[str]]:
    """Parse ``path`` and rewrite its outputs into ``outputs``. Returns the rewritten tree (None
    when nothing needed a change) and the rewritten declarations ("edgeData.file" …); raises
    :class:`ConfinementError` for a file SUMO cannot load confined (``<include>``, not XML)."""
    path = Path(path)
    try:
        tree = ET.parse(path)
    except (ET.ParseError, OSError) as exc:
        raise ConfinementError(f"{path}: not a readable XML file ({exc})") from None
    rewritten: list[str] = []
    changed = False
    for element in tree.getroot().iter():
        tag = element.tag if isinstance(element.tag, str) else ""
        if tag == "include":
            raise ConfinementError(
                f"{path}: <include href={element.get('href')!r}> is not supported; "
                "list the included file among the additional or route files instead"
            )
        for attribute, value in list(element.attrib.items()):
            if not value.strip() or not _PATH_ATTRIBUTE.search(attribute):
                continue
            if _is_input(tag, attribute):
                absolute = str((path.parent / Path(value).expanduser()).resolve())
                changed |= absolute != value
                element.set(attribute, absolute)
            else:
                element.set(attribute, str(outputs / _output_name(value, len(rewritten))))
                rewritten.append(f"{tag}.{attribute}")
                changed = True
        if tag == "param" and _PATH_PARAM.search(element.get("key", "")):
            value = element.get("value", "")
            if value.strip() and value.lower() not in ("true", "false"):
                element.set("value", str(outputs / _output_name(value, len(rewritten))))
                rewritten.append(f"param[{element.get('key')}]")
                changed = True
    return (tree if changed else None), rewritten


def check_loadable(path: Path) -> None:
    """Raise :class:`ConfinementError` if ``path`` cannot be loaded confined (scenario checks)."""
    confine(Path(path), Path("/nonexistent-outputs"))


def confined_files(files: list[Path], run_dir: Path, kind: str) -> list[Path]:
    """The files SUMO should load instead of ``files``: a rewritten copy where outputs had to be
    moved, else a symbolic link; each in its own folder ``run_dir/kind/<k>/``. Outputs of file k
    go to ``run_dir/outputs/<kind><k>/``."""
    out = []
    for k, original in enumerate(files):
        outputs = run_dir / "outputs" / f"{kind}{k}"
        outputs.mkdir(parents=True, exist_ok=True)
        folder = run_dir / kind / str(k)
        folder.mkdir(parents=True, exist_ok=True)
        target = folder / Path(original).name
        if target.is_symlink() or target.exists():
            target.unlink()
        tree, _ = confine(Path(original), outputs)
        if tree is None:
            target.symlink_to(Path(original).resolve())
        else:
            tree.write(target, encoding="UTF-8", xml_declaration=True)
        out.append(target)
    return out
