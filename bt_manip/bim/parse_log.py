"""The IFC parser's complaints, as problems of the file at their lines.

ifcopenshell's STEP parser does not raise on a malformed entity: it logs an error (``token x12
at offset 709992 invalid instance name``, ``Entity with name 'IFCWAL' not found in schema``)
and goes on without the entity, so a file with one broken line would be read as a building
short of that element, or with references to it left empty. :func:`parse_problems` reads the
messages the parse left in ifcopenshell's log (text or JSON lines) and turns each error into a
problem of the file, at the line of the offset the message gives. Reading the log costs
microseconds: the file is parsed once, whether it is sound or not.

Warnings (an entity with too many or too few attributes, say) are not problems: the entity is
read, and what bt-manip needs of it is checked where it is used.
"""

from __future__ import annotations

import json
import re
from typing import Any

from bt_manip.errors import Problem

MAX_PARSE_PROBLEMS = 20
"""Parser errors reported at most (the count of the others is given)."""

_OFFSET = re.compile(r"\s*at offset (\d+)\s*")
_TEXT_LINE = re.compile(r"^\[(\w+)\](?: \[[^\]]*\])*\s*(.*)$")


def clear_log() -> None:
    """Drop what ifcopenshell has logged so far (reading its log empties it)."""
    import ifcopenshell.ifcopenshell_wrapper as wrapper

    wrapper.get_log()


def parse_problems(path: str, text: str, encoded: bytes | None = None) -> list[Problem]:
    """The errors ifcopenshell logged since :func:`clear_log`, as problems of ``path``,
    whose text (as parsed) is ``text``: at most :data:`MAX_PARSE_PROBLEMS`, each at its line
    and column when the message gives an offset. ``encoded``, when given, is ``text`` in
    UTF-8 (the file's bytes, when they decoded without a replacement): the parser's offsets
    count its bytes."""
    import ifcopenshell.ifcopenshell_wrapper as wrapper

    errors = [message for level, message in _entries(str(wrapper.get_log()))
              if level in ("error", "critical", "fatal")]
    if not errors:
        return []
    out: list[Problem] = []
    for message in errors[:MAX_PARSE_PROBLEMS]:
        line = column = None
        found = _OFFSET.search(message)
        if found is not None:
            if encoded is None:
                encoded = text.encode("utf-8", errors="replace")  # the parser's offsets
            offset = min(int(found.group(1)), len(encoded))
            start = encoded.rfind(b"\n", 0, offset) + 1
            line = encoded.count(b"\n", 0, offset) + 1
            column = offset - start + 1
            message = (message[:found.start()] + " " + message[found.end():]).strip()
        out.append(Problem(path, line, f"the IFC file cannot be parsed here: {message}",
                           column))
    if len(errors) > MAX_PARSE_PROBLEMS:
        out.append(Problem(path, None, f"{len(errors) - MAX_PARSE_PROBLEMS} more parse "
                                       "errors not listed"))
    return out


def _entries(log: str) -> list[tuple[str, str]]:
    """(level, message) of each line of ifcopenshell's log, in either of its formats."""
    out: list[tuple[str, str]] = []
    for raw in log.splitlines():
        raw = raw.strip()
        if not raw:
            continue
        if raw.startswith("{"):
            try:
                entry: Any = json.loads(raw)
            except ValueError:
                continue
            if isinstance(entry, dict):
                out.append((str(entry.get("level", "")).lower(), str(entry.get("message", ""))))
            continue
        match = _TEXT_LINE.match(raw)
        if match is not None:
            out.append((match.group(1).lower(), match.group(2)))
    return out
