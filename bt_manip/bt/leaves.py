"""BehaviorTree.CPP v4 built-in leaves: constants, scripts, blackboard edits and Sleep."""

from __future__ import annotations

from typing import Any, ClassVar

from py_trees.common import Status
from py_trees.ports import PortInformation

from bt_manip.bt.blackboard import EntryTypeError
from bt_manip.bt.decorators import TIME_EPS, _ScriptHolder
from bt_manip.bt.node import (
    ActionNode,
    ConditionNode,
    PortError,
    SyncActionNode,
    TreeRuntimeError,
    _truth,
)
from bt_manip.bt.ports import NON_NEGATIVE, InOutPortInformation, Literal, Port, Ref, type_name
from bt_manip.bt.registry import registry
from bt_manip.bt.script import to_text

Ports = dict[str, PortInformation]


@registry.register(builtin=True)
class AlwaysSuccess(SyncActionNode):
    """Returns SUCCESS."""

    def update(self) -> Status:
        return Status.SUCCESS


@registry.register(builtin=True)
class AlwaysFailure(SyncActionNode):
    """Returns FAILURE."""

    def update(self) -> Status:
        return Status.FAILURE


@registry.register(builtin=True)
class Script(SyncActionNode):
    """Runs the script ``code`` on the blackboard and returns SUCCESS."""

    INPUT_PORTS: Ports = {
        "code": PortInformation(str, description="script to run")}
    SCRIPT_PORTS = ("code",)

    def __init__(self, name: str | None = None, **attributes: Any) -> None:
        super().__init__(name, **attributes)
        self._holder = _ScriptHolder()

    def update(self) -> Status:
        script = self._holder.get(self, "code")
        self._run_script("code", script)
        return Status.SUCCESS


@registry.register(builtin=True)
class ScriptCondition(ConditionNode):
    """Evaluates the script ``code``: SUCCESS if its value is true, FAILURE otherwise."""

    INPUT_PORTS: Ports = {
        "code": PortInformation(
            object, description="Piece of code that can be parsed. Must return false or true")}
    SCRIPT_PORTS = ("code",)

    def __init__(self, name: str | None = None, **attributes: Any) -> None:
        super().__init__(name, **attributes)
        self._holder = _ScriptHolder()

    def update(self) -> Status:
        script = self._holder.get(self, "code")
        return Status.SUCCESS if _truth(self, "code", script) else Status.FAILURE


@registry.register(builtin=True)
class SetBlackboard(SyncActionNode):
    """Writes ``value`` into the entry named by ``output_key``; returns SUCCESS.

    ``value`` is text, or a reference ``{other}`` whose value is copied (FAILURE when that
    entry has no value). Text written into an entry of another type is converted to it (an
    error if it cannot be). ``output_key`` is the name of the entry; as in BT.CPP, a reference
    ``{key}`` there names the entry whose *value* is the name to write to.
    """

    INPUT_PORTS: dict[str, PortInformation] = {
        "value": PortInformation(
            object, description="Value to be written into the output_key"),
        "output_key": InOutPortInformation(
            object, description="Name of the blackboard entry where the value should be "
                                "written"),
    }

    def update(self) -> Status:
        bb = self.blackboard
        key_binding = self.bindings["output_key"]
        if isinstance(key_binding, Ref):
            try:
                key = to_text(bb.get(key_binding.key))
            except KeyError:
                raise TreeRuntimeError(
                    f"{self.describe()}: output_key reads the entry name from "
                    f"'{key_binding.key}', which has no value") from None
        else:
            key = str(key_binding.value)
        value_binding = self.bindings["value"]
        if isinstance(value_binding, Literal):
            value = value_binding.value
        else:
            source = value_binding.key
            if not bb.exists(source):
                raise TreeRuntimeError(
                    f"{self.describe()}: value refers to entry '{source}', "
                    "which does not exist") from None
            if not bb.exists(key):  # created with the source entry's type
                source_type = bb.strong_type(source)
                bb.declare(key, bb.entry_type(source) if source_type else object, source_type)
            if not bb.has_value(source):
                self.feedback_message = f"entry '{source}' has no value to copy"
                return Status.FAILURE
            value = bb.get(source)
            held = bb.strong_type(key)
            given = type_name(type(value))
            if (held is not None and held != "std::string" and type(value) is not str
                    and given != held):
                raise TreeRuntimeError(
                    f"{self.describe()}: entry [{key}] holds a {held}; copying a {given} from "
                    f"'{source}' would change its type (BT.CPP: once declared, the type of "
                    "an entry shall not change)")
        try:
            bb.assign(key, value)
        except EntryTypeError as e:
            raise TreeRuntimeError(f"{self.describe()}: {e}") from None
        return Status.SUCCESS


@registry.register(builtin=True)
class UnsetBlackboard(SyncActionNode):
    """Removes the entry ``key`` of this tree's blackboard (if present); returns SUCCESS.

    As in BT.CPP, ``key="{other}"`` removes the entry named by the value of ``other``, and an
    entry a SubTree shares with its parent is not removed from the parent.
    """

    INPUT_PORTS: Ports = {
        "key": PortInformation(str, description="name of the entry to remove")}

    def update(self) -> Status:
        self.blackboard.unset(str(self.get_input("key")))
        return Status.SUCCESS


@registry.register(builtin=True)
class Sleep(ActionNode):
    """Returns RUNNING until ``msec`` milliseconds of the tree's clock have passed, then SUCCESS.

    The first tick always returns RUNNING (SUCCESS at once when ``msec`` is 0). Its timer
    emits the wake-up signal when the time is up (at the start of the next tick, see
    ``TreeContext.start_timer``). Halting it cancels the wait; the next start waits the full
    time again. A negative ``msec`` is refused at load; read from the blackboard, it makes the
    node fail with the reason.
    """

    INPUT_PORTS: Ports = {
        "msec": Port(int, description="", accepts=NON_NEGATIVE)}
    PORT_TYPE_NAMES: ClassVar[dict[str, str]] = {"msec": "unsigned int"}

    def initialise(self) -> None:
        self._start_time = self.now()
        self._first = True
        self._timer: int | None = None

    def update(self) -> Status:
        try:
            msec = self.get_input("msec")
        except PortError as e:  # a blackboard value it cannot take
            self.feedback_message = str(e)
            return Status.FAILURE
        if self._first:
            self._first = False
            if msec <= 0:
                return Status.SUCCESS
            self._timer = self.context.start_timer(msec / 1000.0)
            return Status.RUNNING
        elapsed = self.now() - self._start_time
        if elapsed >= msec / 1000.0 - TIME_EPS:
            return Status.SUCCESS
        return Status.RUNNING

    def terminate(self, new_status: Status) -> None:
        self.context.cancel_timer(getattr(self, "_timer", None))
