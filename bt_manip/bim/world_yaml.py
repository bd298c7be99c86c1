"""world.yaml's text: the world's dicts and lists as YAML, written fast and always alike.

The text is that of ``yaml.dump(world, Dumper=yaml.SafeDumper, sort_keys=False,
default_flow_style=None, width=100)``. :func:`world_yaml` makes it one of two ways:

- directly (:func:`direct_yaml`), for a world of dicts with string keys, lists, floats, ints,
  bools, None and printable ASCII strings, each list and dict met once: the text is written
  as PyYAML's emitter writes it, following the emitter's own column, indentation and
  whitespace bookkeeping (block mappings and sequences, a sequence in a mapping not indented,
  flow style for a list or dict of scalars only, flow items wrapped past column 100, long
  plain or single-quoted strings folded at a space past column 100). Whether a string is
  written plain or in single quotes is the emitter's answer (its resolver and its scalar
  analysis, asked once per distinct string). Anything else (another type, an anchor and
  alias, a string of other characters, a key too long for the simple ``key:`` form, a scalar
  document) is left to the second way, as a whole;
- through YAML nodes, built here (:func:`world_nodes`) rather than by PyYAML's representer,
  which looks each value's type up its class hierarchy: the same nodes, tags, values and flow
  styles, and a list or dict met twice is the same node (an anchor and an alias), as PyYAML's
  SafeRepresenter makes them. libyaml's emitter writes them when every string is printable
  ASCII (written plain or in single quotes: the two emitters fold long double-quoted strings
  differently; the strings are checked while the nodes are built) and no mapping key is empty
  or longer than 120 characters (libyaml's emitter writes such keys as simple keys, PyYAML's
  after ``? ``), PyYAML's otherwise; either way the resolver's answer for each scalar text is
  kept (the emitter asks for it twice per scalar).

A value of any other type than None, bool, int, float, str, list and dict goes through
``yaml.dump`` as a whole.
"""

from __future__ import annotations

import io
import re
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


SIMPLE_KEY = 122
"""The longest string PyYAML's emitter writes as a simple key (``key: value``): a simple key's
text and its tag (``!!str``) are under 128 characters; a longer key is written after ``? ``."""
_LIBYAML_KEY = 120
"""A mapping key longer than this and up to 128 characters may be a simple key to libyaml's
emitter (which counts the key's text alone) and not to PyYAML's (which counts its tag too), and
an empty key is one to libyaml's emitter alone: a world holding such a key is written by
PyYAML's emitter."""


class _Unsupported(Exception):
    """A value the node builder leaves to PyYAML's representer."""


class _Abandon(Exception):
    """A document the direct writer leaves to the node builder (see :func:`direct_yaml`)."""


def world_yaml(world: dict[str, Any]) -> str:
    """The YAML text of ``world`` (see the module docstring)."""
    text = direct_yaml(world)
    if text is not None:
        return text
    builder = _Builder()
    try:
        node = builder.node(world)
    except _Unsupported:
        same = plain_ascii(world) and not _odd_keys(world)
        dumper = FAST_DUMPER if same else yaml.SafeDumper
        return str(yaml.dump(world, Dumper=dumper, sort_keys=False, default_flow_style=None,
                             width=WIDTH))
    dumper = _FastResolving if builder.plain else _SafeResolving
    return str(yaml.serialize(node, Dumper=dumper, width=WIDTH))


def direct_yaml(data: Any) -> str | None:
    """``data``'s YAML text written directly, as :func:`world_yaml` writes it, or None when
    ``data`` is not a dict or list of dicts with string keys, lists, floats, ints, bools,
    None and printable ASCII strings, each list and dict met once, its keys simple keys."""
    try:
        return _Writer().document(data)
    except _Abandon:
        return None


def world_nodes(data: Any) -> Node:
    """The YAML node tree of ``data``, as PyYAML's SafeRepresenter (with ``sort_keys=False``
    and ``default_flow_style=None``) builds it."""
    return _Builder().node(data)


