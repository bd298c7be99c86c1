"""Nav2's condition nodes on goals and result codes."""

from __future__ import annotations

from typing import Any, ClassVar, Protocol, cast

from py_trees.common import Status
from py_trees.ports import PortInformation

from bt_manip.bt.node import ConditionNode
from bt_manip.bt.registry import registry
from bt_manip.bt.status import NodeStatus
from bt_manip.nav2.errors import (
    CONTROLLER_RECOVERABLE,
    PLANNER_RECOVERABLE,
    SMOOTHER_RECOVERABLE,
)


def _codes(text: Any) -> frozenset[int]:
    """Error codes given as a list or as text (``"100,104"`` or ``"100;104"``)."""
    if isinstance(text, (list, tuple, set, frozenset)):
        return frozenset(int(v) for v in text)
    parts = str(text).replace(";", ",").split(",")
    return frozenset(int(p) for p in parts if p.strip())


@registry.register
class AreErrorCodesPresent(ConditionNode):
    """SUCCESS when ``error_code`` is one of ``error_codes_to_check``, FAILURE otherwise."""

    INPUT_PORTS: dict[str, PortInformation] = {
        "error_code": PortInformation(int, False, "The active error code to compare against", 0),
        "error_codes_to_check": PortInformation(
            str, False, "Error codes to check, separated by commas", ""
        ),
    }

    def codes(self) -> frozenset[int]:
        return _codes(self.get_input("error_codes_to_check"))

    def update(self) -> Status:
        code = self.get_input("error_code", 0)
        present = code is not None and int(code) in self.codes()
        self.feedback_message = "" if present else f"error code {code} is not one to recover from"
        return Status.SUCCESS if present else Status.FAILURE


class _WouldARecoveryHelp(AreErrorCodesPresent):
    """SUCCESS when ``error_code`` is one of the fixed codes ``CODES``, FAILURE otherwise.
    ``error_codes_to_check`` is accepted (current Nav2 declares it) but, as in Nav2, the fixed
    codes are the ones checked."""

    CODES: ClassVar[frozenset[Any]] = frozenset()

    def codes(self) -> frozenset[int]:
        return frozenset(int(c) for c in self.CODES)


@registry.register
class WouldAPlannerRecoveryHelp(_WouldARecoveryHelp):
    """SUCCESS when ``error_code`` is a planner failure that a recovery may cure (200 UNKNOWN,
    207 TIMEOUT, 208 NO_VALID_PATH), FAILURE otherwise."""

    CODES = PLANNER_RECOVERABLE


@registry.register
class WouldAControllerRecoveryHelp(_WouldARecoveryHelp):
    """SUCCESS when ``error_code`` is a controller failure that a recovery may cure (100 UNKNOWN,
    104 PATIENCE_EXCEEDED, 105 FAILED_TO_MAKE_PROGRESS, 106 NO_VALID_CONTROL), FAILURE
    otherwise."""

    CODES = CONTROLLER_RECOVERABLE


@registry.register
class WouldASmootherRecoveryHelp(_WouldARecoveryHelp):
    """SUCCESS when ``error_code`` is a smoother failure that a recovery may cure (500 UNKNOWN,
    502 TIMEOUT, 503 SMOOTHED_PATH_IN_COLLISION, 504 FAILED_TO_SMOOTH_PATH), FAILURE
    otherwise."""

    CODES = SMOOTHER_RECOVERABLE


GOAL_PORTS: dict[str, PortInformation] = {
    "goal": PortInformation(object, False, "Destination (default: the entry 'goal')"),
    "goals": PortInformation(object, False, "Destinations (default: the entry 'goals')"),
}


class _PortReader(Protocol):
    """What :class:`GoalsReader` uses of the node class it is mixed into (a ``BtNode``)."""

    def get_input(self, port_name: str, default: Any = ...) -> Any: ...


class GoalsReader:
    """Mixin: the goals now, from the ports ``goal`` and ``goals`` or, when a port is not
    given, from the blackboard entries of the same names (Nav2's ``getInputOrBlackboard``)."""

    DEFAULT_KEYS: ClassVar[tuple[str, ...]] = ("goal", "goals")

    bindings: dict[str, Any]
    blackboard: Any

    def _read(self, port: str) -> Any:
        if port in self.bindings:
            return cast(_PortReader, self).get_input(port, None)
        try:
            return self.blackboard.get(port)
        except KeyError:
            return None

    def current_goals(self) -> tuple[Any, Any]:
        return (_plain(self._read("goal")), _plain(self._read("goals")))


@registry.register
class GoalUpdated(GoalsReader, ConditionNode):
    """Whether the goal (``goal``, or ``goals`` for the through-poses trees) has changed.
    Without the ports, the blackboard entries ``goal`` and ``goals`` are read.

    When the node is not active (IDLE: the first tick, or after a parent reset it) it records
    the goals and returns FAILURE. Otherwise it compares the goals now with the recorded ones:
    SUCCESS (and records them) when they differ, FAILURE when they are the same.
    """

    INPUT_PORTS: dict[str, PortInformation] = GOAL_PORTS

    def __init__(self, name: str | None = None, **attributes: Any) -> None:
        super().__init__(name, **attributes)
        self.recorded: tuple[Any, Any] = (None, None)

    def tick_node(self) -> NodeStatus:
        self._was_active = self.bt_status not in (NodeStatus.IDLE, NodeStatus.SKIPPED)
        return super().tick_node()

    _was_active = False

    def records_only(self) -> bool:
        """Whether this tick only records the goals: the node was not active."""
        return not self._was_active

    def update(self) -> Status:
        now = self.current_goals()
        if self.records_only():
            self.recorded = now
            return Status.FAILURE
        if now != self.recorded:
            self.recorded = now
            return Status.SUCCESS
        return Status.FAILURE


@registry.register
class GlobalUpdatedGoal(GoalUpdated):
    """Like GoalUpdated, but it records the goals only on its very first tick, not each time
    it is reset: SUCCESS whenever the goals differ from those it saw last, FAILURE otherwise
    (and on its first tick)."""

    first_time = True

    def records_only(self) -> bool:
        """Whether this tick only records the goals: it is the very first."""
        first, self.first_time = self.first_time, False
        return first


def _plain(value: Any) -> Any:
    """A comparable form of a goal value (lists and arrays become tuples)."""
    try:
        import numpy as np

        if isinstance(value, np.ndarray):
            return tuple(value.ravel().tolist())
    except ImportError:  # pragma: no cover
        pass
    if isinstance(value, list):
        return tuple(_plain(v) for v in value)
    return value
