"""BehaviorTree.CPP v4 decorators (one child each), with BT.CPP's semantics.

Durations (Timeout, Delay) read the tree's clock (``TreeContext.clock``): the simulation clock
when a world is loaded, so they are deterministic and as fast as physics allows.
"""

from __future__ import annotations

from typing import Any, ClassVar, cast

from py_trees.ports import PortInformation

from bt_manip.bt.context import TIME_EPS
from bt_manip.bt.node import BtNode, DecoratorNode, PortError, TreeRuntimeError, _truth
from bt_manip.bt.ports import NON_NEGATIVE, Port, Ref
from bt_manip.bt.registry import registry
from bt_manip.bt.script import Script, ScriptSyntaxError, parse_script
from bt_manip.bt.status import NodeStatus

IDLE = NodeStatus.IDLE
RUNNING = NodeStatus.RUNNING
SUCCESS = NodeStatus.SUCCESS
FAILURE = NodeStatus.FAILURE
SKIPPED = NodeStatus.SKIPPED


@registry.register(builtin=True)
class Inverter(DecoratorNode):
    """Child SUCCESS gives FAILURE and FAILURE gives SUCCESS; RUNNING and SKIPPED pass through."""

    def tick_node(self) -> NodeStatus:
        self.set_running()
        status = self.child.execute_tick()
        if status is SUCCESS:
            self.reset_child()
            return FAILURE
        if status is FAILURE:
            self.reset_child()
            return SUCCESS
        return status


class _Force(DecoratorNode):
    RESULT = SUCCESS

    def tick_node(self) -> NodeStatus:
        self.set_running()
        status = self.child.execute_tick()
        if status.completed:
            self.reset_child()
            return self.RESULT
        return status


@registry.register(builtin=True)
class ForceSuccess(_Force):
    """Returns SUCCESS when the child finishes (SUCCESS or FAILURE); RUNNING passes through."""


@registry.register(builtin=True)
class ForceFailure(_Force):
    """Returns FAILURE when the child finishes (SUCCESS or FAILURE); RUNNING passes through."""

    RESULT = FAILURE


@registry.register(builtin=True)
class Repeat(DecoratorNode):
    """Ticks the child up to ``num_cycles`` times in a row (-1: forever) while it succeeds.

    A child that started and succeeded within this tick, with cycles left, makes it return
    RUNNING and ask for a wake-up: ``Tree.tick()`` ticks the root again at once, so the cycles
    still run within one tree tick but reactive parents re-check their conditions in between.
    A RUNNING child returns RUNNING and the loop resumes at the next tick. A child FAILURE stops
    the loop and returns FAILURE; after ``num_cycles`` successes the node returns SUCCESS. A
    SKIPPED child makes the node SKIPPED (the count is kept).
    """

    INPUT_PORTS: dict[str, PortInformation] = {
        "num_cycles": PortInformation(
            int, description="repeat a successful child N times; -1 repeats forever"),
    }

    def __init__(self, name: str | None = None, child: BtNode | None = None,
                 **attributes: Any) -> None:
        super().__init__(name, child, **attributes)
        self.count = 0

    def tick_node(self) -> NodeStatus:
        cycles = self.get_input("num_cycles")
        loop = self.count < cycles or cycles == -1
        self.set_running()
        while loop:
            child = self.child
            before = child.bt_status
            status = child.execute_tick()
            if status is SUCCESS:
                self.count += 1
                loop = self.count < cycles or cycles == -1
                self.reset_child()
                if before is IDLE and loop:
                    self.emit_wake_up()
                    return RUNNING
            elif status is FAILURE:
                self.count = 0
                self.reset_child()
                return FAILURE
            elif status is RUNNING:
                return RUNNING
            else:
                self.reset_child()
                return SKIPPED
        self.count = 0
        return SUCCESS

    def halt(self) -> None:
        self.count = 0
        super().halt()


