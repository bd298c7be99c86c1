"""Construction-time checks of a node's attributes against its class's ports.

A node's attributes (XML text, or Python values given to its constructor) are checked once,
when the node is built: each must name a port (or be a pre/post-condition script such as
``_skipIf``), a port's text is a blackboard reference (``{key}``) or a literal converted to the
port's type, and every required input port must be given. :func:`check_attributes` gives the
result as an :class:`AttributeCheck` (bindings, texts, parsed scripts, and one message per
problem); a node class asks it through ``BtNode.check_attributes``.

A tree repeats the same node with the same text attributes (a subtree used once per object),
so the check of text attributes that holds no script and only immutable literals is kept per
class (:data:`_CHECKS_PER_CLASS` at most) and handed out as a copy.
"""

from __future__ import annotations

import difflib
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from py_trees.ports import PortInformation

from bt_manip.bt.ports import (
    Binding,
    InOutPortInformation,
    Literal,
    Ref,
    convert_literal,
    format_literal,
    parse_reference,
    takes_infinity,
    value_problem,
)
from bt_manip.bt.script import Script, ScriptSyntaxError, parse_script

if TYPE_CHECKING:
    from bt_manip.bt.node import BtNode

PRE_CONDITIONS = ("_failureIf", "_successIf", "_skipIf", "_while")
POST_CONDITIONS = ("_onHalted", "_onFailure", "_onSuccess", "_post")
IGNORED_ATTRIBUTES = ("_description", "_uid", "_fullpath")
"""Some of the attributes that are neither ports nor scripts: as BT.CPP, a node keeps every
attribute whose name starts with ``_`` and is no pre/post-condition (``_collapsed``, written by
tree editors) as a non-port attribute, unchecked and unused."""

IMMUTABLE_TYPES = frozenset({int, float, bool, str, bytes, type(None)})
"""Types whose values ``copy.deepcopy`` gives back as they are."""

_CHECKS_FLAG = "_bt_attribute_checks"
_CHECKS_PER_CLASS = 256
"""The most attribute checks kept per node class (the oldest goes first)."""


class UnwritableText(str):
    """The text of an attribute that XML cannot hold (a Python object, a callable): ``to_xml``
    refuses to write it, naming the node and the attribute, and gives ``reason``."""

    reason: str

    def __new__(cls, value: Any, reason: str) -> UnwritableText:
        text = super().__new__(cls, f"<{type(value).__name__}>")
        text.reason = reason
        return text


@dataclass
class AttributeCheck:
    """Result of checking a node's attributes against its class."""

    bindings: dict[str, Binding] = field(default_factory=dict)
    texts: dict[str, str] = field(default_factory=dict)
    pre: list[tuple[str, Script]] = field(default_factory=list)
    post: dict[str, Script] = field(default_factory=dict)
    errors: list[tuple[str, int | None]] = field(default_factory=list)  # (message, column)

    def copy(self) -> AttributeCheck:
        """A check with its own dicts and lists (the bindings and scripts themselves shared)."""
        return AttributeCheck(
            dict(self.bindings), dict(self.texts), list(self.pre), dict(self.post),
            list(self.errors),
        )

    def shareable(self) -> bool:
        """Whether nodes may share what this check holds: no scripts, no errors, and every
        literal an immutable value (a number, a flag, a text)."""
        return not (self.pre or self.post or self.errors) and all(
            isinstance(b, Ref) or type(b.value) in IMMUTABLE_TYPES for b in self.bindings.values()
        )


def closest(word: str, choices: list[str] | set[str], n: int = 3) -> str:
    """' (did you mean 'a', 'b'?)' or '' when nothing is close."""
    matches = difflib.get_close_matches(word, sorted(choices), n=n, cutoff=0.5)
    if not matches:
        return ""
    return " (did you mean " + ", ".join(f"'{m}'" for m in matches) + "?)"


def parse_condition_scripts(
    attributes: Mapping[str, Any], check: AttributeCheck, where: str
) -> None:
    """Parse the ``_skipIf``... attributes present in ``attributes`` into ``check``."""
    for key in PRE_CONDITIONS + POST_CONDITIONS:
        if key not in attributes:
            continue
        code = str(attributes[key])
        check.texts[key] = code
        try:
            script = parse_script(code)
        except ScriptSyntaxError as e:
            check.errors.append((f"script syntax error in {key} of {where}: {e.message}", e.column))
            continue
        if key in PRE_CONDITIONS:
            check.pre.append((key, script))
        else:
            check.post[key] = script
    check.pre.sort(key=lambda item: PRE_CONDITIONS.index(item[0]))


