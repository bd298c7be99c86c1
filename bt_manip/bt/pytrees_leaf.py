"""py_trees behaviours as bt-manip leaves.

Any ``py_trees.behaviour.Behaviour`` subclass can be registered (``registry.register(Hello)``)
or put in a tree built in Python (a plain behaviour given as a child of a bt-manip node is
wrapped automatically). The wrapper keeps py_trees' contract for the behaviour it holds:

- ticked while not RUNNING, the behaviour's ``initialise()`` runs first (every time, also
  when a parent ticks it again after it finished), then ``update()``;
- ``update()`` returning SUCCESS or FAILURE runs ``terminate(status)``; a parent halting it
  while RUNNING runs ``terminate(INVALID)`` once; ``setup(**kwargs)`` and ``shutdown()`` are
  forwarded by py_trees' ``BehaviourTree.setup()``/``shutdown()``;
- its ``status`` and ``feedback_message`` are the wrapper's.

XML attributes go to the behaviour's constructor as keyword arguments (``name`` as usual),
converted by the constructor's annotations: numbers, ``true``/``false``, statuses by name
(``SUCCESS``), enums by member name, ``null`` for an optional value, JSON for lists and dicts
(``queue='["SUCCESS", "RUNNING"]'``). They are declared as input ports in the TreeNodesModel;
a constructor argument is fixed when the tree is built, so it cannot be a blackboard reference.

A behaviour with py_trees ports (``BehaviourWithPorts`` / ``PortsMixin`` with ``INPUT_PORTS``
and ``OUTPUT_PORTS``) gets them as bt-manip ports: ``port="{key}"`` wires the port to a
blackboard entry, other text is a literal converted to the port's type; the behaviour's own
``get_input()``/``_set_output()`` then read and write those.

Blackboard clients of the behaviour (``attach_blackboard_client()``, ports) read and write the
blackboard of the (sub)tree the leaf sits in, while it runs: py_trees' absolute key ``/foo``
and the relative ``foo`` both name entry ``foo`` (``/a/b`` names entry ``a/b``).
"""

from __future__ import annotations

import contextlib
import enum
import inspect
import json
import typing
from collections.abc import Callable, Iterator, MutableMapping
from dataclasses import dataclass
from typing import Any, ClassVar, cast, get_args, get_origin

import py_trees
from py_trees.behaviour import Behaviour
from py_trees.common import Status
from py_trees.ports import PortInformation, PortsMixin

from bt_manip.bt.blackboard import Blackboard
from bt_manip.bt.node import AttributeCheck, LeafNode, TreeRuntimeError
from bt_manip.bt.ports import Literal, Ref, convert_literal
from bt_manip.bt.status import RESULT_OF_PY_TREES, NodeStatus

PORT_PREFIX = "/__bt_manip_port__/"
"""py_trees key of a port that is not wired to an entry (kept by the leaf itself)."""

_NONE_TEXT = ("", "null", "none")
_UNKNOWN = object()  # a constructor argument of a wrapped object that its attributes hide


# ---------------------------------------------------------------------- blackboard bridge


class EntryView(MutableMapping[str, Any]):
    """py_trees' key-value store seen through a bt-manip :class:`Blackboard`.

    ``/foo`` and ``foo`` are entry ``foo``; keys under :data:`PORT_PREFIX` live in ``local``.
    """

    def __init__(self, blackboard: Blackboard, local: dict[str, Any] | None = None) -> None:
        self.blackboard = blackboard
        self.local = local if local is not None else {}

    @staticmethod
    def entry(key: str) -> str:
        return key[1:] if key.startswith("/") else key

    def __getitem__(self, key: str) -> Any:
        if key.startswith(PORT_PREFIX):
            return self.local[key]
        return self.blackboard.get(self.entry(key))

    def __setitem__(self, key: str, value: Any) -> None:
        if key.startswith(PORT_PREFIX):
            self.local[key] = value
        else:
            self.blackboard.set(self.entry(key), value)

    def __delitem__(self, key: str) -> None:
        if key.startswith(PORT_PREFIX):
            del self.local[key]
            return
        name = self.entry(key)
        if not self.blackboard.has_value(name):
            raise KeyError(key)
        self.blackboard.unset(name)

    def __contains__(self, key: object) -> bool:
        if not isinstance(key, str):
            return False
        if key.startswith(PORT_PREFIX):
            return key in self.local
        return self.blackboard.has_value(self.entry(key))

    def __iter__(self) -> Iterator[str]:
        names = self.blackboard.keys()  # a bt-manip Blackboard, not a dict
        yield from ("/" + k for k in names)
        yield from self.local

    def __len__(self) -> int:
        return len(list(self.blackboard.keys())) + len(self.local)


