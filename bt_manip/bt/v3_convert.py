"""BehaviorTree.CPP v3 files to v4, following BehaviorTree.CPP's migration guide.

:func:`convert_v3` rewrites the text of a v3 file (ROS 2 Humble's Nav2 trees, for one) in
place, keeping every line where it was, so that a problem found in the result points at the
line of the original. What it rewrites:

- ``<root>``: ``BTCPP_format="4"`` (added, or replacing ``"3"``);
- the explicit forms ``<Action ID="X" .../>``, ``<Condition ID=...>``, ``<Decorator ID=...>``
  and ``<Control ID=...>`` become ``<X .../>`` (and their closing tags ``</X>``), outside a
  ``<TreeNodesModel>``, where the ID form is the declaration;
- node types renamed in v4: ``SequenceStar`` -> ``SequenceWithMemory``,
  ``RetryUntilSuccesful`` -> ``RetryUntilSuccessful``, ``SubTreePlus`` -> ``SubTree``;
- ``Parallel``'s ``threshold`` / ``success_threshold`` -> ``success_count`` and
  ``failure_threshold`` -> ``failure_count``;
- a SubTree's ``__shared_blackboard`` and a SubTreePlus's ``__autoremap`` -> ``_autoremap``;
- a blackboard reference written ``"${key}"`` (v3 reads it as ``"{key}"``; v4 does not) ->
  ``"{key}"``.

Everything else (attributes, comments, spacing) is kept as it is.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from xml.parsers import expat

from bt_manip.bt.xml_parse import as_strict_xml

RENAMED = {
    "SequenceStar": "SequenceWithMemory",
    "RetryUntilSuccesful": "RetryUntilSuccessful",
    "SubTreePlus": "SubTree",
}
"""Node types whose v4 name differs."""
PARALLEL_PORTS = {
    "threshold": "success_count",
    "success_threshold": "success_count",
    "failure_threshold": "failure_count",
}
"""Parallel's v3 ports and their v4 names."""
SUBTREE_PORTS = {"__shared_blackboard": "_autoremap", "__autoremap": "_autoremap"}
"""SubTree's v3 remapping attributes and their v4 name."""
EXPLICIT = ("Action", "Condition", "Decorator", "Control")
"""Elements naming their node type in an ID attribute."""

Rewrite = tuple[int, str]
"""(line, what was rewritten), e.g. ``(12, "SequenceStar -> SequenceWithMemory")``."""

_TOKEN = re.compile(r"<!--.*?-->|<!\[CDATA\[.*?\]\]>|<\?.*?\?>|<![^>]*>"
                    r"""|</?[^<>"']*(?:(?:"[^"]*"|'[^']*')[^<>"']*)*>""", re.S)
"""A comment, CDATA, processing instruction, declaration or tag (a ``>`` inside a quoted
attribute value, legal XML, does not end the tag)."""
_NAME = re.compile(r"</?\s*([^\s/>]+)")
_ATTR = re.compile(r"""([^\s=/>]+)(\s*=\s*)("[^"]*"|'[^']*')""")


class ConvertError(ValueError):
    """Input that is not well-formed XML: the line of the problem and what it is."""

    def __init__(self, line: int, message: str) -> None:
        super().__init__(f"{line}: {message}")
        self.line = line
        self.message = message


@dataclass
class _Open:
    tag: str
    written: str
    in_model: bool


def check_well_formed(text: str) -> None:
    """Raise :class:`ConvertError` with the line when ``text`` is not XML that BehaviorTree.CPP
    reads: well-formed, or so once what its parser takes and strict XML refuses (text before
    the first element, a raw ``<`` in an attribute value, a ``&`` that starts no reference)
    is stood in for, as the loader does (:func:`~bt_manip.bt.xml_parse.as_strict_xml`)."""
    try:
        expat.ParserCreate().Parse(text.encode("utf-8"), True)
        return
    except expat.ExpatError as exc:
        first = exc
    strict = as_strict_xml(text)
    if strict is None:
        raise ConvertError(first.lineno, expat.ErrorString(first.code)) from None
    try:
        expat.ParserCreate().Parse(strict.encode("utf-8"), True)
    except expat.ExpatError as exc:
        raise ConvertError(exc.lineno, expat.ErrorString(exc.code)) from None