def check_attributes(cls: type[BtNode], attributes: Mapping[str, Any]) -> AttributeCheck:
    """Check and convert ``attributes`` (XML text or Python values) for node class ``cls``.

    The check of text attributes that holds no script and only immutable literals is kept
    per class (see the module docstring) and handed out as a copy, so each node still has its
    own bindings."""
    key = tuple(attributes.items())
    if not all(type(v) is str for _, v in key):
        return _checked_attributes(cls, attributes)
    memo: dict[tuple[tuple[str, Any], ...], AttributeCheck] | None = cls.__dict__.get(
        _CHECKS_FLAG
    )
    if memo is None:
        memo = {}
        setattr(cls, _CHECKS_FLAG, memo)
    known = memo.get(key)
    if known is not None:
        return known.copy()
    check = _checked_attributes(cls, attributes)
    if check.shareable():
        if len(memo) >= _CHECKS_PER_CLASS:
            memo.pop(next(iter(memo)), None)
        memo[key] = check.copy()
    return check


def _checked_attributes(cls: type[BtNode], attributes: Mapping[str, Any]) -> AttributeCheck:
    """:func:`check_attributes` worked out."""
    check = AttributeCheck()
    where = f"{cls.NODE_ID}"
    parse_condition_scripts(attributes, check, where)
    ports = set(cls.INPUT_PORTS) | set(cls.OUTPUT_PORTS)
    for key, value in attributes.items():
        if key.startswith("_"):  # a script, or not a port (IGNORED_ATTRIBUTES)
            continue
        info = cls.port_info(key)
        if info is None:
            known = ", ".join(sorted(ports)) if ports else "none"
            check.errors.append(
                (f"'{key}' is not a port of {cls.NODE_ID}{closest(key, ports)}; "
                 f"its ports are: {known}", None))
            continue
        _bind_port(cls, key, value, info, check)
    for port, info in cls.INPUT_PORTS.items():
        if port not in attributes and info.required and not info.has_default:
            check.errors.append(
                (f"{cls.NODE_ID} is missing its required port '{port}'"
                 f"{_describe(info)}; add {port}=\"...\"", None))
    return check


def _bind_port(
    cls: type[BtNode], port: str, value: Any, info: PortInformation, check: AttributeCheck
) -> None:
    is_output = port in cls.OUTPUT_PORTS
    if isinstance(value, (Ref, Literal)):
        check.bindings[port] = value
        check.texts[port] = (
            "{" + value.key + "}" if isinstance(value, Ref) else format_literal(value.value))
        return
    if isinstance(value, str):
        key = parse_reference(value)
        if key is not None:
            if key in ("=", ""):
                key = port
            check.bindings[port] = Ref(key)
            check.texts[port] = value
            return
        if is_output and not isinstance(info, InOutPortInformation):
            check.errors.append(
                (f"output port '{port}' of {cls.NODE_ID} must be a blackboard reference "
                 f"like \"{{{port}}}\", got '{value}'", None))
            return
        if port in cls.SCRIPT_PORTS:
            try:
                script = parse_script(value)
            except ScriptSyntaxError as e:
                check.errors.append(
                    (f"script syntax error in {port} of {cls.NODE_ID}: {e.message}", e.column))
                return
            check.bindings[port] = Literal(script)
            check.texts[port] = value
            return
        try:
            converted = convert_literal(value, info.data_type, takes_infinity(info))
        except ValueError as e:
            check.errors.append((f"bad value for port '{port}' of {cls.NODE_ID}: {e}", None))
            return
        problem = value_problem(info, converted, value)
        if problem is not None:
            check.errors.append((f"bad value for port '{port}' of {cls.NODE_ID}: {problem}",
                                 None))
            return
        check.bindings[port] = Literal(converted)
        check.texts[port] = value
        return
    problem = value_problem(info, value)
    if problem is not None:
        check.errors.append((f"bad value for port '{port}' of {cls.NODE_ID}: {problem}", None))
        return
    check.bindings[port] = Literal(value)
    check.texts[port] = format_literal(value)


def _describe(info: PortInformation) -> str:
    return f" ({info.description})" if info.description else ""
