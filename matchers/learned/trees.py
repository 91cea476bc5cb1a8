"""LightGBM's text trees, checked as data before LightGBM sees them.

LightGBM's own parser trusts its input: a split feature past the feature count reads outside the
row (the process dies of SIGSEGV), a child index that points back up or out of the tree loops for
ever, a line without ``=`` runs off the end of the buffer, a ``tree_sizes`` that lies sends its
parallel reader to the wrong offsets, and ``nan`` leaves or thresholds are accepted and change the
scores. So a model's text is parsed here first, strictly — exactly the layout LightGBM 4 writes
for a binary classifier on numerical features — and LightGBM is given only the canonical text
rebuilt from what was checked (:func:`check_trees`); nothing it was not checked on reaches it.

Checked: the header (``version=v4``, one class, one tree per iteration, label 0, the binary
objective with ``sigmoid:1``, ``max_feature_idx`` and ``feature_names`` those of the variant,
``feature_infos`` one per feature); per tree, every key once and no other (categorical and linear
trees are refused: cadsim never trains them), every array of the length ``num_leaves`` implies,
every number a plain decimal and finite, every split feature in ``0..width-1``, every decision
type a numerical one, and the child links a tree: each internal node and each leaf reached
exactly once from the root (no cycle, no index out of range, nothing shared or unreachable).
Bounded: :data:`MAX_TREES` trees, :data:`MAX_LEAVES` leaves per tree and
:data:`MAX_TOTAL_LEAVES` in all (prediction time grows with them). What follows ``end of trees``
(feature importances, the training parameters) is not read and not passed on.

Errors are :class:`TreeError` (a ValueError) whose message starts with the place
(``Tree=3: split_feature: ...``); the model loader prefixes the file and the key.
"""

from __future__ import annotations

import math
import re
from collections.abc import Sequence

MAX_TREES = 5000
"""Trees per classifier: ``cadsim train --rounds`` goes up to 5,000 (one tree a round)."""

MAX_LEAVES = 1024
"""Leaves of one tree (training uses 15)."""

MAX_TOTAL_LEAVES = 250_000
"""Leaves of all trees of one classifier together: a row's prediction visits at most this many
nodes (200 rounds × 15 leaves = 3,000 in the trained models)."""

HEADER_KEYS = (
    "version",
    "num_class",
    "num_tree_per_iteration",
    "label_index",
    "max_feature_idx",
    "objective",
    "feature_names",
    "feature_infos",
)
_OPTIONAL_HEADER = ("tree_sizes",)  # recomputed by LightGBM's sequential reader: not passed on
OBJECTIVE = "binary sigmoid:1"
TREE_KEYS = (
    "num_leaves",
    "num_cat",
    "split_feature",
    "split_gain",
    "threshold",
    "decision_type",
    "left_child",
    "right_child",
    "leaf_value",
    "leaf_weight",
    "leaf_count",
    "internal_value",
    "internal_weight",
    "internal_count",
    "is_linear",
    "shrinkage",
)
_INTERNAL_INTS = ("split_feature", "decision_type", "left_child", "right_child", "internal_count")
_INTERNAL_FLOATS = ("split_gain", "threshold", "internal_value", "internal_weight")
_LEAF_FLOATS = ("leaf_value", "leaf_weight")
_LEAF_INTS = ("leaf_count",)
_INT = re.compile(r"-?[0-9]{1,10}")
_FLOAT = re.compile(r"-?(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][-+]?[0-9]{1,3})?")
_FEATURE_INFO = re.compile(r"none|\[([^:\]]+):([^:\]]+)\]")
_TEXT = re.compile(r"[\x20-\x7e\n]*")
_INT32 = 2**31 - 1


class TreeError(ValueError):
    """LightGBM text that is not a model cadsim could have written (the message names where)."""


def _int(token: str, where: str) -> int:
    if not _INT.fullmatch(token):
        raise TreeError(f"{where}: expected an integer, got {token[:40]!r}")
    value = int(token)
    if abs(value) > _INT32:
        raise TreeError(f"{where}: {value} is out of the 32-bit range")
    return value


