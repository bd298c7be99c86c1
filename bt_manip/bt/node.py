"""Base classes of every bt-manip node, with BehaviorTree.CPP's tick protocol.

Each node is a py_trees behaviour with typed ports declared through py_trees'
``PortsMixin``/``PortInformation`` (class attributes ``INPUT_PORTS`` and ``OUTPUT_PORTS``), so one
class serves XML loading, Python authoring, validation and the TreeNodesModel export.

Ticking follows BT.CPP (``TreeNode::executeTick``):

1. pre-condition attributes are checked: when the node is IDLE, ``_failureIf``, ``_successIf``
   and ``_skipIf`` (in this order) may decide its status without ticking it, and a false
   ``_while`` skips it; when it is RUNNING, a false ``_while`` halts it and it is SKIPPED;
2. otherwise the node's own logic runs (``update()`` for leaves);
3. on SUCCESS or FAILURE, ``_onSuccess`` or ``_onFailure`` then ``_post`` run;
4. a SKIPPED node keeps its IDLE status but tells its parent it was skipped.

Halting a RUNNING node calls its ``terminate(INVALID)`` exactly once, then ``_onHalted``.

Subclass :class:`ActionNode` or :class:`ConditionNode` for leaves: implement ``update()`` (and
``initialise()``/``terminate()`` as in py_trees), read ports with :meth:`BtNode.get_input`, write
them with :meth:`BtNode.set_output`, and put a failure reason in ``feedback_message``.
"""

from __future__ import annotations

import copy
import itertools
from collections.abc import Callable, Mapping
from typing import Any, ClassVar, Protocol, cast

import py_trees
from py_trees.common import Status
from py_trees.ports import PortInformation, PortsMixin

try:  # py_trees' own answer when it has one by that name
    from py_trees.ports import _ports_class_is_abstract
except ImportError:  # pragma: no cover - another py_trees release

    def _ports_class_is_abstract(cls: type) -> bool:
        """Whether ``cls`` lacks its port declarations or still has abstract methods."""
        if not (hasattr(cls, "INPUT_PORTS") and hasattr(cls, "OUTPUT_PORTS")):
            return True
        return any(
            getattr(getattr(cls, name, None), "__isabstractmethod__", False) for name in dir(cls)
        )

from bt_manip.bt import py_trees_hook
from bt_manip.bt.attributes import IMMUTABLE_TYPES, AttributeCheck, check_attributes
from bt_manip.bt.attributes import closest as closest  # where behaviours import it from
from bt_manip.bt.blackboard import Blackboard
from bt_manip.bt.context import TreeContext
from bt_manip.bt.ports import (
    Binding,
    InOutPortInformation,
    Literal,
    Ref,
    convert_literal,
    takes_infinity,
    value_problem,
)
from bt_manip.bt.script import Script, ScriptRuntimeError, to_bool
from bt_manip.bt.status import PY_TREES_OF, RESULT_OF_PY_TREES, STATUS_OF_PY_TREES, NodeStatus

_MISSING = object()
_ORDER = itertools.count(1)
_RUNNING = Status.RUNNING
# Enum members hash in Python code: the hot path maps statuses through identity lookups.
_PY_BY_ID = {id(s): p for s, p in PY_TREES_OF.items()}
_IDLE = NodeStatus.IDLE
_SUCCESS = NodeStatus.SUCCESS
_FAILURE = NodeStatus.FAILURE
_SKIPPED = NodeStatus.SKIPPED
_LEAF_RESULT = {id(s): b for s, b in RESULT_OF_PY_TREES.items()}


class TreeRuntimeError(RuntimeError):
    """A tree cannot go on: a script failed, a port has no value, a node misbehaved."""


class PortError(TreeRuntimeError):
    """An input port has no usable value, or an output port cannot be written."""