@registry.register(builtin=True)
class RetryUntilSuccessful(DecoratorNode):
    """Ticks the child again after a FAILURE, up to ``num_attempts`` times (-1: forever).

    A child that started and failed within this tick, with attempts left, makes it return
    RUNNING and ask for a wake-up (``Tree.tick()`` ticks the root again at once, so the retries
    still happen within one tree tick); a RUNNING child returns RUNNING. Child SUCCESS returns
    SUCCESS; after ``num_attempts`` failures the node returns FAILURE. A SKIPPED child makes
    the node SKIPPED.
    """

    INPUT_PORTS: dict[str, PortInformation] = {
        "num_attempts": PortInformation(
            int, description="try the child up to N times; -1 tries forever"),
    }

    def __init__(self, name: str | None = None, child: BtNode | None = None,
                 **attributes: Any) -> None:
        super().__init__(name, child, **attributes)
        self.tries = 0

    def tick_node(self) -> NodeStatus:
        attempts = self.get_input("num_attempts")
        loop = self.tries < attempts or attempts == -1
        self.set_running()
        while loop:
            child = self.child
            before = child.bt_status
            status = child.execute_tick()
            if status is SUCCESS:
                self.tries = 0
                self.reset_child()
                return SUCCESS
            if status is FAILURE:
                self.tries += 1
                attempts = self.get_input("num_attempts")
                loop = self.tries < attempts or attempts == -1
                self.reset_child()
                if before is IDLE and loop:
                    self.emit_wake_up()
                    return RUNNING
            elif status is RUNNING:
                return RUNNING
            else:
                self.reset_child()
                return SKIPPED
        self.tries = 0
        return FAILURE

    def halt(self) -> None:
        self.tries = 0
        super().halt()


@registry.register(builtin=True)
class KeepRunningUntilFailure(DecoratorNode):
    """Returns RUNNING while the child succeeds or runs (restarting it), FAILURE when it fails."""

    def tick_node(self) -> NodeStatus:
        self.set_running()
        status = self.child.execute_tick()
        if status is FAILURE:
            self.reset_child()
            return FAILURE
        if status is SUCCESS:
            self.reset_child()
        return RUNNING


@registry.register(builtin=True)
class Timeout(DecoratorNode):
    """Halts the child and returns FAILURE when it has been RUNNING for ``msec`` milliseconds.

    The time starts at the first tick; a child that finishes earlier returns its status. With
    ``msec`` 0 there is no time limit. As BT.CPP's timer thread does, the timer halts the child
    (and emits the wake-up signal) when it fires, at the start of the tick after the time ran
    out; that tick the node returns FAILURE. A negative ``msec`` is refused at load; read from
    the blackboard, it makes the node fail (halting the child) with the reason.
    """

    INPUT_PORTS: dict[str, PortInformation] = {
        "msec": Port(
            int, description="After a certain amount of time, halt() the child if it is still "
                             "running.", accepts=NON_NEGATIVE),
    }
    PORT_TYPE_NAMES: ClassVar[dict[str, str]] = {"msec": "unsigned int"}

    def __init__(self, name: str | None = None, child: BtNode | None = None,
                 **attributes: Any) -> None:
        super().__init__(name, child, **attributes)
        self._started = False
        self._child_halted = False
        self._timer: int | None = None
        self._msec = 0

    def _on_timeout(self) -> None:
        if self.child.bt_status is RUNNING:
            self._child_halted = True
            self.reset_child()
            self.feedback_message = f"timed out after {self._msec} ms"

    def tick_node(self) -> NodeStatus:
        try:
            msec = self.get_input("msec")
        except PortError as e:  # a blackboard value it cannot take
            self.reset_child()
            self._started = False
            self.feedback_message = str(e)
            return FAILURE
        if not self._started:
            self._started = True
            self.set_running()
            self._child_halted = False
            self._msec = msec
            if msec > 0:
                self._timer = self.context.start_timer(msec / 1000.0, self._on_timeout)
        if self._child_halted:
            self._started = False
            return FAILURE
        status = self.child.execute_tick()
        if status.completed:
            self._started = False
            self.context.cancel_timer(self._timer)
            self.reset_child()
        return status

    def halt(self) -> None:
        self._started = False
        self.context.cancel_timer(self._timer)
        super().halt()


