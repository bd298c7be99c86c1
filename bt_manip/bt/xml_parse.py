"""Safe XML reading with line numbers for every element.

XML files are untrusted input. This reader uses expat directly and refuses any document type
declaration (so no entity can be declared, expanded or fetched), bounds the file size, the
nesting depth and the number of elements, and records the line and column of every element.

BehaviorTree.CPP reads its files with tinyxml2, which takes what strict XML refuses and real
trees contain: a raw ``<`` or ``&&`` in an attribute value (``if="A<2 && B>0"``), a ``&`` that
starts no character reference, text before the first element (``// clang-format off``). A
document that expat refuses is read again through :func:`as_strict_xml`, which stands a placeholder
character in for each of those ``<`` and ``&`` and blanks the text before the first element;
every replacement keeps the length of what it replaces, so lines and columns stay those of the
file, and the placeholders are turned back when attribute values and text are read.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from xml.parsers import expat

from bt_manip.errors import InputError, Problem
from bt_manip.input_files import read_bounded, size_text

MAX_BYTES = 10 * 1024 * 1024
MAX_DEPTH = 256
MAX_ELEMENTS = 200_000


@dataclass
class Element:
    """An XML element: tag, attributes in document order, children, and where it starts."""

    tag: str
    attrib: dict[str, str]
    line: int
    column: int
    children: list[Element] = field(default_factory=list)
    text: str = ""

    def get(self, key: str, default: str | None = None) -> str | None:
        return self.attrib.get(key, default)


class XmlError(Exception):
    """The file is not acceptable XML; carries one :class:`Problem`."""

    def __init__(self, problem: Problem) -> None:
        super().__init__(str(problem))
        self.problem = problem


class _Refused(Exception):
    pass


LT, AMP = "\ufdd0", "\ufdd1"
"""Stand-ins for a raw ``<`` in an attribute value and a ``&`` that starts no reference:
Unicode noncharacters, which no tree file holds (one that does is read strictly)."""
_REFERENCE = re.compile(AMP + r"(?=(?:amp|lt|gt|quot|apos|#[0-9]+|#x[0-9a-fA-F]+);)")
_SKIP = (  # markup that needs no change; possessive, so nothing is scanned twice
    r"<!--.*?(?:-->|\Z)|<!\[CDATA\[.*?(?:\]\]>|\Z)|<\?.*?(?:\?>|\Z)"
    r"|<[^<>\"']*+(?:(?:\"[^\"<]*+\"|'[^'<]*+')[^<>\"']*+)*+(?:>|(?=<))|[^<]++")
_MARKUP = re.compile(
    rf"(?:{_SKIP})++"  # a run of it, handed back whole
    r"|(<[^<>\"'!?]*+(?:(?:\"[^\"<]*+\"|'[^'<]*+')[^<>\"']*+)*+"  # a tag with a raw < in a
    r"(?:\"[^\"<]*+<[^\"]*+(?:\"|\Z)|'[^'<]*+<[^']*+(?:'|\Z))"  # value: to that value's end,
    r"(?:[^<>\"']++|\"[^\"]*+(?:\"|\Z)|'[^']*+(?:'|\Z))*+(?:>|(?=<)|\Z))",  # then the tag's
    re.S)
_PROLOG = re.compile(r"(?:[^<]++|<!--.*?(?:-->|\Z)|<\?.*?(?:\?>|\Z))*+", re.S)
_PROLOG_TEXT = re.compile(r"<!--.*?(?:-->|\Z)|<\?.*?(?:\?>|\Z)|([^<]+)", re.S)


class _TooMany(Exception):
    pass


class _Tags:
    """The replacement of :data:`_MARKUP`'s matches; stops after :data:`MAX_ELEMENTS` changed
    tags (a document with more is refused anyway)."""

    def __init__(self) -> None:
        self.changed = 0

    def __call__(self, match: re.Match[str]) -> str:
        tag = match.group(1)
        if tag is None:
            return match.group()
        self.changed += 1
        if self.changed > MAX_ELEMENTS:
            raise _TooMany
        return "<" + tag[1:].replace("<", LT)  # every < after the first is in a quoted value


def _blank(match: re.Match[str]) -> str:
    text = match.group(1)
    if text is None or not text.strip("\ufeff \t\r\n"):
        return match.group()
    bom = "\ufeff" if text.startswith("\ufeff") else ""  # a byte order mark stays
    return bom + "\n".join(" " * len(line) for line in text[len(bom):].split("\n"))


def as_strict_xml(text: str) -> str | None:
    """``text`` as strict XML takes it, or None when there is nothing to change (see the
    module docstring); lines and columns stay those of ``text``. Linear in the length of the
    text: no expression rescans what it passed, and Python code runs only for each tag it
    changes (and each piece of the text before the first element)."""
    if LT in text or AMP in text:
        return None
    out = _REFERENCE.sub("&", text.replace("&", AMP))  # the references are & again
    prolog = _PROLOG.match(out)
    end = prolog.end() if prolog is not None else 0
    try:
        out = _PROLOG_TEXT.sub(_blank, out[:end]) + _MARKUP.sub(_Tags(), out[end:])
    except _TooMany:
        return None
    return None if out == text else out


def parse_xml_text(text: str | bytes, file: str) -> Element:
    """Parse XML text into :class:`Element` objects; raises :class:`XmlError`.

    A document that expat refuses is read again as BehaviorTree.CPP's parser reads it (see
    :func:`as_strict_xml`); if that fails too, the error is the second reading's."""
    data = text.encode("utf-8") if isinstance(text, str) else text
    if len(data) > MAX_BYTES:
        raise XmlError(Problem(file, None,
                               f"file is larger than the limit of {size_text(MAX_BYTES)}"))
    try:
        return _parse(data, file, False)
    except XmlError as strict:
        if not strict.problem.message.startswith("malformed XML"):
            raise
        try:
            lenient = as_strict_xml(data.decode("utf-8"))
        except UnicodeDecodeError:
            lenient = None
        if lenient is None:
            raise
    return _parse(lenient.encode("utf-8"), file, True)