class BtNode(PortsMixin):
    """Mixin giving a py_trees behaviour BT.CPP's node protocol (see the module docstring)."""

    NODE_ID: ClassVar[str] = ""
    KIND: ClassVar[str] = "Action"
    DESCRIPTION: ClassVar[str] = ""
    MIN_CHILDREN: ClassVar[int] = 0
    MAX_CHILDREN: ClassVar[int | None] = 0
    # py_trees' PortsMixin annotates the two as instance attributes, though every node class
    # declares them at class level: mypy lets no ClassVar override an instance attribute, so
    # port declarations go without ClassVar (ruff's RUF012 is off for them, pyproject.toml).
    INPUT_PORTS: dict[str, PortInformation] = {}
    OUTPUT_PORTS: dict[str, PortInformation] = {}
    SCRIPT_PORTS: ClassVar[tuple[str, ...]] = ()  # ports whose literal is a script
    REQUIRED_ONE_OF: ClassVar[tuple[tuple[str, ...], ...]] = ()
    """Groups of alternative ports of which a tree must give exactly one, checked when a tree
    file is loaded: ``(("position", "object"),)``. An alternative written ``"min+max"`` is two
    ports given together."""
    REQUIRED_ANY_OF: ClassVar[tuple[tuple[str, ...], ...]] = ()
    """Groups of alternative ports of which a tree must give at least one (the node uses the
    first one given)."""
    WORLD_NAMES: ClassVar[dict[str, str]] = {}
    """Ports whose literal names something of the world, by port: ``"object"`` (a movable
    object or model), ``"body"`` (any body: furniture, object, model), ``"model"`` (a model to
    spawn), ``"pose"`` (a named pose; numbers ``x;y;yaw`` pass) or ``"robot"``. ``bt-manip
    validate --world W`` checks them against W."""
    DEFAULT_KEYS: ClassVar[tuple[str, ...]] = ()
    """Blackboard entries the node reads by their own name when a port is not given (Nav2's
    ``getInputOrBlackboard``): a SubTree port of that name is used by it."""
    NEEDS_WORLD: ClassVar[bool] = False
    """Whether the node acts on a simulated world (a tree holding one cannot run without
    ``--world``)."""
    started_order: int = 0
    failure_order: int = 0
    """When the node last started (was ticked while IDLE) and last returned FAILURE, as ranks
    on one counter (0: never); they tell the failures of a node's last run from older ones
    (see :mod:`bt_manip.run.failure_cause`)."""
    PORT_TYPE_NAMES: ClassVar[dict[str, str]] = {}  # BT.CPP type names that differ from ours
    MODEL_TYPE_NAMES: ClassVar[dict[str, str]] = {}
    """Type names the TreeNodesModel shows for ports, when they differ from those the
    blackboard uses (e.g. Nav2's ROS message types, :mod:`bt_manip.nav2.model_types`)."""

    pre_tick: Callable[[BtNode], NodeStatus] | None = None
    """BT.CPP's pre-tick callback: called before the tick of a node that is not finished and
    not decided by a pre-condition; a SUCCESS or FAILURE it returns replaces the tick."""

    def __init_subclass__(cls, **kwargs: Any) -> None:
        kwargs.setdefault("register", False)  # our registry, not py_trees', names nodes
        super().__init_subclass__(**kwargs)
        if "NODE_ID" not in vars(cls):
            cls.NODE_ID = cls.__name__

    def __init__(self, *args: Any, behaviour_class_name: str | None = None, **kwargs: Any) -> None:
        """``PortsMixin.__init__`` with its abstract-class check asked once per class.

        py_trees checks at every construction whether the class is still abstract by scanning
        ``dir()`` of the class, which costs more than the rest of building a node; the answer
        is a property of the class, kept on the class itself (:func:`_class_is_abstract`).
        The same fields are set and the same ``TypeError`` is raised as by ``PortsMixin``.
        """
        cls = type(self)
        if _class_is_abstract(cls):
            raise TypeError(
                f"Can't instantiate abstract class {cls.__name__} without the "
                "INPUT_PORTS and OUTPUT_PORTS class attribute declarations."
            )
        super(PortsMixin, self).__init__(*args, **kwargs)
        self._blackboard_client = None
        self._subtree_namespace = None
        self._ports_logger = None
        self._behaviour_class_name = (
            behaviour_class_name if behaviour_class_name is not None else cls.__name__
        )

    # ------------------------------------------------------------------ construction

    @classmethod
    def port_info(cls, port: str) -> PortInformation | None:
        return cls.INPUT_PORTS.get(port) or cls.OUTPUT_PORTS.get(port)

    @classmethod
    def check_attributes(cls, attributes: Mapping[str, Any]) -> AttributeCheck:
        """Check and convert ``attributes`` (XML text or Python values) for this class.

        A tree repeats the same node with the same text attributes (a subtree used once per
        object): the check of text attributes that holds no script and only immutable
        literals is kept per class and handed out as a copy, so each node still has its own
        bindings (:mod:`bt_manip.bt.attributes`)."""
        return check_attributes(cls, attributes)

    def _init_node(self, attributes: Mapping[str, Any]) -> None:
        check = type(self).check_attributes(attributes)
        if check.errors:
            raise ValueError("; ".join(msg for msg, _ in check.errors))
        self.bindings: dict[str, Binding] = check.bindings
        self.attribute_texts: dict[str, str] = check.texts
        self._pre: list[tuple[str, Script]] = check.pre
        self._post: dict[str, Script] = check.post
        self.bt_status = NodeStatus.IDLE
        self.last_status = NodeStatus.IDLE  # what the node last returned, kept after resets
        self.blackboard = Blackboard()
        self.context = TreeContext()
        self.xml_file: str | None = None
        self.xml_line: int | None = None

    # ------------------------------------------------------------------ ports

    def get_input(self, port_name: str, default: Any = _MISSING) -> Any:
        """Value of an input port, converted to the port type, references resolved.

        Without a value (port not given and no declared default, or a reference to a missing
        blackboard entry) returns ``default`` if given, else raises :class:`PortError`.
        """
        info = self.INPUT_PORTS.get(port_name)
        if info is None:
            raise KeyError(f"{self.describe()}: '{port_name}' is not an input port")
        binding = self.bindings.get(port_name)
        if binding is None:
            if info.has_default:
                value = info.default_value
                # deepcopy returns these unchanged; skip its cost on the tick path
                return value if type(value) in IMMUTABLE_TYPES else copy.deepcopy(value)
            if default is not _MISSING:
                return default
            raise PortError(f"{self.describe()}: input port '{port_name}' has no value")
        if isinstance(binding, Literal):  # Binding is Ref | Literal, neither subclassed
            return binding.value
        try:
            value = self.blackboard.get(binding.key)
        except KeyError:
            if default is not _MISSING:
                return default
            state = "has no value" if self.blackboard.exists(binding.key) else "does not exist"
            raise PortError(
                f"{self.describe()}: input port '{port_name}' reads blackboard entry "
                f"'{binding.key}', which {state}") from None
        if isinstance(value, str) and info.data_type is not str:
            try:
                value = convert_literal(value, info.data_type, takes_infinity(info))
            except ValueError as e:
                raise PortError(
                    f"{self.describe()}: input port '{port_name}' (entry '{binding.key}'): {e}"
                ) from None
        problem = value_problem(info, value)
        if problem is not None:
            raise PortError(
                f"{self.describe()}: input port '{port_name}' (entry '{binding.key}'): {problem}")
        return value

    def set_output(self, port_name: str, value: Any) -> bool:
        """Write an output (or in/out) port; False when the port is not bound to an entry."""
        info = self.OUTPUT_PORTS.get(port_name) or self.INPUT_PORTS.get(port_name)
        if info is None or (port_name not in self.OUTPUT_PORTS
                            and not isinstance(info, InOutPortInformation)):
            raise KeyError(f"{self.describe()}: '{port_name}' is not an output port")
        binding = self.bindings.get(port_name)
        if not isinstance(binding, Ref):
            return False
        try:
            self.blackboard.set(binding.key, value)
        except ValueError as e:  # text that the entry's type cannot hold
            raise PortError(f"{self.describe()}: output port '{port_name}': {e}") from None
        return True

    def _set_output(self, port_name: str, value: Any) -> None:
        self.set_output(port_name, value)

    # ------------------------------------------------------------------ ticking

    def describe(self) -> str:
        where = f" (line {self.xml_line})" if self.xml_line else ""
        name = f" '{self.name}'" if self.name != self.NODE_ID else ""
        return f"{self.NODE_ID}{name}{where}"

    def now(self) -> float:
        """Current time of the tree's clock, in seconds."""
        return self.context.clock.now()

    def _run_script(self, key: str, script: Script) -> Any:
        try:
            return script.run(self.blackboard)
        except ScriptRuntimeError as e:
            raise TreeRuntimeError(f"{self.describe()}: {key}=\"{script.code}\": {e}") from None

    def _check_preconditions(self) -> NodeStatus | None:
        state = self.bt_status
        for key, script in self._pre:
            if state is NodeStatus.IDLE or state is NodeStatus.SKIPPED:
                value = _truth(self, key, script)
                if value:
                    if key == "_failureIf":
                        return NodeStatus.FAILURE
                    if key == "_successIf":
                        return NodeStatus.SUCCESS
                    if key == "_skipIf":
                        return NodeStatus.SKIPPED
                elif key == "_while":
                    return NodeStatus.SKIPPED
            elif (state is NodeStatus.RUNNING and key == "_while"
                  and not _truth(self, key, script)):
                self.halt_node()
                return NodeStatus.SKIPPED
        return None

    def execute_tick(self) -> NodeStatus:
        """Tick this node once, BT.CPP style; returns the status it reports to its parent."""
        if self.bt_status is _IDLE:
            self.started_order = next(_ORDER)
        new = self._check_preconditions() if self._pre else None
        if new is None and self.pre_tick is not None and not self.bt_status.completed:
            forced = self.pre_tick(self)
            if forced is _SUCCESS or forced is _FAILURE:
                new = forced
        if new is None:
            new = self.tick_node()
        post = self._post
        if post and (new is _SUCCESS or new is _FAILURE):
            if new is _SUCCESS and "_onSuccess" in post:
                self._run_script("_onSuccess", post["_onSuccess"])
            elif new is _FAILURE and "_onFailure" in post:
                self._run_script("_onFailure", post["_onFailure"])
            if "_post" in post:
                self._run_script("_post", post["_post"])
        self.last_status = new
        if new is _FAILURE:
            self.failure_order = next(_ORDER)
        if new is not _SKIPPED:
            self.bt_status = new
            self.status = _PY_BY_ID[id(new)]
        context = self.context
        visited = context.visited
        if visited is not None:  # for py_trees tools: the nodes that ran in this tick
            visited.append(self)
        if context.observer is not None:
            context.observer.result(self, new)
        return new

    def tick_node(self) -> NodeStatus:
        """The node's own logic for one tick (BT.CPP's ``tick()``)."""
        raise NotImplementedError

    def emit_wake_up(self) -> None:
        """Ask the tree to tick again from the root within the same ``Tree.tick()``.

        BT.CPP's ``emitWakeUpSignal()``: a node that returns RUNNING only to keep the tree
        interruptible (a SequenceWithMemory whose child finished at once, a Repeat between two
        cycles) emits it, and ``Tree.tick()`` re-ticks the root while one is pending.
        """
        self.context.wake_up = True

    def halt(self) -> None:
        """Stop the node's activity and make it IDLE (BT.CPP's ``halt()``)."""
        self.reset_status()

    def halt_node(self) -> None:
        """Halt, then run the ``_onHalted`` script if any."""
        observer = self.context.observer
        if observer is not None and self.bt_status is NodeStatus.RUNNING:
            observer.halted(self)
        self.halt()
        script = self._post.get("_onHalted") if self._post else None
        if script is not None:
            self._run_script("_onHalted", script)

    def set_running(self) -> None:
        """Mark the node RUNNING (as a control or decorator does before ticking a child)."""
        self.bt_status = NodeStatus.RUNNING
        self.status = _RUNNING

    def reset_status(self) -> None:
        """Make the node IDLE. py_trees' ``status`` keeps a finished node's SUCCESS or FAILURE
        for py_trees tools (``py_trees.display``) until the next ``Tree.tick()`` clears it."""
        self.bt_status = NodeStatus.IDLE
        if self.status is _RUNNING:
            self.status = Status.INVALID

    def tick(self) -> Any:
        """py_trees' generator protocol, for py_trees tools (``py_trees.trees.BehaviourTree``).

        The root of a :class:`~bt_manip.bt.tree.Tree` runs one ``Tree.tick()`` and yields every
        node that ran in it, children before parents, the root last; another node runs one
        tick of itself and yields itself.
        """
        tree = self.context.tree
        if tree is not None and tree.root is self:
            tree.tick()
            yield from tree.visited_nodes()
            return
        self.execute_tick()
        yield self

    def stop(self, new_status: Status = Status.INVALID) -> None:
        """py_trees' stop: for INVALID, halt a RUNNING node (BT.CPP semantics)."""
        if new_status == Status.INVALID:
            if self.bt_status is NodeStatus.RUNNING:
                self.halt_node()
            self.reset_status()
            self.status = Status.INVALID
        else:
            self.status = new_status
            self.bt_status = STATUS_OF_PY_TREES[new_status]

    def bt_children(self) -> list[BtNode]:
        """The node's children (the list itself: read it, do not change it). The children of a
        bt-manip node are bt-manip nodes (the XML loader and ``as_bt_node`` build them)."""
        return cast("list[BtNode]", self.children)


