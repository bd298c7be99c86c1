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
``get_input()``/``_set_output()`` then read and write those. A behaviour wrapped after its
``setup_ports()`` ran (a converted py_trees tree) keeps that wiring
(:mod:`bt_manip.bt.pytrees.wiring`).

The blackboard bridge is :mod:`bt_manip.bt.pytrees.storage`, the conversion of constructor
arguments :mod:`bt_manip.bt.pytrees.arguments`.
"""

from __future__ import annotations

import inspect
import json
import typing
from collections.abc import Callable
from typing import Any, ClassVar, cast

import py_trees
from py_trees.behaviour import Behaviour
from py_trees.common import Status
from py_trees.ports import PortInformation, PortsMixin

from bt_manip.bt.attributes import AttributeCheck, UnwritableText
from bt_manip.bt.node import LeafNode, TreeRuntimeError
from bt_manip.bt.ports import Literal, Ref
from bt_manip.bt.pytrees.arguments import (
    Param,
    constructor_params,
    convert_param,
    format_param,
    port_info,
    recover_arguments,
)
from bt_manip.bt.pytrees.storage import (
    PORT_PREFIX,
    EntryView,
    py_trees_storage,
    raised_as_tree_error,
)
from bt_manip.bt.pytrees.wiring import (
    carried_wiring,
    forget_client,
    setup_entries,
    subtree_namespace,
)
from bt_manip.bt.registry import registry
from bt_manip.bt.status import RESULT_OF_PY_TREES, NodeStatus

_UNKNOWN = object()  # a constructor argument of a wrapped object that its attributes hide


def _is_reference(text: str) -> bool:
    """``{key}`` names a blackboard entry; a JSON object (``{"a": "b"}``) is a value."""
    if not text.strip().startswith("{"):
        return False
    try:
        return not isinstance(json.loads(text), dict)
    except json.JSONDecodeError:
        return True


def takes_name(cls: Callable[..., Behaviour]) -> bool:
    """Whether ``cls``'s constructor takes a ``name`` (or any keyword); a class that names
    itself is built without one and then given the node's name."""
    try:
        parameters = inspect.signature(cls).parameters.values()
    except (TypeError, ValueError):
        return True
    return any(p.name == "name" or p.kind is p.VAR_KEYWORD for p in parameters)


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
            attributes = {**unknown, **{k: Literal(v) for k, v in given.items()},
                          **carried_wiring(behaviour), **attributes}
        super().__init__(name or self.NODE_ID, **attributes)
        for port, binding in list(self.bindings.items()):
            if isinstance(binding, Literal) and binding.value is _UNKNOWN:
                del self.bindings[port]
                self.attribute_texts.pop(port, None)
                if self.PARAMS[port].required:  # XML without it would not load
                    self.attribute_texts[port] = UnwritableText(
                        None, "the behaviour does not keep this constructor argument in an "
                        "attribute of the same name, so its value is unknown")
        if behaviour is None:
            kwargs = {p: b.value for p, b in self.bindings.items()
                      if p in self.PARAMS and isinstance(b, Literal)}
            named = takes_name(self.BEHAVIOUR)
            try:
                behaviour = self.BEHAVIOUR(name=self.name, **kwargs) if named \
                    else self.BEHAVIOUR(**kwargs)
            except Exception as e:  # the constructor refused its arguments
                raise ValueError(f"{self.NODE_ID}: {type(e).__name__}: {e}") from None
            if not named:
                behaviour.name = self.name
        self.behaviour = behaviour
        self.blackboards = behaviour.blackboards
        self._local: dict[str, Any] = {}
        self.setup_entries: dict[str, Any] = setup_entries(behaviour)
        """Entries py_trees' ``setup_ports()`` had written for the behaviour before it was
        wrapped (a converted tree starts with them)."""
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
            if isinstance(value, Ref) or (isinstance(value, str) and _is_reference(value)):
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
        namespace = subtree_namespace(behaviour)  # where an earlier setup_ports() put it
        forget_client(behaviour)
        with py_trees_storage(EntryView(self.blackboard, self._local)):
            behaviour.setup_ports(port_remappings=remap, subtree_namespace=namespace)

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
        inputs[p.name] = port_info(p)
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


# ---------------------------------------------------------------------- clock readers


@registry.register
class PyTreesTimer(LeafNode):
    """py_trees' ``Timer`` on the tree's clock: RUNNING until more than ``duration`` seconds
    have passed since it started, then SUCCESS."""

    INPUT_PORTS: dict[str, PortInformation] = {
        "duration": PortInformation(float, description="seconds", default_value=5.0)}

    def __init__(self, name: str | None = None, **attributes: Any) -> None:
        super().__init__(name, **attributes)
        self.duration = float(self.get_input("duration"))
        self.finish_time = 0.0

    def initialise(self) -> None:
        self.finish_time = self.now() + self.duration
        self.feedback_message = f"configured to fire in '{self.duration}' seconds"

    def update(self) -> Status:
        if self.now() > self.finish_time:
            self.feedback_message = f"timer ran out [{self.duration}]"
            return Status.SUCCESS
        self.feedback_message = "still running"
        return Status.RUNNING


def _clock_counterparts() -> dict[type, type[PyTreesLeaf]]:
    """py_trees classes replaced by bt-manip nodes reading the tree's clock (registered
    under the py_trees class name)."""
    if py_trees.timers.Timer not in _COUNTERPARTS:
        _COUNTERPARTS[py_trees.timers.Timer] = type(
            "Timer", (PyTreesTimer,), {"NODE_ID": "Timer", "__module__": __name__,
                                       "__doc__": PyTreesTimer.__doc__})
    return _COUNTERPARTS


_COUNTERPARTS: dict[type, Any] = {}


def wrap(behaviour: Behaviour) -> LeafNode:
    """A bt-manip leaf running ``behaviour`` (the object itself, not a copy).

    Its class gets the class name as ID, or its module-qualified name
    (``py_trees.demos.stewardship.SuccessEveryN``) where the class name is registered for
    another class, so that the XML ``to_xml`` writes loads this class back."""
    cls = type(behaviour)
    counterpart = _clock_counterparts().get(cls)
    if counterpart is not None:
        timer = cast(py_trees.timers.Timer, behaviour)  # the only class with a counterpart
        return counterpart(timer.name, duration=timer.duration)
    return _conversion_class(cls)(behaviour=behaviour)


_QUALIFIED: dict[type, type[PyTreesLeaf]] = {}


def _conversion_class(cls: type[Behaviour]) -> type[PyTreesLeaf]:
    if cls in _QUALIFIED:
        return _QUALIFIED[cls]
    leaf_class = leaf_class_for(cls)
    registered = registry.get(leaf_class.NODE_ID)
    if registered is None or getattr(registered, "BEHAVIOUR", None) is cls:
        return leaf_class
    qualified = leaf_class_for(cls, f"{cls.__module__}.{cls.__qualname__}")
    _QUALIFIED[cls] = qualified
    return qualified


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
    ids = []
    for cls in PY_TREES_LEAVES:
        wrapper = leaf_class_for(cls)
        registry.register(wrapper)
        ids.append(wrapper.NODE_ID)
    return ids