@contextlib.contextmanager
def py_trees_storage(view: MutableMapping[str, Any]) -> Iterator[None]:
    """Make py_trees' blackboard clients use ``view`` while the block runs."""
    storage = py_trees.blackboard.Blackboard
    saved = storage.storage
    storage.storage = view  # type: ignore[assignment]  # py_trees types it dict; a mapping does
    try:
        yield
    finally:
        storage.storage = saved


@contextlib.contextmanager
def raised_as_tree_error(node: Any) -> Iterator[None]:
    """An exception raised by py_trees code (a behaviour's ``update()``...) becomes a
    :class:`TreeRuntimeError` naming the node, so a run ends with an error, not a traceback."""
    try:
        yield
    except TreeRuntimeError:
        raise
    except Exception as e:
        raise TreeRuntimeError(f"{node.describe()}: {type(e).__name__}: {e}") from e


# ---------------------------------------------------------------------- constructor arguments


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
            value = json.loads(text)
        except json.JSONDecodeError as e:
            raise ValueError(f"expected JSON ({e.msg} at column {e.colno}), got '{text}'") from None
        return _from_json(value, annotation)
    if annotation in (int, float, bool, str):
        return convert_literal(text, annotation)
    if annotation is Any or annotation is object or annotation is inspect.Parameter.empty:
        try:
            return json.loads(text)
        except json.JSONDecodeError:
            return text
    name = getattr(annotation, "__name__", str(annotation))
    raise ValueError(f"a {name} cannot be written in XML; build this node in Python")


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
    if option is Status or (isinstance(option, type) and issubclass(option, enum.Enum)):
        return _status(value) if option is Status else _enum(str(value), option)
    if option is float and isinstance(value, int) and not isinstance(value, bool):
        return float(value)
    if option in (int, float, bool, str) and not isinstance(value, option):
        raise ValueError(f"expected a list of {option.__name__}, got {json.dumps(value)}")
    return value


def format_param(value: Any) -> str:
    """XML text of a constructor argument (read back by :func:`convert_param`)."""
    if value is None:
        return "null"
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, enum.Enum):
        return value.name
    if isinstance(value, (list, tuple, set, dict)):
        return json.dumps(_jsonable(value))
    return str(value)


def _jsonable(value: Any) -> Any:
    if isinstance(value, enum.Enum):
        return value.name
    if isinstance(value, dict):
        return {str(k): _jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple, set)):
        return [_jsonable(v) for v in value]
    return value


# Where py_trees' own behaviours keep their constructor arguments (for saving a wrapped
# instance as XML); other classes are read from an attribute named like the parameter.
_STORED_AS = {"n": ("every_n", "period")}


def recover_arguments(behaviour: Behaviour, params: dict[str, Param]) -> dict[str, Any]:
    """Constructor arguments of an existing behaviour, as far as its attributes tell."""
    found: dict[str, Any] = {}
    generator = vars(behaviour).get("variable_value_generator")
    if "variable_value" in params and callable(generator) and \
            "SetBlackboardVariable.__init__" in getattr(generator, "__qualname__", ""):
        found["variable_value"] = generator()  # py_trees' wrapper around a plain value
    for name in params:
        if name in found:
            continue
        for attribute in (name, "_" + name, *_STORED_AS.get(name, ())):
            if attribute in vars(behaviour):
                found[name] = vars(behaviour)[attribute]
                break
    return found


# ---------------------------------------------------------------------- the wrapper


