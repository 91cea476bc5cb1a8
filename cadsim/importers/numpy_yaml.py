"""The numpy values PyYAML's default dumper writes, rebuilt as plain numbers — and nothing else.

V2V4Real's yaml files were written by ``yaml.dump`` from numpy values, so a ``gps`` entry is a
``!!python/object/apply:numpy.core.multiarray.scalar`` of a ``numpy.dtype`` and a ``!!binary``
payload, and ``lidar_pose`` a ``numpy.core.multiarray._reconstruct`` of a 4×4 array. The safe
loader refuses every such file; a full loader would run any ``!!python/...`` tag. This loader
(the stance of :mod:`~cadsim.importers.restricted_pickle`) accepts exactly these tags, under both
``numpy.core.multiarray.*`` (numpy 1.x dumps, the real files) and ``numpy._core.multiarray.*``
(numpy 2.x dumps):

- ``python/object/apply:numpy.dtype`` with ``args`` [a whitelisted type code, 0/1 or
  false/true, 0/1 or false/true] and an optional ``state`` tuple whose byte order is ``<``,
  ``>``, ``|`` or ``=`` → a numpy dtype (whitelist: :data:`DTYPES`, numbers and booleans only);
- ``python/object/apply:numpy.*core.multiarray.scalar`` [dtype, ``!!binary`` of exactly one
  item] → a Python ``float`` / ``int`` / ``bool``;
- ``python/object/apply:numpy.*core.multiarray._reconstruct`` with ``args`` [``numpy.ndarray``,
  ``(0,)``, ``b'b'``] and ``state`` (1, shape, dtype, fortran flag, ``!!binary`` of exactly the
  shape's bytes) → nested lists of Python numbers: the product of the sizes, each counted as at
  least 1, at most :data:`MAX_ARRAY_ITEMS` (so an empty axis cannot ask for billions of empty
  lists: that product bounds both the numbers and the lists built), and at most
  :data:`MAX_FILE_ARRAY_ITEMS` over all the arrays of one file;
- ``python/tuple`` (a list) and ``python/name:numpy.ndarray`` (inert, only as that argument).

Any other ``!!python/...`` tag is refused, naming it; nothing is imported or called by name.
Anchors and aliases stay legal (the real files share one dtype by alias); the expanded size is
bounded by :func:`cadsim.importers.safe_read.read_yaml`'s event walk before anything is built.
Imports only numpy and PyYAML.
"""

from __future__ import annotations

import math

import numpy as np
import yaml

from cadsim.importers.strict_yaml import UniqueKeyLoader

DTYPES = frozenset(
    {"f2", "f4", "f8", "i1", "i2", "i4", "i8", "u1", "u2", "u4", "u8", "b1"}
)  # fmt: skip
"""Type codes a dtype may name: fixed-size numbers and booleans (never object, bytes, void)."""
MAX_ARRAY_ITEMS = 65_536
"""Most items of one array (a pose is 16; a LiDAR point cloud is not stored in a label yaml)."""
MAX_FILE_ARRAY_ITEMS = 1_000_000
"""Most items of all the arrays of one file together (each size counted as at least 1): as many
as the values its YAML may hold (``safe_read.MAX_YAML_NODES``), so thousands of small empty
arrays cannot add up to billions of lists."""
_BYTE_ORDERS = ("<", ">", "|", "=")
_PY = "tag:yaml.org,2002:python/"
_NUMPY = ("numpy.core.multiarray.", "numpy._core.multiarray.")


class _NdarrayName:
    """The inert marker ``!!python/name:numpy.ndarray`` builds: never called."""


_NDARRAY = _NdarrayName()


def _error(node: yaml.Node, problem: str) -> yaml.constructor.ConstructorError:
    return yaml.constructor.ConstructorError(None, None, problem, node.start_mark)


