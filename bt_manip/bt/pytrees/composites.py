"""py_trees' composites and decorators as bt-manip nodes, with py_trees' semantics.

:func:`bt_manip.bt.from_py_trees` (:mod:`bt_manip.bt.pytrees.convert`) uses a
BehaviorTree.CPP built-in where it ticks like the py_trees node, and these nodes otherwise
(``PyTreesSequence``, ``PyTreesRepeat``, ...). Each runs py_trees' own tick logic
(``py_trees.composites.Sequence.tick`` and so on), so it does exactly what py_trees does, tick
by tick:

- its children keep their status after they finish (py_trees parents stop them with INVALID
  when they start again, which runs a RUNNING child's ``terminate(INVALID)``);
- a BT.CPP parent above it sees SUCCESS, FAILURE or RUNNING as py_trees computed it;
- halted (by a BT.CPP parent or ``Tree.halt()``) it is stopped as py_trees stops it.

They are registered (not as built-ins), so ``to_xml()`` writes them with their ports and a
TreeNodesModel that declares them, and the XML loads back. Durations (``PyTreesTimeout``, and
``PyTreesTimer`` in :mod:`bt_manip.bt.pytrees.leaf`) read the tree's clock: the simulation
clock under a world.
"""

from __future__ import annotations

import functools
import inspect
from collections.abc import Callable
from typing import Any, ClassVar, cast

import py_trees
from py_trees.common import Status
from py_trees.ports import PortInformation

from bt_manip.bt.attributes import AttributeCheck, UnwritableText
from bt_manip.bt.node import BtNode, ControlNode, DecoratorNode, TreeRuntimeError, _truth
from bt_manip.bt.pytrees.storage import EntryView, py_trees_storage, raised_as_tree_error
from bt_manip.bt.registry import registry
from bt_manip.bt.script import Script
from bt_manip.bt.status import STATUS_OF_PY_TREES, NodeStatus

Ports = dict[str, PortInformation]
INVALID = Status.INVALID
POLICIES = ("SuccessOnAll", "SuccessOnOne", "SuccessOnSelected")
ONESHOT_POLICIES = tuple(p.name for p in py_trees.common.OneShotPolicy)


def _result(node: BtNode) -> NodeStatus:
    status = node.status
    if status == INVALID:
        raise TreeRuntimeError(f"{node.describe()}: py_trees' tick left the node INVALID")
    return STATUS_OF_PY_TREES[status]


class _PyTreesNode:
    """What the py_trees composites and decorators share (mixed before ControlNode etc.)."""

    PY: ClassVar[Any]  # the py_trees class whose methods run with this node as self

    def _storage(self) -> Any:
        node = cast(BtNode, self)  # mixed into BtNode classes only
        return py_trees_storage(EntryView(node.blackboard))

    def tick_node(self) -> NodeStatus:
        with self._storage(), raised_as_tree_error(self):
            for _ in self._py_tick():
                pass
        return _result(cast(BtNode, self))

    def _py_tick(self) -> Any:
        return self.PY.tick(self)

    def stop(self, new_status: Status = INVALID) -> None:
        """py_trees' stop (INVALID stops the children too), keeping the BT.CPP status in step."""
        self.PY.stop(self, new_status)
        self.bt_status = STATUS_OF_PY_TREES[new_status]

    def halt(self) -> None:
        self.stop(INVALID)


# ---------------------------------------------------------------------- composites


class _PyTreesComposite(_PyTreesNode, ControlNode):
    MIN_CHILDREN = 0


class _MemoryComposite(_PyTreesComposite):
    """A py_trees composite with the ``memory`` flag (``Sequence``, ``Selector``)."""

    INPUT_PORTS: Ports = {
        "memory": PortInformation(bool, description="resume from the RUNNING child",
                                  default_value=False)}

    def __init__(self, name: str | None = None, children: list[BtNode] | None = None,
                 **attributes: Any) -> None:
        super().__init__(name, children, **attributes)
        self.memory = bool(self.get_input("memory"))


