"""PyYAML's safe loader with one more refusal: a mapping that names a key twice.

YAML 1.2 says keys are unique, but PyYAML keeps the last value silently, so a file with two
``lidar_pose`` entries (or two ``vehicles`` actors written ``101`` twice) would be read as if
the first were never there. :class:`UniqueKeyLoader` raises a ``yaml.constructor.ConstructorError``
naming the key and its line instead; :func:`cadsim.importers.safe_read.read_yaml` turns that into
the importers' one-line error.
"""

from __future__ import annotations

import yaml


class UniqueKeyLoader(getattr(yaml, "CSafeLoader", yaml.SafeLoader)):
    """The safe loader (libyaml's parser where PyYAML has it); a mapping with a repeated key
    (after YAML's own typing) is refused."""

    def construct_mapping(self, node: yaml.MappingNode, deep: bool = False) -> dict:
        if isinstance(node, yaml.MappingNode):
            self.flatten_mapping(node)
            seen: set = set()
            for key_node, _ in node.value:
                key = self.construct_object(key_node, deep=True)
                try:
                    repeated = key in seen
                    seen.add(key)
                except TypeError:  # an unhashable key: the safe loader refuses it itself
                    continue
                if repeated:
                    raise yaml.constructor.ConstructorError(
                        None,
                        None,
                        f"key {str(key)[:40]!r} given twice (line {key_node.start_mark.line + 1})",
                        key_node.start_mark,
                    )
        return super().construct_mapping(node, deep=deep)


__all__ = ["UniqueKeyLoader"]
