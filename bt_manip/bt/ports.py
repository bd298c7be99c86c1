"""Port values: typed literals, blackboard references and their text form.

A port is declared with py_trees' :class:`~py_trees.ports.PortInformation` (type, required,
description, default). In XML (and in Python authoring) a port gets either a literal, converted
to the port type when the tree is loaded, or a blackboard reference: ``{key}``, ``{=}`` (the key
named like the port) or ``{@key}`` (a key of the root blackboard).
"""

from __future__ import annotations

import math
import numbers
import typing
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, cast, get_args, get_origin

from py_trees.ports import PortInformation

from bt_manip.bt.status import NodeStatus


@dataclass(frozen=True)
class InOutPortInformation(PortInformation):
    """A port that is both read and written (BT.CPP's ``BidirectionalPort``)."""


@dataclass(frozen=True)
class Accepts:
    """The values a port takes beyond its type: a range, a set of choices, or both.

    ``low``/``high`` bound a number (inclusive, unless ``low_open``/``high_open``); ``choices``
    lists the only values allowed; ``also`` lists values allowed outside the range (such as a
    ``-1`` meaning "all"). For a list port the rule applies to each item. Numbers of a ``float``
    port must be finite unless ``also`` holds ``math.inf`` (or ``-math.inf``): such a port
    takes that infinity, written ``inf`` or ``infinity`` in any case, with a sign or not, as
    BT.CPP's ``convertFromString<double>`` (``std::stod``) reads them. ``check`` is a further
    test of the whole value for rules a range cannot say: it returns what is wrong, or None;
    ``what`` says in words what ``check`` accepts (for the node reference).
    """

    low: float | None = None
    high: float | None = None
    low_open: bool = False
    high_open: bool = False
    choices: tuple[Any, ...] = ()
    also: tuple[Any, ...] = ()
    check: Callable[[Any], str | None] | None = None
    what: str = ""

    def text(self) -> str:
        """What is allowed, as the end of 'must be ...'."""
        if self.choices:
            return "one of " + ", ".join(format_literal(c) for c in self.choices)
        parts = []
        if self.low is not None and self.high is not None:
            left = "(" if self.low_open else "["
            right = ")" if self.high_open else "]"
            parts.append(f"in {left}{self.low:g}, {self.high:g}{right}")
        elif self.low is not None:
            parts.append(f"{'>' if self.low_open else '>='} {self.low:g}")
        elif self.high is not None:
            parts.append(f"{'<' if self.high_open else '<='} {self.high:g}")
        text = " and ".join(parts) or "any value"
        if self.also:
            text += " or " + " or ".join(format_literal(a) for a in self.also)
        return text

    def allows(self, value: Any) -> bool:
        """Whether a scalar ``value`` passes (values of other kinds are left to the node)."""
        if not isinstance(value, numbers.Real | str) or isinstance(value, bool):
            return True
        if value in self.also:
            return True
        if self.choices:
            return value in self.choices
        if isinstance(value, str):
            return True
        if self.low is not None and (value < self.low or (self.low_open and value == self.low)):
            return False
        # a numbers.Real here; typeshed gives Real no __gt__, hence the cast
        return not (self.high is not None
                    and (cast(float, value) > self.high
                         or (self.high_open and value == self.high)))


NON_NEGATIVE = Accepts(low=0)
POSITIVE = Accepts(low=0, low_open=True)
NON_NEGATIVE_OR_INF = Accepts(low=0, also=(math.inf,))
"""A length or a time that may be unbounded: ``inf`` (or ``infinity``) in XML."""
INFINITY_TEXTS = ("inf", "infinity")
"""How an infinite number is written in a port literal (any case, with a sign or not)."""


@dataclass(frozen=True)
class Port(PortInformation):
    """An input port whose values must also satisfy ``accepts`` (checked at load for literals,
    when read for blackboard values)."""

    accepts: Accepts | None = None


def count_of(*counts: int) -> Accepts:
    """A rule for a list port: it holds one of ``counts`` values (0 for an empty list)."""
    allowed = " or ".join(str(n) for n in counts)

    def check(value: Any) -> str | None:
        if isinstance(value, list | tuple) and len(value) not in counts:
            return f"must hold {allowed} values, got {len(value)}"
        return None

    return Accepts(check=check, what=f"{allowed} values")


def takes_infinity(info: PortInformation) -> bool:
    """Whether the port ``info`` takes an infinite number (its rule's ``also`` holds one)."""
    rule: Accepts | None = getattr(info, "accepts", None)
    return rule is not None and any(
        isinstance(a, float) and math.isinf(a) for a in rule.also
    )


def value_problem(info: PortInformation, value: Any, text: str | None = None) -> str | None:
    """Why ``value`` cannot go through the port ``info``, or None when it can.

    ``text`` is the value as the user wrote it, shown in the message (default: its text form).
    """
    many = isinstance(value, list | tuple)
    numeric = _carries_floats(info.data_type)
    rule: Accepts | None = getattr(info, "accepts", None)
    for item in value if many else [value]:
        if (numeric and isinstance(item, numbers.Real) and not isinstance(item, bool)
                and not math.isfinite(item) and not (takes_infinity(info) and math.isinf(item))):
            shown = text if text is not None else format_literal(value)
            return f"must be a finite number, got {shown}"
        if rule is not None and not rule.allows(item):
            shown = text if text is not None else format_literal(value)
            each = "each value " if many else ""
            return f"{each}must be {rule.text()}, got {shown}"
    if rule is not None and rule.check is not None:
        return rule.check(value)
    return None


