"""Reading an IFC file within bounds, and naming its entities in problems.

An IFC file in the STEP physical format (ISO 10303-21) holds one entity per line
(``#42=IFCWALL('2O2Fr$t4X7Zf8NOew3FLOH',$,'Wall 1',...);``), so a problem about an entity is
reported as ``file:line: #42 IfcWall 'Wall 1': message``. The line is found only when a problem
is reported: the entity's ``#42=`` is searched for in the bytes and the newlines before it are
counted; after a few problems, the offsets of every entity and the line starts are indexed at
once (a line is then a bisection). A problem thus costs about one pass over the file, however
many entities it holds.
"""

from __future__ import annotations

import re
from bisect import bisect_right
from dataclasses import dataclass, field
from functools import cache
from pathlib import Path
from typing import Any

from bt_manip.bim.parse_log import clear_log, parse_problems
from bt_manip.errors import InputError, Problem
from bt_manip.input_files import MIB, read_bounded

MAX_IFC_BYTES = 64 * MIB
"""Largest IFC file read."""
SCHEMAS = ("IFC2X3", "IFC4", "IFC4X3")
"""Schemas read: ``IFC4X3`` and its addenda are read like IFC4."""

_ENTITY_LINE = re.compile(rb"^[ \t]*#(\d+)[ \t]*=", re.MULTILINE)
DIRECT_LOOKUPS = 8
"""Entities looked up one by one (a search of the bytes each) before all are indexed."""


@dataclass
class IfcSource:
    """An opened IFC file: the ifcopenshell model, its bytes, its length unit in metres."""

    path: Path
    data: bytes
    model: Any
    scale: float
    schema: str
    problems: list[Problem] = field(default_factory=list)
    _starts: Any = None
    _offsets: dict[int, int] | None = None
    _lookups: int = 0
    origins: dict[int, tuple[float, float, float] | None] = field(default_factory=dict)
    """Storeys' placement origins (m) by step id, each computed once
    (:func:`~bt_manip.bim.storeys.storey_origin`)."""
    shift: tuple[float, float] = (0.0, 0.0)
    """Subtracted (m) from the model's x and y to give the world's: nonzero for a model placed
    far from its origin (:func:`~bt_manip.bim.convert.model_shift`)."""

    def line_of(self, step_id: int) -> int | None:
        """1-based line on which entity ``#step_id`` is defined (None if not found)."""
        offset = self.offset_of(step_id)
        if offset is None:
            return None
        if self._starts is None and self._lookups <= DIRECT_LOOKUPS:
            return self.data.count(b"\n", 0, offset) + 1  # a few: count, no index
        if self._starts is None:
            import numpy as np

            newlines = np.flatnonzero(np.frombuffer(self.data, dtype=np.uint8) == 10)
            self._starts = newlines.tolist()
        return bisect_right(self._starts, offset) + 1

    def offset_of(self, step_id: int) -> int | None:
        """Byte offset of the line defining ``#step_id`` (None if not found)."""
        if self._offsets is not None:
            return self._offsets.get(step_id)
        self._lookups += 1
        if self._lookups > DIRECT_LOOKUPS:
            self._offsets = {}
            for m in _ENTITY_LINE.finditer(self.data):
                self._offsets.setdefault(int(m.group(1)), m.start())
            return self._offsets.get(step_id)
        return _find_definition(self.data, step_id)

    def problem(self, entity: Any, message: str) -> Problem:
        """``file:line: #id IfcClass 'Name': message`` about ``entity``."""
        step_id = int(entity.id())
        name = getattr(entity, "Name", None)
        label = f"#{step_id} {entity.is_a()}" + (f" '{name}'" if name else "")
        return Problem(str(self.path), self.line_of(step_id), f"{label}: {message}")

    def fail(self, entity: Any, message: str) -> None:
        """Collect a problem about ``entity``."""
        self.problems.append(self.problem(entity, message))

    def raise_problems(self) -> None:
        """Raise the collected problems, if any, as one InputError."""
        if self.problems:
            raise InputError(list(self.problems))