def _float(token: str, where: str) -> float:
    if not _FLOAT.fullmatch(token):
        raise TreeError(f"{where}: expected a finite decimal number, got {token[:40]!r}")
    value = float(token)
    if not math.isfinite(value):
        raise TreeError(f"{where}: {token[:40]} is not finite")
    return value


def _array(text: str, count: int, where: str, parse) -> list:
    tokens = text.split(" ") if text else []
    if len(tokens) != count:
        raise TreeError(f"{where}: {len(tokens)} values, expected {count}")
    return [parse(t, f"{where}[{i}]") for i, t in enumerate(tokens)]


def _key_values(lines: Sequence[str], keys: Sequence[str], optional: Sequence[str], where: str):
    found: dict[str, str] = {}
    for line in lines:
        key, eq, value = line.partition("=")
        if not eq:
            raise TreeError(f"{where}: line {line[:40]!r} is not key=value")
        if key not in keys and key not in optional:
            raise TreeError(f"{where}: unexpected key {key[:40]!r}")
        if key in found:
            raise TreeError(f"{where}: {key} given twice")
        found[key] = value
    missing = [k for k in keys if k not in found]
    if missing:
        raise TreeError(f"{where}: {missing[0]} missing")
    return found


def _check_header(fields: dict[str, str], names: Sequence[str]) -> None:
    width = len(names)
    expected = {
        "version": "v4",
        "num_class": "1",
        "num_tree_per_iteration": "1",
        "label_index": "0",
        "max_feature_idx": str(width - 1),
        "objective": OBJECTIVE,
        "feature_names": " ".join(names),
    }
    for key, value in expected.items():
        if fields[key] != value:
            shown = "the variant's feature names" if key == "feature_names" else repr(value)
            raise TreeError(f"{key}: expected {shown}, got {fields[key][:60]!r}")
    infos = fields["feature_infos"].split(" ")
    if len(infos) != width:
        raise TreeError(f"feature_infos: {len(infos)} entries, expected {width}")
    for i, info in enumerate(infos):
        match = _FEATURE_INFO.fullmatch(info)
        if match is None:
            raise TreeError(f"feature_infos[{i}]: expected none or [low:high], got {info[:40]!r}")
        if info != "none":
            low = _float(match.group(1), f"feature_infos[{i}]")
            high = _float(match.group(2), f"feature_infos[{i}]")
            if low > high:
                raise TreeError(f"feature_infos[{i}]: low {low} above high {high}")


def _check_links(left: list[int], right: list[int], leaves: int, where: str) -> None:
    """The child links form one tree over ``leaves - 1`` internal nodes and ``leaves`` leaves:
    each reached exactly once from the root, node 0 (a non-negative child is an internal node,
    ~c of a negative one a leaf)."""
    internal = leaves - 1
    seen_node = [False] * internal
    seen_leaf = [False] * leaves
    seen_node[0] = True
    stack = [0]
    while stack:
        node = stack.pop()
        for side, child in (("left_child", left[node]), ("right_child", right[node])):
            place = f"{where}: {side}[{node}]"
            if child >= 0:
                if child >= internal:
                    raise TreeError(f"{place}: node {child} out of range (0..{internal - 1})")
                if seen_node[child]:
                    raise TreeError(
                        f"{place}: node {child} reached twice (a cycle or a shared node)"
                    )
                seen_node[child] = True
                stack.append(child)
            else:
                leaf = ~child
                if leaf >= leaves:
                    raise TreeError(f"{place}: leaf {leaf} out of range (0..{leaves - 1})")
                if seen_leaf[leaf]:
                    raise TreeError(f"{place}: leaf {leaf} reached twice")
                seen_leaf[leaf] = True
    if not all(seen_node):
        raise TreeError(f"{where}: node {seen_node.index(False)} is not reached from the root")
    if not all(seen_leaf):
        raise TreeError(f"{where}: leaf {seen_leaf.index(False)} is not reached from the root")