_ABSTRACT_FLAG = "_bt_ports_abstract"


def _class_is_abstract(cls: type) -> bool:
    """py_trees' ``_ports_class_is_abstract(cls)``, computed at the first construction of
    ``cls`` and kept in the class's own namespace (so a subclass never reads its parent's
    answer, and the cache holds one flag per class, no more)."""
    flag = cls.__dict__.get(_ABSTRACT_FLAG)
    if flag is None:
        flag = _ports_class_is_abstract(cls)
        setattr(cls, _ABSTRACT_FLAG, flag)
    return bool(flag)


def _truth(node: BtNode, key: str, script: Script) -> bool:
    value = node._run_script(key, script)
    try:
        return to_bool(value)
    except ScriptRuntimeError as e:
        raise TreeRuntimeError(f"{node.describe()}: {key}=\"{script.code}\": {e}") from None


class LeafNode(BtNode, py_trees.behaviour.Behaviour):
    """A leaf: its ``update()`` decides its status, as in py_trees.

    ``initialise()`` runs when the node starts (it was not RUNNING), ``terminate(status)`` once
    when it finishes (SUCCESS/FAILURE) or is halted while RUNNING (INVALID).

    A ``STATEFUL`` leaf follows BT.CPP's ``StatefulActionNode``: it starts only from IDLE, so
    when its parent ticks it again after it finished without resetting it (a WhileDoElse
    condition while a branch runs, an IfThenElse condition after it failed), it returns the
    status it finished with and runs nothing. Other leaves (BT.CPP's ``SyncActionNode`` and
    ``ConditionNode``) run at every tick.
    """

    STATEFUL: ClassVar[bool] = False

    def __init__(self, name: str | None = None, **attributes: Any) -> None:
        super().__init__(name or self.NODE_ID)
        self._init_node(attributes)

    def tick_node(self) -> NodeStatus:
        if self.status != _RUNNING:
            if self.STATEFUL and self.bt_status is not NodeStatus.IDLE:
                return self.bt_status
            self.initialise()
        result = self.update()
        status = _LEAF_RESULT.get(id(result))
        if status is None:
            raise TreeRuntimeError(f"{self.describe()}: update() returned {result!r}")
        if result is not _RUNNING:
            self.terminate(result)
        self.status = result
        return status

    def halt(self) -> None:
        if self.status == _RUNNING:
            self.terminate(Status.INVALID)
        self.reset_status()