@registry.register
class PyTreesSequence(_MemoryComposite):
    """py_trees' ``Sequence``: ticks children in order while they succeed.

    - child SUCCESS: go on with the next child (all succeeded: SUCCESS; no children: SUCCESS);
    - child FAILURE: return FAILURE; the next tick starts again from the first child;
    - child RUNNING: return RUNNING; with ``memory`` the next tick resumes from that child,
      without it the next tick starts from the first child again (and a RUNNING child further
      right is stopped).
    """

    PY = py_trees.composites.Sequence


@registry.register
class PyTreesSelector(_MemoryComposite):
    """py_trees' ``Selector``: ticks children in order until one does not fail.

    - child FAILURE: try the next child (all failed, or no children: FAILURE);
    - child SUCCESS: return SUCCESS (children further right that were RUNNING are stopped);
    - child RUNNING: return RUNNING; with ``memory`` the next tick resumes from that child,
      without it the next tick starts from the first child again.
    """

    PY = py_trees.composites.Selector


@registry.register
class PyTreesParallel(_PyTreesComposite):
    """py_trees' ``Parallel``: ticks every child at each tick, then decides.

    - any child FAILURE: FAILURE (RUNNING children are stopped);
    - ``policy`` SuccessOnAll: SUCCESS when every child succeeded; SuccessOnOne: when one did;
      SuccessOnSelected: when the children at the indices ``selected`` (``0;2``) did;
    - otherwise RUNNING. With ``synchronise`` (SuccessOnAll, SuccessOnSelected) a child that
      succeeded is not ticked again until the parallel finishes.
    """

    PY = py_trees.composites.Parallel
    INPUT_PORTS: Ports = {
        "policy": PortInformation(str, description="SuccessOnAll, SuccessOnOne or "
                                                   "SuccessOnSelected",
                                  default_value="SuccessOnAll"),
        "synchronise": PortInformation(bool, description="do not re-tick children that "
                                                         "succeeded", default_value=True),
        "selected": PortInformation(list[int], required=False,
                                    description="child indices for SuccessOnSelected"),
    }
    validate_policy_configuration = py_trees.composites.Parallel.validate_policy_configuration

    @classmethod
    def check_attributes(cls, attributes: Any) -> AttributeCheck:
        check = super().check_attributes(attributes)
        policy = attributes.get("policy", "SuccessOnAll")
        if isinstance(policy, str) and policy not in POLICIES:
            check.errors.append((f"bad value for port 'policy' of {cls.NODE_ID}: expected one "
                                 f"of {', '.join(POLICIES)}, got '{policy}'", None))
        if policy == "SuccessOnSelected" and "selected" not in attributes:
            check.errors.append((f"{cls.NODE_ID} with policy SuccessOnSelected needs "
                                 "selected=\"i;j\" (child indices)", None))
        return check

    def __init__(self, name: str | None = None, children: list[BtNode] | None = None,
                 **attributes: Any) -> None:
        super().__init__(name, children, **attributes)
        policy = self.get_input("policy")
        synchronise = bool(self.get_input("synchronise"))
        common = py_trees.common.ParallelPolicy
        if policy == "SuccessOnOne":
            self.policy: Any = common.SuccessOnOne()
        elif policy == "SuccessOnSelected":
            indices = self.get_input("selected", [])
            bad = [i for i in indices if not 0 <= i < len(self.children)]
            if bad:
                raise ValueError(f"{self.NODE_ID}: selected index {bad[0]} is not a child "
                                 f"index (0 to {len(self.children) - 1})")
            self.policy = common.SuccessOnSelected(
                children=[self.children[i] for i in indices], synchronise=synchronise)
        else:
            self.policy = common.SuccessOnAll(synchronise=synchronise)


# ---------------------------------------------------------------------- decorators


class _PyTreesDecorator(_PyTreesNode, DecoratorNode):
    """A py_trees decorator: its child keeps its status when it finishes (no BT.CPP reset)."""

    # any py_trees decorator class: its methods run on this node (see _PyTreesNode.PY)
    PY: ClassVar[Any] = py_trees.decorators.PassThrough

    def execute_tick(self) -> NodeStatus:
        return BtNode.execute_tick(self)

    def initialise(self) -> None:
        self.PY.initialise(self)

    def update(self) -> Status:
        return cast(Status, self.PY.update(self))  # py_trees' update() gives a Status

    def terminate(self, new_status: Status) -> None:
        self.PY.terminate(self, new_status)