def _parse(data: bytes, file: str, placeholders: bool) -> Element:
    """expat on ``data``; with ``placeholders``, :data:`LT` and :data:`AMP` are turned back."""
    parser = expat.ParserCreate()
    stack: list[Element] = []
    roots: list[Element] = []
    count = 0

    def refuse(message: str) -> None:
        raise _Refused(message)

    def start(tag: str, attrs: dict[str, str]) -> None:
        nonlocal count
        count += 1
        if count > MAX_ELEMENTS:
            refuse(f"more than {MAX_ELEMENTS} elements")
        if len(stack) >= MAX_DEPTH:
            refuse(f"elements nested deeper than {MAX_DEPTH} levels")
        if placeholders:
            attrs = {k: v.replace(LT, "<").replace(AMP, "&") for k, v in attrs.items()}
        element = Element(tag, dict(attrs), parser.CurrentLineNumber,
                          parser.CurrentColumnNumber + 1)
        if stack:
            stack[-1].children.append(element)
        else:
            roots.append(element)
        stack.append(element)

    def end(tag: str) -> None:
        stack.pop()

    def chars(data: str) -> None:
        if stack:
            stack[-1].text += data.replace(AMP, "&") if placeholders else data

    def doctype(*args: object) -> None:
        refuse("document type declarations (DOCTYPE) are not allowed")

    def entity(*args: object) -> None:
        refuse("entity declarations are not allowed")

    def external(*args: object) -> int:
        refuse("external entities are not allowed")
        return 0

    parser.StartElementHandler = start
    parser.EndElementHandler = end
    parser.CharacterDataHandler = chars
    parser.StartDoctypeDeclHandler = doctype
    parser.EntityDeclHandler = entity
    parser.UnparsedEntityDeclHandler = entity
    parser.ExternalEntityRefHandler = external
    parser.SetParamEntityParsing(expat.XML_PARAM_ENTITY_PARSING_NEVER)
    parser.ordered_attributes = False
    try:
        parser.Parse(data, True)
    except _Refused as e:
        raise XmlError(Problem(file, parser.CurrentLineNumber, f"refused XML: {e}")) from None
    except expat.ExpatError as e:
        raise XmlError(
            Problem(file, e.lineno, f"malformed XML: {expat.ErrorString(e.code)}", e.offset + 1)
        ) from None
    if not roots:
        raise XmlError(Problem(file, 1, "malformed XML: no root element"))
    return roots[0]


def parse_xml_file(path: str) -> Element:
    """Read and parse ``path``; raises :class:`XmlError` (also for a missing file)."""
    try:
        data = read_bounded(path, MAX_BYTES, "file")
    except InputError as e:
        raise XmlError(e.problems[0]) from None
    return parse_xml_text(data, path)