class ActionNode(LeafNode):
    """Base class for actions (leaves that act; may return RUNNING).

    Actions are stateful (BT.CPP's ``StatefulActionNode``, see :class:`LeafNode`): ticked again
    after they finished, without a reset in between, they return the same status.
    """

    KIND = "Action"
    STATEFUL = True


class SyncActionNode(ActionNode):
    """Base class for actions that finish within their tick (BT.CPP's ``SyncActionNode``).

    They never return RUNNING and run again at every tick, even when not reset.
    """

    STATEFUL = False


class ConditionNode(LeafNode):
    """Base class for conditions (leaves that check; return SUCCESS or FAILURE)."""

    KIND = "Condition"


class ControlNode(BtNode, py_trees.composites.Composite):
    """A node with one or more children that decides which to tick (BT.CPP ``ControlNode``)."""

    KIND = "Control"
    MIN_CHILDREN = 1
    MAX_CHILDREN: ClassVar[int | None] = None

    def __init__(
        self, name: str | None = None, children: list[BtNode] | None = None, **attributes: Any
    ) -> None:
        kids = [as_bt_node(c) for c in children or []]
        super().__init__(name or self.NODE_ID, children=kids)
        self._init_node(attributes)
        self._check_children()

    def _check_children(self) -> None:
        n = len(self.children)
        if n < self.MIN_CHILDREN or (self.MAX_CHILDREN is not None and n > self.MAX_CHILDREN):
            raise ValueError(f"{self.NODE_ID}: {children_rule(type(self))}, got {n}")

    def halt_child(self, index: int) -> None:
        child = cast(BtNode, self.children[index])  # a bt-manip node's children are BtNodes
        if child.bt_status is NodeStatus.RUNNING:
            child.halt_node()
        child.reset_status()

    def reset_children(self) -> None:
        for index in range(len(self.children)):
            self.halt_child(index)

    def halt(self) -> None:
        self.reset_children()
        self.reset_status()

    def update(self) -> Status:  # not used: tick_node holds the logic
        return self.status


