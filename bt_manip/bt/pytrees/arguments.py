"""Constructor arguments of py_trees behaviours as XML attributes, and back.

A py_trees behaviour registered as a bt-manip leaf takes its XML attributes as keyword
arguments of its constructor, converted by the constructor's annotations: numbers,
``true``/``false``, statuses by name (``SUCCESS``), enums by member name, ``null`` for an
optional value, JSON for lists and dicts (``queue='["SUCCESS", "RUNNING"]'``), py_trees'
``ComparisonExpression`` as a JSON object (``{"variable": "a", "value": 3, "operator": "ge"}``)
and a function of the ``operator`` module by its name (``operator="xor"``). Each argument is
declared as an input port (:func:`port_info`) in the TreeNodesModel.

An object of a class the program registered as a value type
(``registry.register_value_type(Nested)``) is written in that JSON as its type's name and its
attributes, ``{"$type": "Nested", "state": {"foo": "bar"}}``, and built back only where the
loading program registered that name (:mod:`bt_manip.bt.pytrees.values`).

A value none of these can hold (an object of an unregistered class, a lambda) is kept as
:class:`UnwritableText`: ``to_xml`` refuses to write it rather than write a file that loads
with another meaning.
"""

from __future__ import annotations

import enum
import inspect
import json
import operator
import typing
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, cast, get_args, get_origin

import py_trees
from py_trees.behaviour import Behaviour
from py_trees.common import ComparisonExpression, Status
from py_trees.ports import PortInformation

from bt_manip.bt.attributes import UnwritableText
from bt_manip.bt.ports import convert_literal
from bt_manip.bt.pytrees import values
from bt_manip.bt.pytrees.values import ValueTypeError

_NONE_TEXT = ("", "null", "none")


@dataclass(frozen=True)
class Param:
    """One keyword parameter of a behaviour's constructor."""

    name: str
    annotation: Any
    required: bool
    default: Any = None


def _hints(cls: type[Any]) -> dict[str, Any]:
    try:
        return typing.get_type_hints(cls.__init__)
    except Exception:  # unresolvable annotations: use them as written
        return dict(getattr(cls.__init__, "__annotations__", {}))


def constructor_params(cls: type[Behaviour]) -> dict[str, Param]:
    """Keyword parameters of ``cls``'s constructor other than ``name`` (and ``*args``)."""
    try:
        signature = inspect.signature(cls.__init__)
    except (TypeError, ValueError):
        return {}
    hints = _hints(cls)
    params: dict[str, Param] = {}
    for index, p in enumerate(signature.parameters.values()):
        if index == 0 or p.name == "name" or p.kind in (p.VAR_POSITIONAL, p.VAR_KEYWORD):
            continue
        if p.name == "behaviour_class_name":  # PortsMixin's own bookkeeping
            continue
        required = p.default is inspect.Parameter.empty
        params[p.name] = Param(p.name, hints.get(p.name, Any), required,
                               None if required else p.default)
    return params


def _is_optional(annotation: Any) -> tuple[bool, list[Any]]:
    origin = get_origin(annotation)
    if origin is typing.Union or str(origin) == "<class 'types.UnionType'>":
        args = list(get_args(annotation))
        return type(None) in args, [a for a in args if a is not type(None)]
    return False, [annotation]


def convert_param(text: str, annotation: Any) -> Any:
    """Convert an XML attribute to a constructor argument of type ``annotation``.

    Raises ValueError saying what was expected."""
    optional, options = _is_optional(annotation)
    if optional and text.strip().lower() in _NONE_TEXT:
        return None
    errors = []
    for option in options:
        try:
            return _convert_one(text, option)
        except ValueTypeError:  # a registered value's JSON: no other reading makes sense
            raise
        except ValueError as e:
            errors.append(str(e))
    raise ValueError("; ".join(dict.fromkeys(errors)))