def convert_v3(text: str) -> tuple[str, list[Rewrite]]:
    """The v4 form of the v3 XML ``text`` and the rewrites made, by line (module
    docstring). Lines stay where they are. Raises :class:`ConvertError` for text that is not
    well-formed XML."""
    check_well_formed(text)
    out: list[str] = []
    rewrites: list[Rewrite] = []
    stack: list[_Open] = []
    pos = 0
    seen_root = False
    for match in _TOKEN.finditer(text):
        token = match.group(0)
        line = text.count("\n", 0, match.start()) + 1
        out.append(text[pos:match.start()])
        pos = match.end()
        if token.startswith(("<!", "<?")):
            out.append(token)
            continue
        name_match = _NAME.match(token)
        if name_match is None:  # pragma: no cover - well-formed XML has names
            out.append(token)
            continue
        tag = name_match.group(1)
        if token.startswith("</"):
            opened = stack.pop() if stack else _Open(tag, tag, False)
            out.append(token.replace(tag, opened.written, 1) if opened.written != tag else token)
            continue
        in_model = bool(stack and stack[-1].in_model) or tag == "TreeNodesModel"
        new, written = _start_tag(token, tag, line, in_model, rewrites,
                                  root=not seen_root)
        seen_root = True
        out.append(new)
        if not token.rstrip().endswith("/>"):
            stack.append(_Open(tag, written, in_model))
    out.append(text[pos:])
    return "".join(out), rewrites


def _start_tag(token: str, tag: str, line: int, in_model: bool, rewrites: list[Rewrite],
               root: bool) -> tuple[str, str]:
    """The rewritten start tag and the element name it now has."""
    if root and tag == "root":
        return _root(token, line, rewrites), tag
    if in_model:
        return token, tag
    new, written = token, tag
    if tag in EXPLICIT:
        id_attr = next((m for m in _ATTR.finditer(token) if m.group(1) == "ID"), None)
        if id_attr is not None:
            node = id_attr.group(3)[1:-1]
            if _plain_name(node):
                start, end = id_attr.span()
                while start > 0 and token[start - 1].isspace():
                    start -= 1
                new = token[:start] + token[end:]
                new = new.replace(tag, node, 1)
                written = node
                rewrites.append((line, f'<{tag} ID="{node}"> -> <{node}>'))
    if written in RENAMED:
        renamed = RENAMED[written]
        new = new.replace(written, renamed, 1)
        rewrites.append((line, f"{written} -> {renamed}"))
        old_type, written = written, renamed
    else:
        old_type = written
    ports = (PARALLEL_PORTS if written == "Parallel"
             else SUBTREE_PORTS if written == "SubTree" else {})
    if ports:
        new = _rename_attributes(new, ports, old_type, line, rewrites)
    return _dollar_references(new, line, rewrites), written


_DOLLAR = re.compile(r"\s*\$\{(.*)\}\s*", re.S)
"""A v3 blackboard reference ``${key}`` (spaces around it allowed, as v3 strips them)."""


def _dollar_references(token: str, line: int, rewrites: list[Rewrite]) -> str:
    """``token`` with each attribute value that is a v3 ``${key}`` reference written
    ``{key}`` (the element's ``ID`` and ``name`` are names, left as they are)."""
    def swap(m: re.Match[str]) -> str:
        key, quoted = m.group(1), m.group(3)
        ref = _DOLLAR.fullmatch(quoted[1:-1])
        if key in ("ID", "name") or ref is None:
            return m.group(0)
        rewrites.append((line, f"{key}: ${{{ref.group(1)}}} -> {{{ref.group(1)}}}"))
        return key + m.group(2) + quoted[0] + "{" + ref.group(1) + "}" + quoted[0]

    return _ATTR.sub(swap, token)


def _plain_name(name: str) -> bool:
    return bool(re.fullmatch(r"[A-Za-z_][\w.\-:]*", name))


def _rename_attributes(token: str, names: dict[str, str], node: str, line: int,
                       rewrites: list[Rewrite]) -> str:
    def swap(m: re.Match[str]) -> str:
        old = m.group(1)
        if old not in names:
            return m.group(0)
        rewrites.append((line, f"{node} {old} -> {names[old]}"))
        return names[old] + m.group(2) + m.group(3)

    return _ATTR.sub(swap, token)


def _root(token: str, line: int, rewrites: list[Rewrite]) -> str:
    fmt = next((m for m in _ATTR.finditer(token) if m.group(1) == "BTCPP_format"), None)
    if fmt is None:
        rewrites.append((line, 'no BTCPP_format -> BTCPP_format="4"'))
        return token.replace("root", 'root BTCPP_format="4"', 1)
    value = fmt.group(3)[1:-1].strip()
    if value == "4":
        return token
    rewrites.append((line, f'BTCPP_format="{value}" -> BTCPP_format="4"'))
    start, end = fmt.span(3)
    return token[:start] + '"4"' + token[end:]