class PyTreesLeaf(LeafNode):
    """A leaf running a py_trees behaviour with py_trees' contract (see the module docstring).

    On each tick: RUNNING, SUCCESS or FAILURE as the behaviour's ``update()`` returns; halted
    while RUNNING, the behaviour's ``terminate(INVALID)`` runs once.
    """

    BEHAVIOUR: ClassVar[Callable[..., Behaviour]] = Behaviour  # the class (abstract here)
    PARAMS: ClassVar[dict[str, Param]] = {}

    def __init__(self, name: str | None = None, behaviour: Behaviour | None = None,
                 **attributes: Any) -> None:
        if behaviour is not None:  # arguments it was built with, where its attributes tell
            name = behaviour.name
            given = recover_arguments(behaviour, self.PARAMS)
            unknown = {p: Literal(_UNKNOWN) for p in self.PARAMS if p not in given}
            attributes = {**unknown, **{k: Literal(v) for k, v in given.items()}, **attributes}
        super().__init__(name or self.NODE_ID, **attributes)
        for port, binding in list(self.bindings.items()):
            if isinstance(binding, Literal) and binding.value is _UNKNOWN:
                del self.bindings[port]
                self.attribute_texts.pop(port, None)
        if behaviour is None:
            kwargs = {p: b.value for p, b in self.bindings.items()
                      if p in self.PARAMS and isinstance(b, Literal)}
            try:
                behaviour = self.BEHAVIOUR(name=self.name, **kwargs)
            except Exception as e:  # the constructor refused its arguments
                raise ValueError(f"{self.NODE_ID}: {type(e).__name__}: {e}") from None
        self.behaviour = behaviour
        self.blackboards = behaviour.blackboards
        self._local: dict[str, Any] = {}
        if isinstance(behaviour, PortsMixin):
            self._wire_ports(behaviour)

    @classmethod
    def check_attributes(cls, attributes: typing.Mapping[str, Any]) -> AttributeCheck:
        converted: dict[str, Any] = {}
        errors: list[tuple[str, int | None]] = []
        texts: dict[str, str] = {}
        for key, value in attributes.items():
            param = cls.PARAMS.get(key)
            if param is None:
                converted[key] = value
                continue
            if isinstance(value, Ref) or (isinstance(value, str) and value.strip().startswith("{")
                                          and value.strip().endswith("}")):
                errors.append((f"parameter '{key}' of {cls.NODE_ID} is a constructor argument "
                               "and cannot be a blackboard reference; give its value", None))
                converted[key] = Literal(None)
                continue
            if isinstance(value, Literal):
                value = value.value
            if isinstance(value, str):
                try:
                    converted[key] = Literal(convert_param(value, param.annotation))
                    texts[key] = value
                except ValueError as e:
                    errors.append((f"bad value for parameter '{key}' of {cls.NODE_ID}: {e}",
                                   None))
                    converted[key] = Literal(None)  # reported once, not as missing
                continue
            converted[key] = Literal(value)
            texts[key] = format_param(value)
        check = super().check_attributes(converted)
        check.texts.update(texts)
        check.errors = errors + check.errors
        return check

    def _wire_ports(self, behaviour: PortsMixin) -> None:
        remap: dict[str, str] = {}
        for port in (*behaviour.input_ports(), *behaviour.output_ports()):
            binding = self.bindings.get(port)
            if isinstance(binding, Ref):
                remap[port] = "/" + binding.key
            else:
                remap[port] = PORT_PREFIX + port
                if isinstance(binding, Literal):
                    self._local[PORT_PREFIX + port] = binding.value
        with py_trees_storage(EntryView(self.blackboard, self._local)):
            behaviour.setup_ports(port_remappings=remap, subtree_namespace="/")

    def _view(self) -> EntryView:
        return EntryView(self.blackboard, self._local)

    def tick_node(self) -> NodeStatus:
        behaviour = self.behaviour
        with py_trees_storage(self._view()), raised_as_tree_error(self):
            for _ in behaviour.tick():
                pass
        self.feedback_message = behaviour.feedback_message
        status = RESULT_OF_PY_TREES.get(behaviour.status)
        if status is None:
            raise TreeRuntimeError(
                f"{self.describe()}: the py_trees behaviour returned {behaviour.status!r}")
        return status

    def halt(self) -> None:
        behaviour = self.behaviour
        if behaviour.status == Status.RUNNING:
            with py_trees_storage(self._view()):
                behaviour.stop(Status.INVALID)
            self.feedback_message = behaviour.feedback_message
        self.reset_status()

    def stop(self, new_status: Status = Status.INVALID) -> None:
        """py_trees' stop: a py_trees parent stopping the leaf stops the behaviour too (its
        ``terminate(INVALID)`` runs, also when it had finished, as in py_trees)."""
        if new_status != Status.INVALID:
            super().stop(new_status)
            return
        was_running = self.bt_status is NodeStatus.RUNNING
        with py_trees_storage(self._view()):
            self.behaviour.stop(Status.INVALID)
        self.feedback_message = self.behaviour.feedback_message
        self.reset_status()
        self.status = Status.INVALID
        script = self._post.get("_onHalted") if was_running and self._post else None
        if script is not None:
            self._run_script("_onHalted", script)

    def setup(self, **kwargs: Any) -> None:
        with py_trees_storage(self._view()):
            self.behaviour.setup(**kwargs)

    def shutdown(self) -> None:
        self.behaviour.shutdown()

    def update(self) -> Status:  # not used: tick_node runs the behaviour's own tick
        return self.behaviour.status