def _carries_floats(data_type: Any) -> bool:
    """Whether values of ``data_type`` hold floats (remembered per type: it is asked at
    every read of a port)."""
    try:
        return _CARRIES_FLOATS[data_type]
    except KeyError:
        pass
    except TypeError:  # an unhashable type description
        return _find_floats(data_type)
    found = _find_floats(data_type)
    if len(_CARRIES_FLOATS) < 1024:
        _CARRIES_FLOATS[data_type] = found
    return found


_CARRIES_FLOATS: dict[Any, bool] = {}


def _find_floats(data_type: Any) -> bool:
    if data_type is float:
        return True
    return any(_find_floats(arg) for arg in get_args(data_type))


@dataclass(frozen=True)
class Ref:
    """A port bound to a blackboard entry."""

    key: str


@dataclass(frozen=True)
class Literal:
    """A port bound to a constant, already converted to the port type."""

    value: Any


Binding = Ref | Literal

_BOOL_TEXT = {"true": True, "false": False, "1": True, "0": False}


def parse_reference(text: str) -> str | None:
    """Blackboard key of ``{key}``, ``{=}``-style text (``=`` is returned as is), else None."""
    stripped = text.strip()
    if stripped == "=":
        return "="
    if len(stripped) >= 3 and stripped[0] == "{" and stripped[-1] == "}":
        return stripped[1:-1].strip()
    return None


def convert_literal(text: str, data_type: Any, infinite: bool = False) -> Any:
    """Convert ``text`` to ``data_type``; raises ValueError saying what was expected.

    A number must be finite, unless ``infinite`` (the port :func:`takes_infinity`) and the text
    is an infinity spelled out (:data:`INFINITY_TEXTS`): a number too large for a double
    (``1e999``) is refused as ``std::stod`` refuses it, and ``nan`` always.
    """
    if data_type is str or data_type is object or data_type is typing.Any:
        return text
    s = text.strip()
    if data_type is bool:
        low = s.lower()
        if low in _BOOL_TEXT:
            return _BOOL_TEXT[low]
        raise ValueError(f"expected true or false, got '{text}'")
    if data_type is int:
        try:
            return int(s, 0) if s.lower().startswith(("0x", "-0x")) else int(s)
        except ValueError:
            raise ValueError(f"expected an integer, got '{text}'") from None
    if data_type is float:
        try:
            number = float(s)
        except ValueError:
            raise ValueError(f"expected a number, got '{text}'") from None
        if not math.isfinite(number) and not (
            infinite and s.lstrip("+-").lower() in INFINITY_TEXTS
        ):
            raise ValueError(f"expected a finite number, got '{text}'")
        return number
    if data_type is NodeStatus:
        return NodeStatus.parse(s)
    origin = get_origin(data_type)
    if origin is list:
        (item_type,) = get_args(data_type) or (str,)
        if s == "":
            return []
        return [convert_literal(part, item_type, infinite) for part in s.split(";")]
    if origin is typing.Union or str(origin) == "<class 'types.UnionType'>":
        errors = []
        for option in get_args(data_type):
            try:
                return convert_literal(text, option, infinite)
            except ValueError as e:
                errors.append(str(e))
        raise ValueError("; ".join(errors))
    from_string = getattr(data_type, "from_string", None)
    if callable(from_string):
        return from_string(s)
    name = getattr(data_type, "__name__", str(data_type))
    raise ValueError(f"a {name} cannot be written as text; use a blackboard reference {{key}}")


def format_literal(value: Any) -> str:
    """Text form of a literal, as it would appear in XML."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, NodeStatus):
        return value.value
    if isinstance(value, (list, tuple)):
        return ";".join(format_literal(v) for v in value)
    return str(value)


def type_name(data_type: Any) -> str:
    """BT.CPP-style type name for a TreeNodesModel."""
    names = {int: "int", float: "double", bool: "bool", str: "std::string",
             NodeStatus: "BT::NodeStatus", object: "BT::AnyTypeAllowed"}
    if data_type in names:
        return names[data_type]
    origin = get_origin(data_type)
    if origin is list:
        (item,) = get_args(data_type) or (str,)
        return f"std::vector<{type_name(item)}>"
    return getattr(data_type, "__name__", str(data_type))


def type_from_name(name: str | None) -> Any:
    """Python type for a TreeNodesModel type name (unknown names give ``object``)."""
    if not name:
        return object
    table = {"int": int, "unsigned": int, "unsigned int": int, "int64_t": int, "uint64_t": int,
             "long": int, "short": int, "unsigned short": int, "int8_t": int, "uint8_t": int,
             "int16_t": int, "uint16_t": int, "int32_t": int, "uint32_t": int, "size_t": int,
             "std::chrono::milliseconds": int, "double": float, "float": float, "bool": bool,
             "std::string": str,
             "string": str, "BT::NodeStatus": NodeStatus, "NodeStatus": NodeStatus,
             "std::vector<double>": list[float], "std::vector<int>": list[int],
             "std::vector<std::string>": list[str]}
    return table.get(name.strip(), object)


def direction_of(info: PortInformation, is_output: bool) -> str:
    if isinstance(info, InOutPortInformation):
        return "inout"
    return "output" if is_output else "input"
