"""Safe XML reading with line numbers for every element.

XML files are untrusted input. This reader uses expat directly and refuses any document type
declaration (so no entity can be declared, expanded or fetched), bounds the file size, the
nesting depth and the number of elements, and records the line and column of every element.
"""

from __future__ import annotations

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


def parse_xml_text(text: str | bytes, file: str) -> Element:
    """Parse XML text into :class:`Element` objects; raises :class:`XmlError`."""
    data = text.encode("utf-8") if isinstance(text, str) else text
    if len(data) > MAX_BYTES:
        raise XmlError(Problem(file, None,
                               f"file is larger than the limit of {size_text(MAX_BYTES)}"))
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
            stack[-1].text += data

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