def _convert_one(text: str, annotation: Any) -> Any:
    if annotation is Status:
        return _status(text)
    if isinstance(annotation, type) and issubclass(annotation, enum.Enum):
        return _enum(text, annotation)
    origin = get_origin(annotation)
    if origin in (list, tuple, dict, set) or annotation in (list, tuple, dict, set):
        try:
            value = values.loads(text)
        except json.JSONDecodeError as e:
            raise ValueError(f"expected JSON ({e.msg} at column {e.colno}), got '{text}'") from None
        return _from_json(value, annotation)
    if annotation is ComparisonExpression:
        try:
            return _comparison(values.loads(text))
        except json.JSONDecodeError as e:
            raise ValueError(f"expected JSON ({e.msg} at column {e.colno}), got '{text}'") from None
    if origin is Callable or annotation is Callable:
        return _operator(text)
    if annotation in (int, float, bool, str):
        return convert_literal(text, annotation)
    if annotation is Any or annotation is object or annotation is inspect.Parameter.empty:
        try:
            return values.loads(text)
        except json.JSONDecodeError:
            return text
    name = getattr(annotation, "__name__", str(annotation))
    raise ValueError(f"a {name} cannot be written in XML; build this node in Python")


def _operator(name: Any) -> Callable[..., Any]:
    function = getattr(operator, str(name).strip(), None)
    if not callable(function) or str(name).startswith("_"):
        raise ValueError(f"expected the name of a function of the operator module (eq, ge, "
                         f"xor...), got '{name}'")
    return cast(Callable[..., Any], function)


def _comparison(value: Any) -> ComparisonExpression:
    if not isinstance(value, dict) or set(value) != {"variable", "value", "operator"}:
        raise ValueError('expected a JSON object {"variable": ..., "value": ..., "operator": '
                         f'...}}, got {json.dumps(value)}')
    return ComparisonExpression(str(value["variable"]), value["value"],
                                _operator(value["operator"]))


def _status(text: Any) -> Status:
    word = str(text).strip().upper().removeprefix("STATUS.")
    try:
        return Status[word]
    except KeyError:
        raise ValueError(
            f"expected one of SUCCESS, FAILURE, RUNNING, INVALID, got '{text}'") from None


def _enum(text: str, annotation: type[enum.Enum]) -> enum.Enum:
    word = text.strip().split(".")[-1]
    for member in annotation:
        if member.name.lower() == word.lower():
            return member
    names = ", ".join(m.name for m in annotation)
    raise ValueError(f"expected one of {names}, got '{text}'")


def _from_json(value: Any, annotation: Any) -> Any:
    origin = get_origin(annotation) or annotation
    args = get_args(annotation)
    if origin in (list, tuple, set):
        if not isinstance(value, list):
            raise ValueError(f"expected a JSON list, got {json.dumps(value)}")
        item = args[0] if args else Any
        items = [_json_item(v, item) for v in value]
        return origin(items) if origin is not list else items
    if origin is dict:
        if not isinstance(value, dict):
            raise ValueError(f"expected a JSON object, got {json.dumps(value)}")
        return value
    return value


def _json_item(value: Any, annotation: Any) -> Any:
    optional, options = _is_optional(annotation)
    if value is None and optional:
        return None
    option = options[0] if options else Any
    if option is ComparisonExpression:
        return _comparison(value)
    if option is Status or (isinstance(option, type) and issubclass(option, enum.Enum)):
        return _status(value) if option is Status else _enum(str(value), option)
    if option is float and isinstance(value, int) and not isinstance(value, bool):
        return float(value)
    if option in (int, float, bool, str) and not isinstance(value, option):
        raise ValueError(f"expected a list of {option.__name__}, got {json.dumps(value)}")
    return value


def format_param(value: Any) -> str:
    """XML text of a constructor argument (read back by :func:`convert_param`), or an
    :class:`UnwritableText` saying why XML cannot hold it."""
    if value is None:
        return "null"
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, enum.Enum):
        return value.name
    try:
        if isinstance(value, (list, tuple, set, dict, ComparisonExpression)):
            return json.dumps(_jsonable(value))
        if isinstance(value, (int, float, str)):
            return str(value)
        if values.is_value(value):
            return json.dumps(values.encode_value(value))
        if callable(value):
            return _operator_name(value)
    except (TypeError, ValueError) as e:
        return UnwritableText(value, str(e))
    kind = type(value).__name__
    return UnwritableText(value, f"a {kind} cannot be written in XML; to write it as its "
                          f"attributes, register its class: registry.register_value_type({kind})")


