"""Objects of registered value types in the JSON of constructor arguments, and back.

A py_trees behaviour's constructor argument can be an object of a class of the user's own
(py_trees' blackboard demo sets ``SetBlackboardVariable(variable_value=Nested())``). XML is
untrusted input, so it never names a class to build: the program registers the classes it
trusts (``registry.register_value_type(Nested)``, :mod:`bt_manip.bt.registry`), and in the
JSON of a constructor argument an object of such a class is written as::

    {"$type": "Nested", "state": {"foo": "bar"}}

its registered name and its attributes (``vars(obj)``). Loading builds one only when the name
is registered: without calling ``__init__`` (as ``pickle`` does), its attributes set from
``state``. An unregistered name, a malformed ``$type`` object, or attributes JSON cannot hold
(a set, a tuple, an object of an unregistered class...) are refused with a message naming the
value type.

User data keeps its meaning: a dict whose key is ``$type`` is written with the key ``$$type``
(any key of ``$`` signs then ``type`` gets one more ``$``) and read back with one ``$`` less,
so only an object that ``to_xml`` wrote as a value, or that a user wrote on purpose, holds the
key ``$type``.
"""

from __future__ import annotations

import json
import re
from typing import Any

from bt_manip.bt.registry import registry

TYPE_KEY = "$type"
STATE_KEY = "state"
MAX_DEPTH = 100
"""The deepest nesting of JSON lists and objects in a constructor argument, read or written (a
value counts two: its ``$type`` object and its ``state``)."""

_RESERVED = re.compile(r"\$+type")
_JSON_SCALARS = (str, int, float, bool, type(None))


class ValueTypeError(ValueError):
    """A ``$type`` object that cannot be built: its name is not a registered value type, or
    the object is malformed. No other reading of the text is tried."""


def escape_key(key: str) -> str:
    """The key as written: ``$type``, ``$$type``... get one more ``$``."""
    return "$" + key if _RESERVED.fullmatch(key) else key


def unescape_key(key: str) -> str:
    """The key as the user wrote it: ``$$type`` is ``$type`` (``$type`` itself marks a value)."""
    return key[1:] if key.startswith("$$") and _RESERVED.fullmatch(key) else key


def is_value(value: Any) -> bool:
    """Whether ``value`` is an object of a registered value type (exactly that class)."""
    return registry.value_type_name(type(value)) is not None


def encode_value(value: Any, depth: int = 0) -> dict[str, Any]:
    """The JSON object for ``value``, an object of a registered value type.

    Raises ValueError naming the attribute JSON cannot hold."""
    name = registry.value_type_name(type(value))
    if name is None:
        raise ValueError(f"a {type(value).__name__} is not a registered value type")
    state: dict[str, Any] = {}
    for key, item in vars(value).items():
        where = f"the {name}'s attribute '{key}'"
        state[escape_key(str(key))] = _state_item(item, where, depth + 2)
    return {TYPE_KEY: name, STATE_KEY: state}


def _state_item(value: Any, where: str, depth: int) -> Any:
    if depth >= MAX_DEPTH:
        raise ValueError(f"{where} is nested more than {MAX_DEPTH} levels deep")
    if type(value) in _JSON_SCALARS:
        return value
    if type(value) is list:
        return [_state_item(v, f"{where}[{i}]", depth + 1) for i, v in enumerate(value)]
    if type(value) is dict:
        out = {}
        for key, item in value.items():
            if type(key) is not str:
                raise ValueError(f"{where} has the key {key!r}, a {type(key).__name__}; "
                                 "JSON keys are text")
            out[escape_key(key)] = _state_item(item, f"{where}[{key!r}]", depth + 1)
        return out
    if is_value(value):
        return encode_value(value, depth)
    raise ValueError(f"{where} is a {type(value).__name__}, which would not load back as one: "
                     "a value type's attributes must be null, true/false, numbers, text, lists, "
                     "dicts with text keys or objects of registered value types")


def loads(text: str) -> Any:
    """``json.loads(text)`` with ``$type`` objects built and escaped keys restored.

    Raises json.JSONDecodeError for text that is not JSON, ValueTypeError for a ``$type``
    object that cannot be built or JSON nested more than :data:`MAX_DEPTH` levels deep."""
    too_deep = ValueTypeError(f"the JSON is nested more than {MAX_DEPTH} levels deep")
    try:
        value = json.loads(text, object_hook=_object_hook)
    except RecursionError:
        raise too_deep from None
    if _depth(value) > MAX_DEPTH:
        raise too_deep
    return value


def _depth(value: Any) -> int:
    """How many lists and dicts are nested in ``value`` (a value's attributes counted as a
    ``$type`` object holding its ``state``); no recursion."""
    deepest = 0
    pending = [(value, 0)]
    while pending:
        item, depth = pending.pop()
        if isinstance(item, list):
            children, depth = item, depth + 1
        elif isinstance(item, dict):
            children, depth = list(item.values()), depth + 1
        elif is_value(item):
            children, depth = list(vars(item).values()), depth + 2
        else:
            continue
        deepest = max(deepest, depth)
        if depth > MAX_DEPTH:
            break
        pending.extend((child, depth) for child in children)
    return deepest


def _object_hook(obj: dict[str, Any]) -> Any:
    if TYPE_KEY in obj:
        return _build(obj)
    if any(_RESERVED.fullmatch(key) for key in obj):
        return {unescape_key(key): value for key, value in obj.items()}
    return obj


def _short(value: Any, limit: int = 60) -> str:
    text = json.dumps(value, default=repr)
    return text if len(text) <= limit else text[:limit] + "..."


def _build(obj: dict[str, Any]) -> Any:
    if set(obj) != {TYPE_KEY, STATE_KEY}:
        raise ValueTypeError(
            f'an object with the key "{TYPE_KEY}" is a value of a registered type, '
            f'{{"{TYPE_KEY}": NAME, "{STATE_KEY}": {{...}}}}, got the keys '
            f'{_short(sorted(obj))}; for a key named "{TYPE_KEY}" write '
            f'"${TYPE_KEY}"')
    name, state = obj[TYPE_KEY], obj[STATE_KEY]
    if not isinstance(name, str):
        raise ValueTypeError(f'"{TYPE_KEY}" names a value type, got {_short(name)}')
    cls: Any = registry.value_type(name)
    if cls is None:
        names = sorted(registry.value_types())
        known = ", ".join(names[:10]) + (f" and {len(names) - 10} more" if names[10:] else "")
        shown = json.dumps(name)[1:-1]  # the file's text, escaped and cut short
        shown = shown if len(shown) <= 60 else shown[:60] + "..."
        raise ValueTypeError(
            f"value type '{shown}' is not registered (registered: {known or 'none'}); the "
            "program that loads this tree must trust its class first: "
            f"registry.register_value_type({shown}) (for bt-manip's commands, in a module "
            "given with --import)")
    if not isinstance(state, dict):
        raise ValueTypeError(f'the "{STATE_KEY}" of a {name} is a JSON object of its '
                             f"attributes, got {_short(state)}")
    try:
        made = cls.__new__(cls)
        vars(made).update(state)
    except Exception as e:  # a class that cannot be made this way
        raise ValueTypeError(f"cannot make a {name} from its attributes: "
                             f"{type(e).__name__}: {e}") from None
    return made
