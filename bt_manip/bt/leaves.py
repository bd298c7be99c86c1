"""BehaviorTree.CPP v4 built-in leaves: constants, scripts, blackboard edits and Sleep."""

from __future__ import annotations

from typing import Any, ClassVar

from py_trees.common import Status
from py_trees.ports import PortInformation

from bt_manip.bt.decorators import TIME_EPS, _ScriptHolder
from bt_manip.bt.node import ActionNode, ConditionNode, PortError, TreeRuntimeError, _truth
from bt_manip.bt.ports import NON_NEGATIVE, InOutPortInformation, Literal, Port, Ref
from bt_manip.bt.registry import registry

Ports = dict[str, PortInformation]


@registry.register(builtin=True)
class AlwaysSuccess(ActionNode):
    """Returns SUCCESS."""

    def update(self) -> Status:
        return Status.SUCCESS


@registry.register(builtin=True)
class AlwaysFailure(ActionNode):
    """Returns FAILURE."""

    def update(self) -> Status:
        return Status.FAILURE


@registry.register(builtin=True)
class Script(ActionNode):
    """Runs the script ``code`` on the blackboard and returns SUCCESS."""

    INPUT_PORTS: ClassVar[Ports] = {"code": PortInformation(str, description="script to run")}
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

    INPUT_PORTS: ClassVar[Ports] = {
        "code": PortInformation(str, description="script whose value is the result")}
    SCRIPT_PORTS = ("code",)

    def __init__(self, name: str | None = None, **attributes: Any) -> None:
        super().__init__(name, **attributes)
        self._holder = _ScriptHolder()

    def update(self) -> Status:
        script = self._holder.get(self, "code")
        return Status.SUCCESS if _truth(self, "code", script) else Status.FAILURE


@registry.register(builtin=True)
class SetBlackboard(ActionNode):
    """Writes ``value`` into the entry named by ``output_key``; returns SUCCESS.

    ``value`` may be text or a reference ``{other}`` (the other entry's value is copied).
    ``output_key`` is the name of the entry (a reference ``{key}`` names the entry ``key``).
    """

    INPUT_PORTS: ClassVar[dict[str, PortInformation]] = {
        "value": PortInformation(str, description="value to write (text, or {key} to copy)"),
        "output_key": InOutPortInformation(str, description="name of the entry to write"),
    }

    def update(self) -> Status:
        key_binding = self.bindings["output_key"]
        key = key_binding.key if isinstance(key_binding, Ref) else str(key_binding.value)
        value_binding = self.bindings["value"]
        if isinstance(value_binding, Literal):
            value = value_binding.value
        else:
            try:
                value = self.blackboard.get(value_binding.key)
            except KeyError:
                raise TreeRuntimeError(
                    f"{self.describe()}: value refers to entry '{value_binding.key}', "
                    "which does not exist") from None
        self.blackboard.set(key, value)
        return Status.SUCCESS


@registry.register(builtin=True)
class UnsetBlackboard(ActionNode):
    """Removes the entry ``key`` from the blackboard (if present); returns SUCCESS."""

    INPUT_PORTS: ClassVar[Ports] = {
        "key": PortInformation(str, description="name of the entry to remove")}

    def update(self) -> Status:
        binding = self.bindings["key"]
        key = binding.key if isinstance(binding, Ref) else str(self.get_input("key"))
        self.blackboard.unset(key)
        return Status.SUCCESS


@registry.register(builtin=True)
class Sleep(ActionNode):
    """Returns RUNNING until ``msec`` milliseconds of the tree's clock have passed, then SUCCESS.

    The first tick always returns RUNNING (SUCCESS at once when ``msec`` is 0). Halting it
    stops the wait; the next start waits the full time again. A negative ``msec`` is refused
    at load; read from the blackboard, it makes the node fail with the reason.
    """

    INPUT_PORTS: ClassVar[Ports] = {
        "msec": Port(int, description="milliseconds to wait", accepts=NON_NEGATIVE)}

    def initialise(self) -> None:
        self._start_time = self.now()
        self._first = True

    def update(self) -> Status:
        try:
            msec = self.get_input("msec")
        except PortError as e:  # a blackboard value it cannot take
            self.feedback_message = str(e)
            return Status.FAILURE
        if self._first:
            self._first = False
            return Status.SUCCESS if msec <= 0 else Status.RUNNING
        elapsed = self.now() - self._start_time
        if elapsed >= msec / 1000.0 - TIME_EPS:
            return Status.SUCCESS
        return Status.RUNNING