@registry.register(builtin=True)
class Delay(DecoratorNode):
    """Waits ``delay_msec`` milliseconds (returning RUNNING), then ticks the child.

    The wait starts at the first tick, which always returns RUNNING (even with 0 ms: BT.CPP
    starts a timer there and looks at it again at the next tick). Once the time has passed,
    the child is ticked and its status returned; the next start waits again. A negative
    ``delay_msec`` is refused at load (an unsigned int in BT.CPP).
    """

    INPUT_PORTS: dict[str, PortInformation] = {
        "delay_msec": Port(
            int, description="Tick the child after a few milliseconds", accepts=NON_NEGATIVE),
    }
    PORT_TYPE_NAMES: ClassVar[dict[str, str]] = {"delay_msec": "unsigned int"}

    def __init__(self, name: str | None = None, child: BtNode | None = None,
                 **attributes: Any) -> None:
        super().__init__(name, child, **attributes)
        self._started = False
        self._start_time = 0.0
        self._timer: int | None = None

    def tick_node(self) -> NodeStatus:
        try:
            delay = self.get_input("delay_msec")
        except PortError as e:  # a blackboard value it cannot take
            self._started = False
            self.feedback_message = str(e)
            return FAILURE
        if not self._started:
            self._started = True
            self.set_running()
            self._start_time = self.now()
            self._timer = self.context.start_timer(delay / 1000.0)
            return RUNNING
        if self.now() - self._start_time >= delay / 1000.0 - TIME_EPS:
            status = self.child.execute_tick()
            if status.completed:
                self._started = False
                self.reset_child()
            return status
        return RUNNING

    def halt(self) -> None:
        self._started = False
        self.context.cancel_timer(self._timer)
        super().halt()


@registry.register(builtin=True)
class RunOnce(DecoratorNode):
    """Ticks the child until it finishes once; afterwards never ticks it again.

    After that first run the node is SKIPPED if ``then_skip`` is true (default), otherwise it
    returns the child's remembered status forever.
    """

    INPUT_PORTS: dict[str, PortInformation] = {
        "then_skip": PortInformation(
            bool, required=False, default_value=True,
            description="if true, skip after the first execution, otherwise return the "
                        "status the child returned then"),
    }

    def __init__(self, name: str | None = None, child: BtNode | None = None,
                 **attributes: Any) -> None:
        super().__init__(name, child, **attributes)
        self._done = False
        self._returned = NodeStatus.IDLE

    def tick_node(self) -> NodeStatus:
        try:  # BT.CPP: true unless the port gives a bool (no value, or text that is none)
            skip = self.get_input("then_skip", True)
        except PortError:
            skip = True
        if self._done:
            return SKIPPED if skip else self._returned
        self.set_running()
        status = self.child.execute_tick()
        if status.completed:
            self._done = True
            self._returned = status
            self.reset_child()
        return status


class _ScriptHolder:
    """Parses a script port once, or again when a referenced script text changes."""

    def __init__(self) -> None:
        self._text: str | None = None
        self._script: Script | None = None

    def get(self, node: BtNode, port: str) -> Script:
        binding = node.bindings.get(port)
        if not isinstance(binding, Ref):
            return cast(Script, node.get_input(port))  # a script port's literal is parsed
        text = str(node.get_input(port))
        if text != self._text or self._script is None:
            try:
                self._script = parse_script(text)
            except ScriptSyntaxError as e:
                raise TreeRuntimeError(
                    f"{node.describe()}: script in '{port}' (column {e.column}): {e.message}"
                ) from None
            self._text = text
        return self._script


@registry.register(builtin=True)
class Precondition(DecoratorNode):
    """Ticks the child only if the script ``if`` is true; otherwise returns ``else``.

    The condition is evaluated when the child is not already running; once the child started
    it is ticked until it finishes, then the node returns the child's status.
    """

    INPUT_PORTS: dict[str, PortInformation] = {
        "if": PortInformation(str, description="script: the condition"),
        "else": PortInformation(
            NodeStatus, required=False, default_value=NodeStatus.FAILURE,
            description="status returned when the condition is false"),
    }
    SCRIPT_PORTS = ("if",)

    def __init__(self, name: str | None = None, child: BtNode | None = None,
                 **attributes: Any) -> None:
        super().__init__(name, child, **attributes)
        self._child_running = False
        self._script = _ScriptHolder()

    def tick_node(self) -> NodeStatus:
        otherwise = self.get_input("else")
        if not self._child_running:
            script = self._script.get(self, "if")
            self._child_running = _truth(self, "if", script)
        if not self._child_running:
            return cast(NodeStatus, otherwise)  # the "else" port holds a NodeStatus
        status = self.child.execute_tick()
        if status.completed:
            self.reset_child()
            self._child_running = False
        return status

    def halt(self) -> None:
        self._child_running = False
        super().halt()
