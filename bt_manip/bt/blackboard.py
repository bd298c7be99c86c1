"""Blackboards with BehaviorTree.CPP scoping.

Every tree (the main tree and each SubTree instance) has its own :class:`Blackboard`. A SubTree's
blackboard sees its parent's entries only through explicit remapping (``port="{parent_key}"``)
or, with ``_autoremap``, through every key that does not start with ``_``. A key written as
``@key`` always addresses the root blackboard. There is no global state: each loaded tree owns
its blackboards.

Entries are typed as in BehaviorTree.CPP: a port bound to ``{key}`` declares the entry with the
port's type when the tree is built (:meth:`Blackboard.declare`; the entry exists but has no
value yet), and an entry first written without a declaration takes the type of that value.
Text written into an entry of another type (``SetBlackboard value="5"`` over an int) is
converted to that type, or raises :class:`EntryTypeError`. Every write bumps the entry's update
counter (:meth:`Blackboard.sequence_id`), which WasEntryUpdated and its decorators watch.
"""

from __future__ import annotations

import json
import math
import re
import typing
from collections.abc import Callable, Iterator
from typing import Any

from bt_manip.bt.ports import convert_literal, type_name

UNTYPED = (object, typing.Any, None)
SCALARS = frozenset({"int", "unsigned int", "double", "bool", "std::string"})


class EntryTypeError(ValueError):
    """A value cannot be stored in an entry of another type."""


class Blackboard:
    """A key/value store with an optional parent, remapping table and auto-remapping."""

    def __init__(
        self,
        parent: Blackboard | None = None,
        remap: dict[str, str] | None = None,
        autoremap: bool = False,
    ) -> None:
        self.parent = parent
        self.remap: dict[str, str] = dict(remap or {})
        self.autoremap = autoremap
        self._data: dict[str, Any] = {}
        self._types: dict[str, Any] = {}  # declared by a port, or the type of the first value
        self._strong: dict[str, str] = {}  # BT.CPP type name of the strongly typed entries
        self._sequence: dict[str, int] = {}  # how many times each entry was written

    @classmethod
    def from_dict(cls, values: dict[str, Any] | None, typed: bool = True) -> Blackboard:
        """A root blackboard holding ``values``. ``typed`` entries are strongly typed by their
        values (as BT.CPP's typed ``set``); otherwise they are created as a script creates
        them, so that ports of any number type can read them (``--bb`` values)."""
        bb = cls()
        write = bb.set if typed else bb.assign
        for key, value in (values or {}).items():
            write(key, value)
        return bb

    def root(self) -> Blackboard:
        bb = self
        while bb.parent is not None:
            bb = bb.parent
        return bb

    def _owner(self, key: str) -> tuple[Blackboard, str]:
        """Return the blackboard that stores ``key`` and the key's name there."""
        bb = self
        while True:
            if key.startswith("@"):
                return bb.root(), key[1:]
            parent = bb.parent
            if key in bb._data or key in bb._types or parent is None:
                return bb, key
            if key in bb.remap:
                key = bb.remap[key]
                bb = parent
                continue
            if bb.autoremap and not key.startswith("_"):
                bb = parent
                continue
            return bb, key

    def exists(self, key: str) -> bool:
        """Whether the entry exists (declared by a port, or written), with a value or not."""
        bb, name = self._owner(key)
        return name in bb._data or name in bb._types

    def has_value(self, key: str) -> bool:
        bb, name = self._owner(key)
        return name in bb._data

    def get(self, key: str) -> Any:
        """Value of ``key``; raises KeyError when the entry does not exist or has no value."""
        bb, name = self._owner(key)
        return bb._data[name]

    def get_or(self, key: str, default: Any = None) -> Any:
        bb, name = self._owner(key)
        return bb._data.get(name, default)

    def entry_type(self, key: str) -> Any:
        """The entry's type (declared by a port, or of its first value); None if untyped."""
        bb, name = self._owner(key)
        return bb._types.get(name)

    def declare(self, key: str, data_type: Any, cpp_type: str | None = None) -> None:
        """Create the entry (without a value) for a port bound to it, with the port's type.

        An entry that already has a type keeps it; an untyped port creates an untyped entry,
        which takes the type of the first value written. As BT.CPP refuses to build a tree in
        which two ports give one entry different types, a port whose scalar type (int,
        unsigned int, double, bool, string) differs from the scalar type of an existing
        strongly typed entry (other than a string) raises :class:`EntryTypeError`.
        """
        bb, name = self._owner(key)
        untyped = data_type in UNTYPED
        port_type = None if untyped else (cpp_type or type_name(data_type))
        previous = bb._strong.get(name)
        if (previous is not None and port_type is not None and previous != port_type
                and previous in SCALARS and port_type in SCALARS
                and previous != "std::string"):
            raise EntryTypeError(
                f"entry [{name}] was created with type [{previous}] and this port uses type "
                f"[{port_type}]; BT.CPP refuses such a tree: use one type for the entry")
        if name in bb._data or name in bb._types:
            if bb._types.get(name) is None and not untyped:
                bb._types[name] = data_type
            return
        bb._types[name] = None if untyped else data_type
        if port_type is not None:
            bb._strong[name] = port_type

    def strong_type(self, key: str) -> str | None:
        """BT.CPP type name of a strongly typed entry (created by a typed port or a typed
        write, not by a script); None otherwise."""
        bb, name = self._owner(key)
        return bb._strong.get(name)

    def set(self, key: str, value: Any) -> None:
        """Write ``key``; text written into an entry of another type is converted to it.

        A new entry is strongly typed by the value (as BT.CPP's typed ``Blackboard::set``)."""
        self._write(key, value, True)

    def set_own(self, key: str, value: Any) -> None:
        """Write an entry of this blackboard itself, as :meth:`set` does but without following
        remapping (a SubTree's literal port with ``_autoremap``, as BT.CPP sets it)."""
        self._store(key, value, True)

    def assign(self, key: str, value: Any) -> None:
        """Write ``key`` from a script: a new entry is not strongly typed (BT.CPP's scripts
        create their entries untyped; the value they hold still has a type)."""
        self._write(key, value, False)

    def _write(self, key: str, value: Any, strong: bool) -> None:
        bb, name = self._owner(key)
        bb._store(name, value, strong)

    def _store(self, name: str, value: Any, strong: bool) -> None:
        """Write the entry ``name`` of this blackboard itself (see :meth:`_write`)."""
        bb = self
        types = bb._types
        declared = types.get(name)
        if declared is None:
            if value is not None:
                if strong and name not in types and name not in bb._data:
                    bb._strong[name] = type_name(type(value))
                types[name] = type(value)
        elif type(value) is str and declared is not str:
            value = _from_text(name, value, declared)
        bb._data[name] = value
        sequence = bb._sequence
        sequence[name] = sequence.get(name, 0) + 1

    def sequence_id(self, key: str) -> int | None:
        """How many times the entry was written (None when it does not exist)."""
        bb, name = self._owner(key)
        if name not in bb._data and name not in bb._types:
            return None
        return bb._sequence.get(name, 0)

    def unset(self, key: str) -> None:
        """Remove an entry of this blackboard itself.

        As in BT.CPP, the key is not followed through remapping: in a SubTree, unsetting an
        entry shared with the parent does nothing.
        """
        self._data.pop(key, None)
        self._types.pop(key, None)
        self._strong.pop(key, None)
        self._sequence.pop(key, None)

    def keys(self) -> Iterator[str]:
        """Keys stored in this blackboard itself (not those reached through the parent)."""
        return iter(list(self._data))

    def as_dict(self, other: Callable[[Any], Any] = str) -> dict[str, Any]:
        """The entries of this blackboard as a JSON-serialisable dict; a value JSON has no
        type for (not a number, text, list, dict, array or enum) is ``other(value)``, its text
        by default."""
        return {key: _jsonable(value, other) for key, value in sorted(self._data.items())}

    def __repr__(self) -> str:
        return f"Blackboard({self._data!r})"


