"""YAML loading that remembers where every value came from (file, line, column).

PyYAML's YAML 1.1 resolver would turn ``6060:00`` into a base-60 integer and ``on:`` into ``True``; ecattool
keeps such scalars as strings (object addresses are common in project files) and mapping keys always as the
text that was written.
"""

from __future__ import annotations

import sys
from typing import Any

import yaml

from ecattool.errors import InputError, Location

Path_ = tuple[str | int, ...]

MAX_YAML_BYTES = 16 * 1024 * 1024

#: How many values aliases (``*name``) may add beyond the nodes written in the file: a document of a few hundred
#: bytes whose anchors refer to anchors ("billion laughs") would otherwise expand exponentially. Real project files
#: repeat a block with an alias now and then; this is far more than they need and far less than a bomb makes.
MAX_ALIAS_VALUES = 10_000

#: libyaml's parser where PyYAML has it (10x faster on large projects; same nodes, marks and errors)
_Loader: Any = getattr(yaml, "CSafeLoader", yaml.SafeLoader)


class LocatedYaml:
    """A loaded YAML document plus a map from value paths to locations."""

    def __init__(self, data: Any, locations: dict[Path_, Location], source: str,
                 key_locations: dict[Path_, Location] | None = None) -> None:
        self.data = data
        self.locations = locations
        self.key_locations = key_locations or {}
        self.source = source

    def locate_key(self, path: Path_) -> Location:
        """The location of the mapping key that ends ``path`` (falls back to the value's)."""
        return self.key_locations.get(tuple(path)) or self.locate(path)

    def locate(self, path: Path_) -> Location:
        """The location of the value at ``path`` (or of its closest located parent)."""
        p = tuple(path)
        while p:
            if p in self.locations:
                return self.locations[p]
            p = p[:-1]
        return self.locations.get((), Location(self.source, 1, 1))


def load_yaml(text: str | bytes, source: str) -> LocatedYaml:
    if len(text) > MAX_YAML_BYTES:
        raise InputError(f"YAML file is larger than {MAX_YAML_BYTES} bytes", Location(source))
    try:
        loader = _Loader(text)
    except yaml.YAMLError as exc:  # the reader checks characters and encoding up front
        raise InputError(f"invalid YAML: {exc}".splitlines()[0], Location(source, 1)) from None
    try:
        node = loader.get_single_node()
    except yaml.MarkedYAMLError as exc:
        mark = exc.problem_mark or exc.context_mark
        line = mark.line + 1 if mark else None
        col = mark.column + 1 if mark else None
        raise InputError(f"invalid YAML: {exc.problem or exc.context}", Location(source, line, col)) from None
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None) or getattr(exc, "context_mark", None)
        line = mark.line + 1 if mark else 1  # reader errors (encoding, control characters) have no mark
        text0 = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise InputError(f"invalid YAML: {text0}", Location(source, line)) from None
    finally:
        loader.dispose()
    locations: dict[Path_, Location] = {}
    keys: dict[Path_, Location] = {}
    if node is None:
        return LocatedYaml(None, {(): Location(source, 1, 1)}, source)
    data = _convert(node, (), locations, keys, source, loader, depth=0, budget=_Budget())
    return LocatedYaml(data, locations, source, keys)


def _loc(node: yaml.Node, source: str) -> Location:
    return Location(source, node.start_mark.line + 1, node.start_mark.column + 1)


class _Budget:
    """The nodes met so far and how many values aliases have added (see :data:`MAX_ALIAS_VALUES`)."""

    __slots__ = ("seen", "repeated")

    def __init__(self) -> None:
        self.seen: set[int] = set()
        self.repeated = 0

    def visit(self, node: yaml.Node, source: str) -> None:
        key = id(node)
        if key not in self.seen:
            self.seen.add(key)
            return
        self.repeated += 1
        if self.repeated > MAX_ALIAS_VALUES:
            raise InputError(f"YAML aliases expand to more than {MAX_ALIAS_VALUES} values (an alias bomb?); "
                             "write the repeated blocks out", _loc(node, source))


def _convert(node: yaml.Node, path: Path_, locs: dict[Path_, Location], keys: dict[Path_, Location], source: str,
             loader: yaml.SafeLoader, depth: int, budget: _Budget) -> Any:
    if depth > 64:
        raise InputError("YAML nesting is deeper than 64 levels", _loc(node, source))
    budget.visit(node, source)
    locs[path] = _loc(node, source)
    if isinstance(node, yaml.MappingNode):
        out: dict[str, Any] = {}
        for key_node, value_node in node.value:
            if key_node.tag == "tag:yaml.org,2002:merge":
                raise InputError("YAML merge keys (<<) are not supported in ecattool files", _loc(key_node, source))
            if not isinstance(key_node, yaml.ScalarNode):
                raise InputError("mapping keys must be plain scalars", _loc(key_node, source))
            key = str(key_node.value)
            if key in out:
                raise InputError(f"duplicate key {key!r}", _loc(key_node, source))
            keys[(*path, key)] = _loc(key_node, source)
            out[key] = _convert(value_node, (*path, key), locs, keys, source, loader, depth + 1, budget)
        return out
    if isinstance(node, yaml.SequenceNode):
        return [_convert(v, (*path, i), locs, keys, source, loader, depth + 1, budget) for i, v in enumerate(node.value)]
    assert isinstance(node, yaml.ScalarNode)
    tag = node.tag
    if tag.endswith((":int", ":float")) and ":" in node.value:
        return node.value  # 6060:00 is an object address, not a base-60 number
    if tag.endswith(":bool") and node.value.lower() not in ("true", "false"):
        return node.value  # yes/no/on/off stay words
    if tag.endswith(":timestamp") or tag.endswith(":binary"):
        return node.value
    if tag.rsplit(":", 1)[-1] in ("seq", "map", "set", "omap", "pairs"):  # !!set x: a collection tag on a scalar
        raise InputError(f"invalid YAML value: the tag !!{tag.rsplit(':', 1)[-1]} does not fit the scalar "
                         f"{node.value[:40]!r}", _loc(node, source))
    try:
        value = loader.construct_object(node)
    except yaml.YAMLError as exc:  # the location is ours; the library's text repeats it on further lines
        what = getattr(exc, "problem", None) or str(exc).splitlines()[0]
        raise InputError(f"invalid YAML value: {what}", _loc(node, source)) from None
    except (ValueError, TypeError, OverflowError, IndexError, KeyError) as exc:  # a tag the text does not fit: !!int x
        kind = tag.rsplit(":", 1)[-1]
        if "digits" in str(exc):  # Python's int() refuses more than 4300 decimal digits
            raise InputError(f"a number of more than {sys.get_int_max_str_digits()} digits", _loc(node, source)) from None
        raise InputError(f"invalid YAML value: {node.value[:40]!r} is not a valid {kind}", _loc(node, source)) from None
    if isinstance(value, int) and not isinstance(value, bool) and value.bit_length() > 256:
        raise InputError(f"number of {value.bit_length()} bits is absurdly large ({node.value[:20]!r}...)",
                         _loc(node, source))
    return value