def _find_definition(data: bytes, step_id: int) -> int | None:
    """Offset of the line starting ``#step_id=`` (blanks allowed around the ``=``)."""
    needle = b"#%d" % step_id
    at = data.find(needle)
    while at >= 0:
        end = at + len(needle)
        rest = data[end:end + 16].lstrip(b" \t")
        line_start = data.rfind(b"\n", 0, at) + 1
        if rest.startswith(b"=") and not data[line_start:at].strip(b" \t\r"):
            return line_start
        at = data.find(needle, end)
    return None


def parsed_release(schema: str) -> str | None:
    """The schema the parser reads a file of ``schema`` (its header's name) as: the release
    itself when the parser has it, else the final release of its line (IFC4X3 and its
    candidates and addenda as IFC4X3_ADD2, IFC2X3_TC1 as IFC2X3, IFC4's addenda as IFC4);
    None for a schema none of these covers (IFC4X1, IFC4X2) or not of :data:`SCHEMAS`' lines
    at all."""
    if not schema.startswith(SCHEMAS):
        return None
    known = _parser_schemas()
    if schema in known:
        return schema
    for line in ("IFC4X3", "IFC2X3"):
        if schema.startswith(line):
            return max((k for k in known if k.startswith(line)), default=None)
    if schema == "IFC4" or schema.startswith("IFC4_"):
        return "IFC4" if "IFC4" in known else None
    return None


@cache
def _parser_schemas() -> frozenset[str]:
    """The schemas ifcopenshell's parser reads (asked once: the call takes about a
    millisecond, as long as parsing a small file)."""
    import ifcopenshell.ifcopenshell_wrapper as wrapper

    return frozenset(wrapper.schema_names())


def open_ifc(path: str | Path) -> IfcSource:
    """Read and parse an IFC file (STEP format, at most :data:`MAX_IFC_BYTES`); an entity the
    parser cannot read is a problem at its line (:mod:`~bt_manip.bim.parse_log`)."""
    import ifcopenshell
    import ifcopenshell.util.unit

    path = Path(path)
    data = read_bounded(path, MAX_IFC_BYTES, "IFC file")
    head = data[:4096].lstrip(b"\xef\xbb\xbf \t\r\n")
    if not head.startswith(b"ISO-10303-21;"):
        hint = ""
        if head.startswith(b"PK"):
            hint = " (an .ifczip archive: unzip it first)"
        elif head.startswith(b"<"):
            hint = " (ifcXML is not read: export the model as .ifc)"
        raise InputError.single(
            str(path), 1, f"not an IFC file: it does not start with 'ISO-10303-21;'{hint}"
        )
    schema_match = re.search(rb"FILE_SCHEMA\s*\(\s*\(\s*'([A-Za-z0-9_]+)'", data[:65536])
    if schema_match is None:
        raise InputError.single(str(path), 1, "not an IFC file: no FILE_SCHEMA in its header")
    schema = schema_match.group(1).decode().upper()
    release = parsed_release(schema)
    if release is None:
        line = data.count(b"\n", 0, schema_match.start()) + 1
        raise InputError.single(
            str(path), line, f"schema {schema} is not read; IFC2X3, IFC4 and IFC4X3 files are"
        )
    try:
        text, exact = data.decode("utf-8"), True
    except UnicodeDecodeError:
        text, exact = data.decode("utf-8", errors="replace"), False
    if release != schema:  # the name in the header, as the parser knows it
        start, end = schema_match.span(1)
        at = len(data[:start].decode("utf-8", errors="replace"))
        text = text[:at] + release + text[at + end - start:]
    clear_log()
    try:
        model = ifcopenshell.file.from_string(text)
    except Exception as exc:
        raise InputError.single(str(path), None, f"cannot parse the IFC file: {exc}") from None
    problems = parse_problems(str(path), text, data if exact else None)
    if problems:
        raise InputError(problems)
    scale = float(ifcopenshell.util.unit.calculate_unit_scale(model))
    return IfcSource(path, data, model, scale, model.schema)


def check_count(source: IfcSource, ifc_class: str, found: list[Any], limit: int) -> None:
    """Refuse a file holding more than ``limit`` entities of ``ifc_class``."""
    if len(found) > limit:
        raise InputError.single(
            str(source.path),
            None,
            f"the file holds {len(found)} {ifc_class} entities, more than the limit of {limit}",
        )