_INT_PREFIX = re.compile(r"-?\d+")
_REAL_PREFIX = re.compile(
    r"\s*[+-]?(?:(0[xX][0-9a-fA-F]*\.?[0-9a-fA-F]*(?:[pP][+-]?\d+)?)"
    r"|((?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?)|(inf(?:inity)?|nan))", re.IGNORECASE)


def bb_value(text: str) -> Any:
    """A blackboard entry given as text (``--bb KEY=VALUE``, a swept ``bb:KEY=...``):
    ``1`` -> 1, ``2.5`` -> 2.5, ``true`` -> True, ``"a b"`` -> 'a b'; anything that is
    not a JSON number, boolean or string (``abc``, ``[1]``, ``null``, ``NaN``) stays the text."""
    try:
        value = json.loads(text)
    except ValueError:
        return text
    if isinstance(value, float) and not math.isfinite(value):
        return text  # json reads NaN and Infinity; keep them as text
    if isinstance(value, bool | int | float | str):
        return value
    return text


def number_from_text(text: str, data_type: type) -> int | float:
    """BT.CPP's text to int (``std::from_chars``) or double (``std::stod``): the number at the
    start of the text, the rest ignored (``"2.5"`` is 2 for an int); ValueError if none."""
    if data_type is int:
        match = _INT_PREFIX.match(text)
        if match is None:
            raise ValueError(f"expected an integer, got '{text}'")
        return int(match.group(0))
    match = _REAL_PREFIX.match(text)
    if match is None:
        raise ValueError(f"expected a number, got '{text}'")
    number = match.group(0).strip()
    if match.group(1):
        sign = -1.0 if number.startswith("-") else 1.0
        digits = number.lstrip("+-")
        return sign * float.fromhex(digits if len(digits) > 2 else "0x0")
    return float(number)


def _from_text(name: str, text: str, data_type: Any) -> Any:
    try:
        if data_type is int or data_type is float:
            return number_from_text(text, data_type)
        return convert_literal(text, data_type)
    except ValueError as e:
        raise EntryTypeError(
            f"cannot convert '{text}' to the type of entry [{name}] "
            f"({type_name(data_type)}): {e}") from None


def _jsonable(value: Any, other: Callable[[Any], Any] = str) -> Any:
    if value is None or isinstance(value, (bool, int, str)):
        return value
    if isinstance(value, float):
        return value if math.isfinite(value) else str(value)
    if isinstance(value, dict):
        return {str(k): _jsonable(v, other) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_jsonable(v, other) for v in value]
    tolist = getattr(value, "tolist", None)
    if callable(tolist):
        return _jsonable(tolist(), other)
    if hasattr(value, "value") and hasattr(value, "name"):  # enums
        return str(value.name)
    return other(value)