def _float_text(value: float) -> str:
    """A float's YAML scalar, as SafeRepresenter writes it."""
    text = repr(value)
    if "e" not in text and "n" not in text:  # a finite float's digits and point
        return text
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


_ANALYST = yaml.SafeDumper(io.StringIO())
"""A safe dumper asked only for its resolver's tag and its emitter's analysis of a string."""
_PLAIN_WORD = re.compile(r"[A-Za-z0-9_/][A-Za-z0-9_./-]*")
"""Strings holding no YAML indicator (no space, no ``:``, ``#``, ``,``, bracket or brace, not
starting with ``-``, ``.`` or a quote): written plain unless they read as another type."""
_SCALARS = frozenset({float, int, str, bool, type(None)})
"""The scalar types the direct writer writes."""


class _Writer:
    """Writes one document as PyYAML's emitter writes it, keeping the emitter's state: the
    ``column``, ``whitespace`` (the last character written is a space or a line break) and
    ``indention`` (the line holds indentation and indicators only); an indent argument is the
    emitter's indentation of the node's parent (None at the document's root)."""

    def __init__(self) -> None:
        self.parts: list[str] = []
        self.column = 0
        self.whitespace = True
        self.indention = True
        self.seen: set[int] = set()
        """The ids of the lists and dicts written (one met again would be an alias)."""
        self.strings: dict[str, tuple[str, str]] = {}
        """Each string's text in block and in flow context: plain, or in single quotes."""

    def document(self, data: Any) -> str:
        """The text of the document holding ``data``."""
        if type(data) is not dict and type(data) is not list:
            raise _Abandon  # a scalar document (a plain one ends with "...")
        self.node(data, None, False)
        self.write_indent(0)
        return "".join(self.parts)

    def write_indent(self, indent: int) -> None:
        """The emitter's ``write_indent``: a line break unless the line holds indicators only
        and is not past ``indent``, then spaces up to ``indent``."""
        if (not self.indention or self.column > indent
                or (self.column == indent and not self.whitespace)):
            self.parts.append("\n" + " " * indent)
            self.column = indent
            self.indention = self.whitespace = True
        elif self.column < indent:
            self.parts.append(" " * (indent - self.column))
            self.column = indent
            self.whitespace = True

    def text(self, value: Any, flow: int) -> str:
        """A scalar's text in block (``flow`` 0) or flow (1) context."""
        kind = type(value)
        if kind is float:
            return _float_text(value)
        if kind is str:
            return (self.strings.get(value) or self.string_texts(value))[flow]
        if kind is int:
            return str(value)
        if kind is bool:
            return "true" if value else "false"
        if value is None:
            return "null"
        raise _Abandon

    def string_texts(self, value: str) -> tuple[str, str]:
        """A string's texts in block and flow context, as the emitter chooses its style: plain
        when it reads back as a string and the emitter's analysis allows plain in the context,
        else in single quotes (always allowed for printable ASCII)."""
        if not (value.isascii() and value.isprintable()):
            raise _Abandon
        quoted = "'" + value.replace("'", "''") + "'"
        if _ANALYST.resolve(ScalarNode, value, (True, False)) != _STR:
            texts = (quoted, quoted)
        elif _PLAIN_WORD.fullmatch(value):
            texts = (value, value)
        else:
            analysis = _ANALYST.analyze_scalar(value)
            if not analysis.allow_single_quoted:
                raise _Abandon
            texts = (value if analysis.allow_block_plain else quoted,
                     value if analysis.allow_flow_plain else quoted)
        self.strings[value] = texts
        return texts

    def node(self, data: Any, indent: int | None, in_mapping: bool) -> None:
        """Writes a node in block context: a mapping's value (``in_mapping``), a sequence's
        item or the root."""
        kind = type(data)
        if kind is not dict and kind is not list:
            self.scalar(self.text(data, 0), 2 if indent is None else indent + 2, True)
            return
        if id(data) in self.seen:
            raise _Abandon  # an anchor and an alias
        self.seen.add(id(data))
        for item in data.values() if kind is dict else data:
            if type(item) not in _SCALARS:
                break
        else:  # scalars only (or none): flow style
            if kind is dict:
                self.flow_mapping(data, indent)
            else:
                self.flow_sequence(data, indent)
            return
        if kind is dict:
            self.block_mapping(data, indent)
        else:
            self.block_sequence(data, indent, in_mapping)

    def block_mapping(self, data: dict[Any, Any], indent: int | None) -> None:
        """Writes a block mapping, one ``key:`` a line."""
        inner = 0 if indent is None else indent + 2
        for key, value in data.items():
            if type(key) is not str or not 0 < len(key) <= SIMPLE_KEY:
                raise _Abandon  # another key type, or a key written after "? "
            self.write_indent(inner)  # the line then ends with whitespace: no space before
            key_text = (self.strings.get(key) or self.string_texts(key))[0]
            if type(value) in _SCALARS:
                text = self.text(value, 0)
                end = self.column + len(key_text) + 2 + len(text)
                if end <= WIDTH + 1 or " " not in text:  # "key: value", the value not folded
                    self.parts.append(f"{key_text}: {text}")
                    self.column = end
                    self.whitespace = self.indention = False
                    continue
            self.parts.append(key_text + ":")
            self.column += len(key_text) + 1
            self.whitespace = self.indention = False
            self.node(value, inner, True)

    def block_sequence(self, data: list[Any], indent: int | None, in_mapping: bool) -> None:
        """Writes a block sequence, one ``-`` a line; in a mapping, not indented."""
        if indent is None:
            inner = 0
        elif in_mapping and not self.indention:
            inner = indent
        else:
            inner = indent + 2
        for item in data:
            self.write_indent(inner)  # the line then ends with whitespace: no space before
            self.parts.append("-")
            self.column += 1
            self.whitespace = False
            self.node(item, inner, False)

    def flow_sequence(self, data: list[Any], indent: int | None) -> None:
        """Writes a list of scalars in flow style, wrapped as the emitter wraps it."""
        texts = [_float_text(item) if type(item) is float else self.text(item, 1)
                 for item in data]
        if not self.flow_fits(", ".join(texts), "[", "]"):
            self.flow_open("[")
            inner = 2 if indent is None else indent + 2
            for i, text in enumerate(texts):
                if i:
                    self.flow_comma()
                if self.column > WIDTH:
                    self.write_indent(inner)
                self.scalar(text, inner + 2, True)
            self.flow_close("]")

    def flow_mapping(self, data: dict[Any, Any], indent: int | None) -> None:
        """Writes a dict of scalars in flow style, wrapped as the emitter wraps it."""
        pairs: list[tuple[str, str]] = []
        for key, value in data.items():
            if type(key) is not str or not 0 < len(key) <= SIMPLE_KEY:
                raise _Abandon
            pairs.append(((self.strings.get(key) or self.string_texts(key))[1],
                          self.text(value, 1)))
        if not self.flow_fits(", ".join([f"{k}: {v}" for k, v in pairs]), "{", "}"):
            self.flow_open("{")
            inner = 2 if indent is None else indent + 2
            for i, (key_text, value_text) in enumerate(pairs):
                if i:
                    self.flow_comma()
                if self.column > WIDTH:
                    self.write_indent(inner)
                self.scalar(key_text, inner + 2, False)
                self.parts.append(":")
                self.column += 1
                self.whitespace = False
                self.scalar(value_text, inner + 2, True)
            self.flow_close("}")

    def flow_fits(self, body: str, opening: str, closing: str) -> bool:
        """Writes a flow collection on the line if it ends by column ``WIDTH`` + 1: then no
        item starts past ``WIDTH`` and no string folds; whether it was written."""
        if not self.whitespace:
            opening = " " + opening
        end = self.column + len(opening) + len(body) + 1
        if end > WIDTH + 1:
            return False
        self.parts.append(opening + body + closing)
        self.column = end
        self.whitespace = self.indention = False
        return True

    def flow_open(self, indicator: str) -> None:
        """The emitter's ``[`` or ``{`` indicator."""
        self.parts.append(indicator if self.whitespace else " " + indicator)
        self.column += 1 if self.whitespace else 2
        self.whitespace = True
        self.indention = False

    def flow_comma(self) -> None:
        """The emitter's ``,`` between flow items."""
        self.parts.append(",")
        self.column += 1
        self.whitespace = False

    def flow_close(self, indicator: str) -> None:
        """The emitter's ``]`` or ``}`` indicator."""
        self.parts.append(indicator)
        self.column += 1
        self.whitespace = False

    def scalar(self, text: str, indent: int, split: bool) -> None:
        """Writes a scalar's text (plain, or quoted: a plain scalar never starts with a quote)
        after a space unless the line ends with whitespace; unless it is a simple key
        (``split`` false), folded at single spaces past column ``WIDTH``, the next line
        indented to ``indent``."""
        if not self.whitespace:
            self.parts.append(" ")
            self.column += 1
        self.whitespace = self.indention = False
        if split and self.column + len(text) > WIDTH + 1 and " " in text:
            if text[0] == "'":
                self.fold_quoted(text[1:-1].replace("''", "'"), indent)
            else:
                self.fold_plain(text, indent)
            self.whitespace = self.indention = False
        else:
            self.parts.append(text)
            self.column += len(text)

    def fold_plain(self, text: str, indent: int) -> None:
        """The emitter's ``write_plain`` of a string without line breaks."""
        spaces = False
        start = end = 0
        while end <= len(text):
            ch = text[end] if end < len(text) else None
            if spaces:
                if ch != " ":
                    if start + 1 == end and self.column > WIDTH:
                        self.write_indent(indent)
                        self.whitespace = self.indention = False
                    else:
                        self.parts.append(text[start:end])
                        self.column += end - start
                    start = end
            elif ch is None or ch == " ":
                self.parts.append(text[start:end])
                self.column += end - start
                start = end
            if ch is not None:
                spaces = ch == " "
            end += 1

    def fold_quoted(self, text: str, indent: int) -> None:
        """The emitter's ``write_single_quoted`` of a string without line breaks, quotes
        included."""
        self.parts.append("'")
        self.column += 1
        spaces = False
        start = end = 0
        while end <= len(text):
            ch = text[end] if end < len(text) else None
            if spaces:
                if ch != " ":
                    if (start + 1 == end and self.column > WIDTH and start != 0
                            and end != len(text)):
                        self.write_indent(indent)
                    else:
                        self.parts.append(text[start:end])
                        self.column += end - start
                    start = end
            elif (ch is None or ch == " " or ch == "'") and start < end:
                self.parts.append(text[start:end])
                self.column += end - start
                start = end
            if ch == "'":
                self.parts.append("''")
                self.column += 2
                start = end + 1
            if ch is not None:
                spaces = ch == " "
            end += 1
        self.parts.append("'")
        self.column += 1


class _Builder:
    """Builds the nodes of one document, noting whether every string is printable ASCII
    (:func:`plain_ascii`) on the way."""

    def __init__(self) -> None:
        self.plain = True
        """Whether libyaml's emitter writes the nodes as PyYAML's does: every string printable
        ASCII, no mapping key empty or longer than ``_LIBYAML_KEY``."""
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
                if isinstance(key_node, ScalarNode) and not 0 < len(key_node.value) <= _LIBYAML_KEY:
                    self.plain = False
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


def _odd_keys(data: Any) -> bool:
    """Whether ``data`` holds a dict with a string key empty or longer than ``_LIBYAML_KEY``."""
    stack = [data]
    while stack:
        item = stack.pop()
        if isinstance(item, dict):
            if any(isinstance(key, str) and not 0 < len(key) <= _LIBYAML_KEY for key in item):
                return True
            stack.extend(item.values())
        elif isinstance(item, list | tuple):
            stack.extend(item)
    return False