def _simple(py_class: type, doc: str) -> type:
    cls = type(f"PyTrees{py_class.__name__}", (_PyTreesDecorator,),
               {"PY": py_class, "__doc__": doc, "__module__": __name__})
    return registry.register(cls)


PyTreesPassThrough = _simple(py_trees.decorators.PassThrough,
                             "py_trees' ``PassThrough``: returns the child's status.")
PyTreesInverter = _simple(py_trees.decorators.Inverter,
                          "py_trees' ``Inverter``: SUCCESS and FAILURE swapped, RUNNING kept.")
PyTreesRunningIsFailure = _simple(py_trees.decorators.RunningIsFailure,
                                  "py_trees' ``RunningIsFailure``: child RUNNING gives FAILURE "
                                  "(the child is stopped); other statuses pass.")
PyTreesRunningIsSuccess = _simple(py_trees.decorators.RunningIsSuccess,
                                  "py_trees' ``RunningIsSuccess``: child RUNNING gives SUCCESS "
                                  "(the child is stopped); other statuses pass.")
PyTreesFailureIsSuccess = _simple(py_trees.decorators.FailureIsSuccess,
                                  "py_trees' ``FailureIsSuccess``: child FAILURE gives SUCCESS; "
                                  "other statuses pass.")
PyTreesFailureIsRunning = _simple(py_trees.decorators.FailureIsRunning,
                                  "py_trees' ``FailureIsRunning``: child FAILURE gives RUNNING; "
                                  "other statuses pass.")
PyTreesSuccessIsFailure = _simple(py_trees.decorators.SuccessIsFailure,
                                  "py_trees' ``SuccessIsFailure``: child SUCCESS gives FAILURE; "
                                  "other statuses pass.")
PyTreesSuccessIsRunning = _simple(py_trees.decorators.SuccessIsRunning,
                                  "py_trees' ``SuccessIsRunning``: child SUCCESS gives RUNNING; "
                                  "other statuses pass.")


@registry.register
class PyTreesRepeat(_PyTreesDecorator):
    """py_trees' ``Repeat``: child SUCCESS counts one success and returns RUNNING until
    ``num_success`` successes (then SUCCESS; -1: never); child FAILURE gives FAILURE; child
    RUNNING gives RUNNING. One cycle per tick."""

    PY = py_trees.decorators.Repeat
    INPUT_PORTS: Ports = {
        "num_success": PortInformation(int, description="successes needed; -1 repeats forever")}

    def __init__(self, name: str | None = None, child: BtNode | None = None,
                 **attributes: Any) -> None:
        super().__init__(name, child, **attributes)
        self.num_success = self.get_input("num_success")
        self.success = 0


@registry.register
class PyTreesRetry(_PyTreesDecorator):
    """py_trees' ``Retry``: child FAILURE returns RUNNING until ``num_failures`` failures (then
    FAILURE); child SUCCESS gives SUCCESS; RUNNING gives RUNNING. One attempt per tick."""

    PY = py_trees.decorators.Retry
    INPUT_PORTS: Ports = {
        "num_failures": PortInformation(int, description="failures before giving up")}

    def __init__(self, name: str | None = None, child: BtNode | None = None,
                 **attributes: Any) -> None:
        super().__init__(name, child, **attributes)
        self.num_failures = self.get_input("num_failures")
        self.failures = 0


@registry.register
class PyTreesTimeout(_PyTreesDecorator):
    """py_trees' ``Timeout`` on the tree's clock: ticks the child; if it is still RUNNING
    more than ``duration`` seconds after the decorator started, stops it and returns FAILURE;
    otherwise returns the child's status."""

    PY = py_trees.decorators.Timeout
    INPUT_PORTS: Ports = {
        "duration": PortInformation(float, description="seconds", default_value=5.0)}

    def __init__(self, name: str | None = None, child: BtNode | None = None,
                 **attributes: Any) -> None:
        super().__init__(name, child, **attributes)
        self.duration = float(self.get_input("duration"))
        self.finish_time = 0.0

    def initialise(self) -> None:
        self.finish_time = self.now() + self.duration
        self.feedback_message = ""

    def update(self) -> Status:
        now = self.now()
        child = self.decorated
        if child.status == Status.RUNNING and now > self.finish_time:
            self.feedback_message = "timed out"
            child.stop(INVALID)
            return Status.FAILURE
        if child.status == Status.RUNNING:
            self.feedback_message = f"time still ticking [remaining: {self.finish_time - now}s]"
        else:
            self.feedback_message = "child finished before timeout triggered"
        return child.status


