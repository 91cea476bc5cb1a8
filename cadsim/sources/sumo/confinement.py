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
from functools import cache
from pathlib import Path
from xml.parsers import expat

from cadsim.sources.sumo.xml_files import open_xml, parse_xml

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


@cache
def _names_a_path(attribute: str) -> bool:
    return bool(_PATH_ATTRIBUTE.search(attribute))


def _is_input(tag: str, attribute: str) -> bool:
    return (tag, attribute) in INPUT_ATTRIBUTES or ("*", attribute) in INPUT_ATTRIBUTES


def _output_name(value: str, k: int) -> str:
    base = Path(value.replace("\\", "/")).name
    return f"{k}-{base}" if base not in ("", ".", "..") else f"{k}-output.xml"


def _rewritten(
    tag: str, attrs: dict[str, str], path: Path, outputs: Path, rewritten: list[str]
) -> dict[str, str]:
    """The attributes of one element ``tag`` of file ``path`` that must change, with their new
    values (outputs into ``outputs``, inputs made absolute against ``path``'s folder); each
    rewritten output declaration is appended to ``rewritten``. Raises for ``<include>``."""
    if tag == "include":
        raise ConfinementError(
            f"{path}: <include href={attrs.get('href')!r}> is not supported; "
            "list the included file among the additional or route files instead"
        )
    new: dict[str, str] = {}
    for attribute, value in attrs.items():
        if not _names_a_path(attribute) or not value.strip():
            continue
        if _is_input(tag, attribute):
            absolute = str((path.parent / Path(value).expanduser()).resolve())
            if absolute != value:
                new[attribute] = absolute
        else:
            new[attribute] = str(outputs / _output_name(value, len(rewritten)))
            rewritten.append(f"{tag}.{attribute}")
    if tag == "param" and _PATH_PARAM.search(attrs.get("key", "")):
        value = attrs.get("value", "")
        if value.strip() and value.lower() not in ("true", "false"):
            new["value"] = str(outputs / _output_name(value, len(rewritten)))
            rewritten.append(f"param[{attrs.get('key')}]")
    return new


def needs_rewrite(path: Path) -> bool:
    """Whether ``path`` declares anything to rewrite. Read as a stream by expat (no tree: memory
    stays small and large route files are read fast) and remembered in this process while the
    file is unchanged; :class:`ConfinementError` for a file that cannot be loaded confined."""
    path = Path(path).resolve()
    try:
        st = path.stat()
    except OSError as exc:
        raise ConfinementError(f"{path}: not a readable XML file ({exc})") from None
    return _scan(path, st.st_size, st.st_mtime_ns, st.st_ino)


@cache
def _scan(path: Path, size: int, mtime_ns: int, inode: int) -> bool:
    """needs_rewrite's work, keyed by the file's identity and stat data."""
    found = False

    def start(tag: str, attrs: dict[str, str]) -> None:
        nonlocal found
        if tag in ("include", "param") or any(map(_names_a_path, attrs)):  # else: nothing to do
            found |= bool(_rewritten(tag, attrs, path, Path("/"), []))

    parser = expat.ParserCreate()
    parser.StartElementHandler = start
    try:
        with open_xml(path) as f:  # gzip-compressed or plain, decompressed size bounded
            parser.ParseFile(f)
    except (expat.ExpatError, OSError) as exc:
        raise ConfinementError(f"{path}: not a readable XML file ({exc})") from None
    return found


def confine(path: Path, outputs: Path) -> tuple[ET.ElementTree | None, list[str]]:
    """``path`` with its outputs rewritten into ``outputs``: the rewritten tree (None when
    nothing needed a change) and the rewritten declarations ("edgeData.file", …); raises
    :class:`ConfinementError` for a file SUMO cannot load confined (``<include>``, not XML)."""
    path = Path(path)
    if not needs_rewrite(path):
        return None, []
    tree = parse_xml(path)
    rewritten: list[str] = []
    for element in tree.getroot().iter():
        tag = element.tag if isinstance(element.tag, str) else ""
        changes = _rewritten(tag, dict(element.attrib), path, outputs, rewritten)
        for attribute, value in changes.items():
            element.set(attribute, value)
    return tree, rewritten


def check_loadable(path: Path) -> None:
    """Raise :class:`ConfinementError` if ``path`` cannot be loaded confined (scenario checks)."""
    needs_rewrite(Path(path))


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
        tree, _ = confine(Path(original), outputs)
        name = Path(original).name
        if tree is not None and name.endswith(".gz"):  # the rewritten copy is plain XML
            name = name[: -len(".gz")]
        target = folder / name
        if target.is_symlink() or target.exists():
            target.unlink()
        if tree is None:
            target.symlink_to(Path(original).resolve())
        else:
            tree.write(target, encoding="UTF-8", xml_declaration=True)
        out.append(target)
    return out