_CLASSES: dict[type, type[PyTreesLeaf]] = {}


def leaf_class_for(cls: type[Behaviour], node_id: str | None = None) -> type[PyTreesLeaf]:
    """The bt-manip leaf class wrapping py_trees behaviour class ``cls`` (made once)."""
    if cls in _CLASSES and node_id in (None, _CLASSES[cls].NODE_ID):
        return _CLASSES[cls]
    if issubclass(cls, (py_trees.composites.Composite, py_trees.decorators.Decorator)):
        raise TypeError(f"{cls.__qualname__} is a py_trees composite or decorator: only leaves "
                        "can be registered; convert a tree that uses py_trees' own composites "
                        "and decorators with bt_manip.bt.from_py_trees")
    clock_reading = _clock_counterparts().get(cls)
    if clock_reading is not None:
        return clock_reading
    params = constructor_params(cls)
    inputs: dict[str, PortInformation] = {}
    for p in params.values():
        inputs[p.name] = _port_info(p)
    outputs: dict[str, PortInformation] = {}
    if issubclass(cls, PortsMixin) and hasattr(cls, "INPUT_PORTS"):
        inputs.update(cls.input_ports())
        outputs.update(cls.output_ports())
    doc = (cls.__doc__ or "").strip().split("\n")[0] or f"py_trees behaviour {cls.__name__}"
    wrapper = type(cls.__name__, (PyTreesLeaf,), {
        "NODE_ID": node_id or cls.__name__,
        "BEHAVIOUR": cls,
        "PARAMS": params,
        "INPUT_PORTS": inputs,
        "OUTPUT_PORTS": outputs,
        "__doc__": f"{doc} (py_trees behaviour {cls.__module__}.{cls.__qualname__})",
        "__module__": cls.__module__,
        "__qualname__": cls.__qualname__,
    })
    if node_id is None:
        _CLASSES[cls] = wrapper
    return wrapper


def _port_info(p: Param) -> PortInformation:
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


def _clock_counterparts() -> dict[type, type[PyTreesLeaf]]:
    """py_trees classes replaced by bt-manip nodes reading the tree's clock (registered
    under the py_trees class name)."""
    from bt_manip.bt.pytrees_composites import PyTreesTimer

    if py_trees.timers.Timer not in _COUNTERPARTS:
        _COUNTERPARTS[py_trees.timers.Timer] = type(
            "Timer", (PyTreesTimer,), {"NODE_ID": "Timer", "__module__": __name__,
                                       "__doc__": PyTreesTimer.__doc__})
    return _COUNTERPARTS


_COUNTERPARTS: dict[type, Any] = {}


def wrap(behaviour: Behaviour) -> LeafNode:
    """A bt-manip leaf running ``behaviour`` (the object itself, not a copy)."""
    counterpart = _clock_counterparts().get(type(behaviour))
    if counterpart is not None:
        timer = cast(py_trees.timers.Timer, behaviour)  # the only class with a counterpart
        return counterpart(timer.name, duration=timer.duration)
    return leaf_class_for(type(behaviour))(behaviour=behaviour)


PY_TREES_LEAVES: tuple[type[Behaviour], ...] = (
    py_trees.behaviours.Success, py_trees.behaviours.Failure, py_trees.behaviours.Running,
    py_trees.behaviours.Dummy, py_trees.behaviours.Periodic, py_trees.behaviours.StatusQueue,
    py_trees.behaviours.SuccessEveryN, py_trees.behaviours.TickCounter,
    py_trees.behaviours.BlackboardToStatus, py_trees.behaviours.CheckBlackboardVariableExists,
    py_trees.behaviours.WaitForBlackboardVariable, py_trees.behaviours.UnsetBlackboardVariable,
    py_trees.behaviours.SetBlackboardVariable, py_trees.behaviours.ProbabilisticBehaviour,
    py_trees.timers.Timer,
)
"""py_trees' own leaves whose constructor arguments can be written in XML."""


def register_py_trees_behaviours() -> list[str]:
    """Register py_trees' own leaves (:data:`PY_TREES_LEAVES`); returns their node IDs.

    Done when :mod:`bt_manip.bt` is imported; calling it again changes nothing."""
    from bt_manip.bt.registry import registry

    ids = []
    for cls in PY_TREES_LEAVES:
        wrapper = leaf_class_for(cls)
        registry.register(wrapper)
        ids.append(wrapper.NODE_ID)
    return ids