def _operator_name(function: Any) -> str:
    name = getattr(function, "__name__", "")
    if getattr(operator, name, None) is not function:
        raise ValueError(f"{getattr(function, '__qualname__', repr(function))} is not a "
                         "function of the operator module")
    return str(name)


def _jsonable(value: Any) -> Any:
    if isinstance(value, enum.Enum):
        return value.name
    if isinstance(value, ComparisonExpression):
        generator = value.value_generator
        if "ComparisonExpression.__init__" not in getattr(generator, "__qualname__", ""):
            raise ValueError("a ComparisonExpression whose value is a callable cannot be "
                             "written in XML")
        return {"variable": value.variable, "value": _jsonable(generator()),
                "operator": _operator_name(value.operator)}
    if isinstance(value, dict):
        return {values.escape_key(str(k)): _jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple, set)):
        return [_jsonable(v) for v in value]
    if isinstance(value, (str, int, float, bool, type(None))):
        return value
    if values.is_value(value):
        return values.encode_value(value)
    raise ValueError(f"a {type(value).__name__} cannot be written in XML")


# Where py_trees' own behaviours keep their constructor arguments (for saving a wrapped
# instance as XML); other classes are read from an attribute named like the parameter, and a
# ``remap_to`` argument that no attribute keeps from the remappings of the behaviour's
# blackboard clients (py_trees' ``register_key(key, remap_to=...)``).
_STORED_AS = {"n": ("every_n", "period")}


def recover_arguments(behaviour: Behaviour, params: dict[str, Param]) -> dict[str, Any]:
    """Constructor arguments of an existing behaviour, as far as its attributes tell."""
    found: dict[str, Any] = {}
    generator = vars(behaviour).get("variable_value_generator")
    if "variable_value" in params and callable(generator) and \
            "SetBlackboardVariable.__init__" in getattr(generator, "__qualname__", ""):
        found["variable_value"] = generator()  # py_trees' wrapper around a plain value
    results = vars(behaviour).get("blackboard_results")  # CheckBlackboardVariableValues
    if "namespace" in params and isinstance(results, py_trees.blackboard.Client):
        found["namespace"] = results.namespace
    if "remap_to" in params and not any(a in vars(behaviour) for a in ("remap_to", "_remap_to")):
        remapped = _client_remappings(behaviour)  # register_key(..., remap_to=...) of its own
        if remapped:
            found["remap_to"] = remapped
    for name in params:
        if name in found:
            continue
        for attribute in (name, "_" + name, *_STORED_AS.get(name, ())):
            if attribute in vars(behaviour):
                found[name] = vars(behaviour)[attribute]
                break
    return found


def _client_remappings(behaviour: Behaviour) -> dict[str, str]:
    """The keys that ``behaviour``'s blackboard clients registered remapped elsewhere
    (``register_key(key, remap_to=...)``), as ``{key: remapped key}``."""
    remapped: dict[str, str] = {}
    for client in behaviour.blackboards:
        mapping: dict[str, str] = object.__getattribute__(client, "remappings")
        remapped.update({k: v for k, v in mapping.items() if k != v})
    return remapped


def port_info(p: Param) -> PortInformation:
    """The input port declaring constructor argument ``p`` in the TreeNodesModel."""
    description = "constructor argument"
    default = p.default
    data_type = p.annotation  # as the model shows it; conversion uses the annotation itself
    optional, options = _is_optional(data_type)
    if get_origin(data_type) is typing.Union or optional:
        data_type = options[0] if len(options) == 1 else object
    try:
        return PortInformation(data_type, required=p.required, description=description,
                               default_value=default)
    except TypeError:
        return PortInformation(object, required=p.required, description=description,
                               default_value=default)