class NumpyTagLoader(UniqueKeyLoader):
    """The strict safe loader plus the numpy tags of the module docstring."""

    def _args_state(self, node: yaml.Node) -> tuple[list, object]:
        """An ``apply`` node's (args, state): a sequence is args alone; a mapping has keys
        ``args`` and optionally ``state``, nothing else."""
        if isinstance(node, yaml.SequenceNode):
            return self.construct_sequence(node, deep=True), None
        if isinstance(node, yaml.MappingNode):
            value = self.construct_mapping(node, deep=True)
            if not set(value) <= {"args", "state"} or not isinstance(value.get("args"), list):
                raise _error(node, f"{node.tag.removeprefix(_PY)}: expected args (and state)")
            return value["args"], value.get("state")
        raise _error(node, f"{node.tag.removeprefix(_PY)}: expected args")

    def construct_dtype(self, node: yaml.Node) -> np.dtype:
        args, state = self._args_state(node)
        if (
            len(args) != 3
            or not isinstance(args[0], str)
            or args[0] not in DTYPES
            or any(a not in (0, 1) for a in args[1:])
        ):
            raise _error(
                node, f"numpy.dtype: expected one of {sorted(DTYPES)}, got {str(args)[:40]}"
            )
        dtype = np.dtype(args[0])
        if state is not None:
            if (
                not isinstance(state, tuple)
                or len(state) != 8
                or not isinstance(state[1], str)
                or state[1] not in _BYTE_ORDERS  # exactly one of them, not a substring
                or any(part is not None for part in state[2:5])
            ):
                order = state[1] if isinstance(state, tuple) and len(state) > 1 else None
                shown = repr(order)[:20] if isinstance(order, str | int) else type(order).__name__
                raise _error(
                    node,
                    f"numpy.dtype: state is not a plain dtype's (byte order {shown}; expected "
                    "one of < > | =, no subarray or fields)",
                )
            if state[1] in ("<", ">"):
                dtype = dtype.newbyteorder(state[1])
        return dtype

    def construct_scalar_value(self, node: yaml.Node):
        args, state = self._args_state(node)
        if state is not None or len(args) != 2:
            raise _error(node, "numpy scalar: expected [dtype, binary]")
        dtype, payload = args
        if not isinstance(dtype, np.dtype) or not isinstance(payload, bytes):
            raise _error(node, "numpy scalar: expected [dtype, binary]")
        if len(payload) != dtype.itemsize:
            raise _error(
                node, f"numpy scalar: {len(payload)} bytes for a {dtype.itemsize}-byte item"
            )
        return np.frombuffer(payload, dtype=dtype)[0].item()

    def construct_array(self, node: yaml.Node) -> list:
        args, state = self._args_state(node)
        if (
            len(args) != 3
            or args[0] is not _NDARRAY
            or args[1] != (0,)
            or args[2] != b"b"
            or not isinstance(state, tuple)
            or len(state) != 5
            or state[0] != 1
        ):
            raise _error(node, "numpy array: expected _reconstruct(ndarray, (0,), b'b') + state")
        _, shape, dtype, fortran, payload = state
        if not isinstance(shape, tuple) or not all(
            isinstance(s, int) and not isinstance(s, bool) and 0 <= s <= MAX_ARRAY_ITEMS
            for s in shape
        ) or len(shape) > 4:  # fmt: skip
            raise _error(node, f"numpy array: shape {str(shape)[:40]} is not up to 4 sizes")
        items = math.prod(shape)
        # what tolist() builds: a list per index of every leading axis, so an empty axis
        # bounds the numbers (0) but not the lists; each size counted as at least 1 bounds both
        cells = math.prod(max(s, 1) for s in shape)
        self._array_items = getattr(self, "_array_items", 0) + min(cells, MAX_ARRAY_ITEMS + 1)
        if self._array_items > MAX_FILE_ARRAY_ITEMS:
            raise _error(
                node,
                f"numpy arrays: more than {MAX_FILE_ARRAY_ITEMS} items in one file (0 counts as 1)",
            )
        if cells > MAX_ARRAY_ITEMS:
            raise _error(
                node,
                f"numpy array: shape {str(shape)[:30]} is more than {MAX_ARRAY_ITEMS} items "
                "(0 counts as 1)",
            )
        if (
            not isinstance(dtype, np.dtype)
            or fortran not in (0, 1)
            or not isinstance(payload, bytes)
        ):
            raise _error(node, "numpy array: state is not (1, shape, dtype, flag, binary)")
        if len(payload) != items * dtype.itemsize:
            raise _error(
                node, f"numpy array: {len(payload)} bytes for {items} items of {dtype.itemsize}"
            )
        order = "F" if fortran else "C"
        return np.frombuffer(payload, dtype=dtype).reshape(shape, order=order).tolist()

    def construct_ndarray_name(self, node: yaml.Node) -> _NdarrayName:
        if not isinstance(node, yaml.ScalarNode) or node.value:
            raise _error(node, "numpy.ndarray: expected the name alone")
        return _NDARRAY

    def construct_tuple(self, node: yaml.Node) -> tuple:
        if not isinstance(node, yaml.SequenceNode):
            raise _error(node, "python/tuple: expected a sequence")
        return tuple(self.construct_sequence(node, deep=True))

    def refuse_python(self, suffix: str, node: yaml.Node):
        raise _error(node, f"refused tag !!python/{suffix[:60]} (only numpy numbers and arrays)")


NumpyTagLoader.add_constructor(_PY + "object/apply:numpy.dtype", NumpyTagLoader.construct_dtype)
NumpyTagLoader.add_constructor(_PY + "tuple", NumpyTagLoader.construct_tuple)
NumpyTagLoader.add_constructor(_PY + "name:numpy.ndarray", NumpyTagLoader.construct_ndarray_name)
for _prefix in _NUMPY:
    NumpyTagLoader.add_constructor(
        _PY + f"object/apply:{_prefix}scalar", NumpyTagLoader.construct_scalar_value
    )
    NumpyTagLoader.add_constructor(
        _PY + f"object/apply:{_prefix}_reconstruct", NumpyTagLoader.construct_array
    )
NumpyTagLoader.add_multi_constructor(_PY, NumpyTagLoader.refuse_python)


__all__ = ["DTYPES", "MAX_ARRAY_ITEMS", "MAX_FILE_ARRAY_ITEMS", "NumpyTagLoader"]