@registry.register
class PyTreesCount(_PyTreesDecorator):
    """py_trees' ``Count``: returns the child's status and counts ticks, RUNNING ticks,
    successes, failures and interruptions (shown in its feedback message)."""

    PY: ClassVar[Any] = py_trees.decorators.Count

    def __init__(self, name: str | None = None, child: BtNode | None = None,
                 **attributes: Any) -> None:
        super().__init__(name, child, **attributes)
        self.total_tick_count = self.failure_count = self.success_count = 0
        self.running_count = self.interrupt_count = 0

    def setup(self, **kwargs: Any) -> None:
        self.PY.setup(self, **kwargs)


@registry.register
class PyTreesOneShot(_PyTreesDecorator):
    """py_trees' ``OneShot``: ticks the child until it finishes with a status of ``policy``
    (ON_COMPLETION: SUCCESS or FAILURE; ON_SUCCESSFUL_COMPLETION: SUCCESS), then returns that
    status for ever without ticking the child."""

    PY = py_trees.decorators.OneShot
    INPUT_PORTS: Ports = {
        "policy": PortInformation(str, description="ON_COMPLETION or ON_SUCCESSFUL_COMPLETION",
                                  default_value="ON_COMPLETION")}

    @classmethod
    def check_attributes(cls, attributes: Any) -> AttributeCheck:
        check = super().check_attributes(attributes)
        policy = attributes.get("policy", "ON_COMPLETION")
        if isinstance(policy, str) and policy not in ONESHOT_POLICIES:
            check.errors.append((f"bad value for port 'policy' of {cls.NODE_ID}: expected one "
                                 f"of {', '.join(ONESHOT_POLICIES)}, got '{policy}'", None))
        return check

    def __init__(self, name: str | None = None, child: BtNode | None = None,
                 **attributes: Any) -> None:
        super().__init__(name, child, **attributes)
        self.policy = py_trees.common.OneShotPolicy[self.get_input("policy")]
        self.final_status: Status | None = None


@registry.register
class PyTreesCondition(_PyTreesDecorator):
    """py_trees' ``Condition``: ticks the child; SUCCESS when the child's status is
    ``status``, RUNNING otherwise."""

    PY = py_trees.decorators.Condition
    INPUT_PORTS: Ports = {
        "status": PortInformation(NodeStatus, description="child status that means SUCCESS",
                                  default_value=NodeStatus.SUCCESS)}

    def __init__(self, name: str | None = None, child: BtNode | None = None,
                 **attributes: Any) -> None:
        super().__init__(name, child, **attributes)
        self.succeed_status = NodeStatus(self.get_input("status")).to_py_trees()


class _ClientDecorator(_PyTreesDecorator):
    """A decorator with a py_trees blackboard client (reading the tree's blackboard)."""

    def _client(self, keys: dict[str, py_trees.common.Access]) -> Any:
        client = self.attach_blackboard_client(self.name)
        for key, access in keys.items():
            client.register_key(key=key, access=access)
        return client


@registry.register
class PyTreesStatusToBlackboard(_ClientDecorator):
    """py_trees' ``StatusToBlackboard``: writes the child's py_trees status into entry
    ``variable_name`` after each tick and returns it."""

    PY = py_trees.decorators.StatusToBlackboard
    INPUT_PORTS: Ports = {
        "variable_name": PortInformation(str, description="entry to write the status to")}

    def __init__(self, name: str | None = None, child: BtNode | None = None,
                 **attributes: Any) -> None:
        super().__init__(name, child, **attributes)
        self.variable_name = str(self.get_input("variable_name"))
        self.client = self._client(
            {self.variable_name.split(".")[0]: py_trees.common.Access.WRITE})

    def update(self) -> Status:
        self.client.set(self.variable_name, self.decorated.status, overwrite=True)
        return self.decorated.status