class DecoratorNode(BtNode, py_trees.decorators.Decorator):
    """A node with exactly one child (BT.CPP ``DecoratorNode``).

    After each tick, a child that finished (SUCCESS/FAILURE) is reset to IDLE, as in BT.CPP.
    """

    KIND = "Decorator"
    MIN_CHILDREN = 1
    MAX_CHILDREN = 1

    def __init__(
        self, name: str | None = None, child: BtNode | None = None, **attributes: Any
    ) -> None:
        if child is None:
            raise ValueError(f"{self.NODE_ID}: {children_rule(type(self))}, got 0")
        super().__init__(name or self.NODE_ID, as_bt_node(child))
        self._init_node(attributes)

    @property
    def child(self) -> BtNode:
        return cast(BtNode, self.decorated)  # the child of a bt-manip node is a BtNode

    def execute_tick(self) -> NodeStatus:
        status = BtNode.execute_tick(self)
        child = self.child
        if child.bt_status is NodeStatus.SUCCESS or child.bt_status is NodeStatus.FAILURE:
            child.reset_status()
        return status

    def reset_child(self) -> None:
        child = self.child
        if child.bt_status is NodeStatus.RUNNING:
            child.halt_node()
        child.reset_status()

    def halt(self) -> None:
        self.reset_child()
        self.reset_status()

    def update(self) -> Status:
        return self.status


class ChildCounts(Protocol):
    """What :func:`children_rule` reads: a node class, or a model's numbers."""

    @property
    def MIN_CHILDREN(self) -> int: ...

    @property
    def MAX_CHILDREN(self) -> int | None: ...


def children_rule(cls: ChildCounts) -> str:
    lo, hi = cls.MIN_CHILDREN, cls.MAX_CHILDREN
    if hi == 0:
        return "is a leaf and takes no children"
    if lo == hi:
        return f"must have exactly {lo} child" + ("" if lo == 1 else "ren")
    if hi is None:
        return f"must have at least {lo} child" + ("" if lo == 1 else "ren")
    return f"must have {lo} to {hi} children"


def as_bt_node(node: Any) -> BtNode:
    """``node`` itself, or a plain py_trees behaviour (or whole py_trees tree) converted by the
    py_trees adapter (:mod:`bt_manip.bt.py_trees_hook`)."""
    if isinstance(node, BtNode) or not isinstance(node, py_trees.behaviour.Behaviour):
        return node
    return py_trees_hook.adapter().convert_node(node)