def _check_tree(fields: dict[str, str], width: int, where: str) -> None:
    leaves = _int(fields["num_leaves"], f"{where}: num_leaves")
    if not 1 <= leaves <= MAX_LEAVES:
        raise TreeError(f"{where}: num_leaves: {leaves}, expected 1..{MAX_LEAVES}")
    if fields["num_cat"] != "0":
        raise TreeError(f"{where}: num_cat: categorical splits are not supported")
    if fields["is_linear"] != "0":
        raise TreeError(f"{where}: is_linear: linear trees are not supported")
    _float(fields["shrinkage"], f"{where}: shrinkage")
    values = {}
    for key in _INTERNAL_INTS:
        values[key] = _array(fields[key], leaves - 1, f"{where}: {key}", _int)
    for key in _INTERNAL_FLOATS:
        _array(fields[key], leaves - 1, f"{where}: {key}", _float)
    for key in _LEAF_FLOATS:
        _array(fields[key], leaves, f"{where}: {key}", _float)
    for key in _LEAF_INTS:
        values[key] = _array(fields[key], leaves, f"{where}: {key}", _int)
    for key in ("internal_count", "leaf_count"):
        negative = [v for v in values[key] if v < 0]
        if negative:
            raise TreeError(f"{where}: {key}: {negative[0]} is negative")
    for node, feature in enumerate(values["split_feature"]):
        if not 0 <= feature < width:
            raise TreeError(
                f"{where}: split_feature[{node}]: feature {feature} out of range "
                f"(the model has {width} features: 0..{width - 1})"
            )
    for node, kind in enumerate(values["decision_type"]):
        # bit 0: categorical; bit 1: missing values go left; bits 2-3: missing type 0..2
        if not 0 <= kind <= 15 or kind & 1 or (kind >> 2) & 3 > 2:
            raise TreeError(f"{where}: decision_type[{node}]: {kind} is not a numerical split")
    if leaves > 1:
        _check_links(values["left_child"], values["right_child"], leaves, where)


def check_trees(text: str, names: Sequence[str]) -> tuple[str, int]:
    """(the canonical text LightGBM is given, the number of trees) of the LightGBM text model
    ``text`` whose features are ``names``; :class:`TreeError` for anything else (module
    docstring)."""
    if not _TEXT.fullmatch(text):
        bad = next(i for i, c in enumerate(text) if not (c == "\n" or " " <= c <= "~"))
        raise TreeError(f"character {bad}: {text[bad]!r}; LightGBM text is printable ASCII")
    lines = text.split("\n")
    if lines[0] != "tree":
        raise TreeError("expected LightGBM's text model format (first line 'tree')")
    end = lines.index("", 1) if "" in lines[1:] else len(lines)
    header = _key_values(lines[1:end], HEADER_KEYS, _OPTIONAL_HEADER, "header")
    _check_header(header, names)
    width = len(names)
    trees: list[dict[str, str]] = []
    total = 0
    i = end
    while True:
        while i < len(lines) and lines[i] == "":
            i += 1
        if i >= len(lines):
            raise TreeError("'end of trees' missing")
        if lines[i] == "end of trees":
            break
        where = f"Tree={len(trees)}"
        if lines[i] != where:
            raise TreeError(f"{where}: expected this line, got {lines[i][:40]!r}")
        if len(trees) == MAX_TREES:
            raise TreeError(f"more than {MAX_TREES} trees")
        stop = i + 1
        while stop < len(lines) and lines[stop] != "" and stop - i <= len(TREE_KEYS):
            stop += 1
        fields = _key_values(lines[i + 1 : stop], TREE_KEYS, (), where)
        _check_tree(fields, width, where)
        total += int(fields["num_leaves"])
        if total > MAX_TOTAL_LEAVES:
            raise TreeError(f"{where}: more than {MAX_TOTAL_LEAVES:,} leaves in all")
        trees.append(fields)
        i = stop
    if not trees:
        raise TreeError("no trees")
    if "tree_sizes" in header:
        _array(header["tree_sizes"], len(trees), "tree_sizes", _int)
    out = ["tree", *(f"{k}={header[k]}" for k in HEADER_KEYS), ""]
    for n, fields in enumerate(trees):
        out += [f"Tree={n}", *(f"{k}={fields[k]}" for k in TREE_KEYS), "", ""]
    out += ["end of trees", ""]
    return "\n".join(out), len(trees)
