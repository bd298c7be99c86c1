"""world.yaml's text: the world's dicts and lists as YAML, written fast and always alike.

The text is that of ``yaml.dump(world, Dumper=yaml.SafeDumper, sort_keys=False,
default_flow_style=None, width=100)``, made in two cheaper steps:

- the YAML nodes are built here (:func:`world_nodes`) rather than by PyYAML's representer, which
  looks each value's type up its class hierarchy and spends most of a dump's time doing so:
  the same nodes, tags, values and flow styles (a list or dict of scalars only is written in
  flow style), and a list or dict met twice is the same node (an anchor and an alias), as
  PyYAML's SafeRepresenter makes them;
- libyaml's emitter writes them when every string is printable ASCII (written plain or in
  single quotes: the two emitters fold long double-quoted strings differently; the strings
  are checked while the nodes are built), PyYAML's otherwise; either way the resolver's
  answer for each scalar text is kept (the emitter asks for it twice per scalar).

A value of any other type than None, bool, int, float, str, list and dict goes through
``yaml.dump`` as a whole.
"""

from __future__ import annotations

from typing import Any

import yaml
from yaml.nodes import MappingNode, Node, ScalarNode, SequenceNode
from yaml.resolver import BaseResolver

WIDTH = 100
"""Line width of world.yaml's flow sequences."""
FAST_DUMPER: Any = getattr(yaml, "CSafeDumper", yaml.SafeDumper)
"""libyaml's emitter when installed: several times faster than PyYAML's, and the same text as
long as no string needs double quotes (the two fold long double-quoted strings differently)."""

_NULL = "tag:yaml.org,2002:null"
_BOOL = "tag:yaml.org,2002:bool"
_INT = "tag:yaml.org,2002:int"
_FLOAT = "tag:yaml.org,2002:float"
_STR = "tag:yaml.org,2002:str"
_SEQ = "tag:yaml.org,2002:seq"
_MAP = "tag:yaml.org,2002:map"


class _Unsupported(Exception):
    """A value the node builder leaves to PyYAML's representer."""


def world_yaml(world: dict[str, Any]) -> str:
    """The YAML text of ``world`` (see the module docstring)."""
    builder = _Builder()
    try:
        node = builder.node(world)
    except _Unsupported:
        dumper = FAST_DUMPER if plain_ascii(world) else yaml.SafeDumper
        return str(yaml.dump(world, Dumper=dumper, sort_keys=False, default_flow_style=None,
                             width=WIDTH))
    dumper = _FastResolving if builder.plain else _SafeResolving
    return str(yaml.serialize(node, Dumper=dumper, width=WIDTH))


def world_nodes(data: Any) -> Node:
    """The YAML node tree of ``data``, as PyYAML's SafeRepresenter (with ``sort_keys=False``
    and ``default_flow_style=None``) builds it."""
    return _Builder().node(data)


def _float_text(value: float) -> str:
    """A float's YAML scalar, as SafeRepresenter writes it."""
    if value != value:
        return ".nan"
    if value == float("inf"):
        return ".inf"
    if value == float("-inf"):
        return "-.inf"
    text = repr(value).lower()
    if "." not in text and "e" in text:  # 1e17: a YAML float needs its point
        text = text.replace("e", ".0e", 1)
    return text


class _Builder:
    """Builds the nodes of one document, noting whether every string is printable ASCII
    (:func:`plain_ascii`) on the way."""

    def __init__(self) -> None:
        self.plain = True
        self.seen: dict[int, tuple[Node, Any]] = {}
        """The lists and dicts built so far by id (with the object itself, so that its id is
        not reused while the tree is built)."""

    def node(self, data: Any) -> Node:
        """``data``'s node."""
        kind = type(data)
        if kind is float:
            return ScalarNode(_FLOAT, _float_text(data))
        if kind is str:
            if self.plain and not (data.isascii() and data.isprintable()):
                self.plain = False
            return ScalarNode(_STR, data)
        if kind is int:
            return ScalarNode(_INT, str(data))
        if kind is bool:
            return ScalarNode(_BOOL, "true" if data else "false")
        if data is None:
            return ScalarNode(_NULL, "null")
        if kind is not list and kind is not dict:
            raise _Unsupported(kind.__name__)
        known = self.seen.get(id(data))
        if known is not None:
            return known[0]
        flow = True
        if kind is list:
            items: list[Node] = []
            node: Node = SequenceNode(_SEQ, items)
            self.seen[id(data)] = (node, data)
            for item in data:
                child = self.node(item)
                flow = flow and isinstance(child, ScalarNode)
                items.append(child)
        else:
            pairs: list[tuple[Node, Node]] = []
            node = MappingNode(_MAP, pairs)
            self.seen[id(data)] = (node, data)
            for key, value in data.items():
                key_node, value_node = self.node(key), self.node(value)
                flow = (flow and isinstance(key_node, ScalarNode)
                        and isinstance(value_node, ScalarNode))
                pairs.append((key_node, value_node))
        node.flow_style = flow
        return node


def _resolve_kept(self: Any, kind: Any, value: Any, implicit: Any) -> Any:
    """A safe dumper's ``resolve`` keeping each scalar's answer: the emitter asks twice per
    scalar, and a world repeats its values (0.0, the same heights). Safe dumpers have no path
    resolvers, so a scalar's tag depends on its text and the implicit flags alone."""
    if kind is not ScalarNode:
        return BaseResolver.resolve(self, kind, value, implicit)
    kept = self.__dict__.setdefault("_resolved", {})
    key = (value, implicit)
    found = kept.get(key)
    if found is None:
        found = kept[key] = BaseResolver.resolve(self, kind, value, implicit)
    return found


_FastResolving: Any = type("_FastResolving", (FAST_DUMPER,), {"resolve": _resolve_kept})
"""libyaml's emitter, its resolver's answers kept."""
_SafeResolving: Any = type("_SafeResolving", (yaml.SafeDumper,), {"resolve": _resolve_kept})
"""PyYAML's emitter, its resolver's answers kept."""


def plain_ascii(data: Any) -> bool:
    """Whether every string in ``data`` (dicts, lists, scalars) is printable ASCII on one
    line: such strings are written plain or single-quoted, never double-quoted."""
    stack = [data]
    while stack:
        item = stack.pop()
        if isinstance(item, str):
            if not (item.isascii() and item.isprintable()):
                return False
        elif isinstance(item, dict):
            stack.extend(item.keys())
            stack.extend(item.values())
        elif isinstance(item, list | tuple):
            stack.extend(item)
    return True