@registry.register
class PyTreesEternalGuard(_ClientDecorator):
    """py_trees' ``EternalGuard``: checks ``condition`` at every tick before the child; false
    stops the child and returns FAILURE, true ticks the child and returns its status.

    In Python the condition is a callable returning a bool or a py_trees Status (given the
    blackboard client when it takes a ``blackboard`` argument); in XML it is a bt-manip script
    evaluated on the blackboard (``condition="battery > 20"``).
    """

    PY = py_trees.decorators.EternalGuard
    INPUT_PORTS: Ports = {
        "condition": PortInformation(object, description="script (XML) or Python callable"),
        "blackboard_keys": PortInformation(list[str], required=False,
                                           description="entries a Python condition reads"),
    }
    SCRIPT_PORTS = ("condition",)

    def __init__(self, name: str | None = None, child: BtNode | None = None,
                 **attributes: Any) -> None:
        keys = attributes.get("blackboard_keys") or []
        super().__init__(name, child, **attributes)
        client = self._client({k: py_trees.common.Access.READ for k in keys})
        condition = self.bindings["condition"]
        value = getattr(condition, "value", None)
        if isinstance(value, Script):
            script = value
            self.condition: Callable[[], Any] = lambda: _truth(self, "condition", script)
        elif callable(value):
            if "blackboard" in inspect.signature(value).parameters:
                self.condition = functools.partial(value, client)
            else:
                self.condition = value
            function = getattr(value, "func", value)
            self.attribute_texts["condition"] = UnwritableText(
                value, f"the Python callable {getattr(function, '__qualname__', value)!s} "
                "cannot be written in XML (give a script instead)")
        else:
            raise ValueError(f"{self.NODE_ID}: condition must be a script or a Python "
                             "callable, got a blackboard reference or a value")

    def _py_tick(self) -> Any:
        result = self.condition()
        if isinstance(result, Status):
            result = result != Status.FAILURE
        elif not isinstance(result, bool):
            raise TreeRuntimeError(f"{self.describe()}: the condition must return a bool or a "
                                   f"py_trees Status, got {type(result).__name__}")
        if not result:
            self.stop(Status.FAILURE)
            return iter(())
        return py_trees.decorators.Decorator.tick(self)

    def update(self) -> Status:
        return self.decorated.status


@registry.register
class PyTreesForEach(_ClientDecorator):
    """py_trees' ``ForEach``: at start reads the list in entry ``source_key`` and writes its
    first item into ``target_key``; each child SUCCESS moves to the next item and returns
    RUNNING, SUCCESS after the last one (or for an empty list); child FAILURE or RUNNING is
    returned as is."""

    PY = py_trees.decorators.ForEach
    INPUT_PORTS: Ports = {
        "source_key": PortInformation(str, description="entry holding the items"),
        "target_key": PortInformation(str, description="entry receiving the current item"),
    }

    def __init__(self, name: str | None = None, child: BtNode | None = None,
                 **attributes: Any) -> None:
        super().__init__(name, child, **attributes)
        self.source_key = str(self.get_input("source_key"))
        self.target_key = str(self.get_input("target_key"))
        self.client = self._client({self.source_key: py_trees.common.Access.READ,
                                    self.target_key: py_trees.common.Access.WRITE})
        self._items: Any = None
        self._current: Any = None

    def initialise(self) -> None:
        items = self.client.get(self.source_key) or []
        try:
            self._items = iter(items)
        except TypeError:
            raise TreeRuntimeError(f"{self.describe()}: entry '{self.source_key}' is not a "
                                   "list") from None
        self._advance()

    def _advance(self) -> None:
        try:
            self._current = next(self._items) if self._items is not None else None
            if self._current is not None:
                self.client.set(self.target_key, self._current)
        except StopIteration:
            self._current = None

    def update(self) -> Status:
        if self._current is None:
            return Status.SUCCESS
        status = self.decorated.status
        if status == Status.SUCCESS:
            self._advance()
            if self._current is not None:
                return Status.RUNNING
        return status

    def terminate(self, new_status: Status) -> None:
        self._items = None
        self._current = None


# py_trees' display and dot export pick their glyphs and shapes by isinstance.
py_trees.composites.Sequence.register(PyTreesSequence)
py_trees.composites.Selector.register(PyTreesSelector)
py_trees.composites.Parallel.register(PyTreesParallel)
