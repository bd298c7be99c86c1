"""Nav2's decorator nodes. Durations read the tree's clock (the world's sim clock in a run)."""

from __future__ import annotations

import math
from typing import Any

from py_trees.ports import PortInformation

from bt_manip.behaviours.base import ROBOT_PORT, ActionFailed, WorldAccess
from bt_manip.bt.node import BtNode, DecoratorNode
from bt_manip.bt.ports import POSITIVE, Port
from bt_manip.bt.registry import registry
from bt_manip.bt.status import NodeStatus
from bt_manip.nav2.conditions import GOAL_PORTS, GoalsReader

IDLE = NodeStatus.IDLE
RUNNING = NodeStatus.RUNNING
SUCCESS = NodeStatus.SUCCESS
FAILURE = NodeStatus.FAILURE


@registry.register
class RateController(DecoratorNode):
    """Ticks its child at most ``hz`` times per second.

    When it starts (from IDLE) the child is ticked at once. After that the child is ticked
    again only once ``1/hz`` seconds have passed since the last time it succeeded, or while it
    is RUNNING. It returns the child's status when the child was ticked:

    - child SUCCESS: SUCCESS (the period restarts now);
    - child RUNNING: RUNNING;
    - child FAILURE: FAILURE.

    On a tick where the child is not due it returns RUNNING without ticking it.
    """

    INPUT_PORTS: dict[str, PortInformation] = {
        "hz": Port(float, False, "Rate (Hz)", 10.0, POSITIVE),
    }

    def __init__(self, name: str | None = None, child: BtNode | None = None,
                 **attributes: Any) -> None:
        super().__init__(name, child, **attributes)
        self.started = 0.0
        self.first_time = True

    def tick_node(self) -> NodeStatus:
        period = 1.0 / float(self.get_input("hz"))
        now = self.now()
        if self.bt_status is IDLE:
            self.started = now
            self.first_time = True
        self.set_running()
        due = now - self.started >= period - 1e-9
        if self.first_time or self.child.bt_status is RUNNING or due:
            self.first_time = False
            status = self.child.execute_tick()
            if status is SUCCESS:
                self.started = now
            return status
        return RUNNING


@registry.register
class DistanceController(WorldAccess, DecoratorNode):
    """Ticks its child each time the robot has travelled ``distance`` metres (straight-line,
    from where it was when the child last succeeded).

    When it starts (from IDLE) the child is ticked at once. Later ticks tick the child while
    it is RUNNING or once the robot is ``distance`` from that point; otherwise it returns
    RUNNING without ticking it. Child SUCCESS: SUCCESS (the distance is measured from here
    now); child RUNNING: RUNNING; child FAILURE: FAILURE.
    """

    INPUT_PORTS: dict[str, PortInformation] = {
        "robot": ROBOT_PORT,
        "distance": Port(float, False, "Distance (m)", 1.0, POSITIVE),
        "global_frame": PortInformation(str, False, "Global frame", "map"),
        "robot_base_frame": PortInformation(str, False, "Robot base frame", "base_link"),
    }

    def __init__(self, name: str | None = None, child: BtNode | None = None,
                 **attributes: Any) -> None:
        super().__init__(name, child, **attributes)
        self.start = (0.0, 0.0)
        self.first_time = True

    def tick_node(self) -> NodeStatus:
        try:
            x, y, _ = self.believed_pose()
        except ActionFailed as exc:
            self.feedback_message = str(exc)
            return FAILURE
        if self.bt_status is IDLE:
            self.start = (x, y)
            self.first_time = True
        self.set_running()
        travelled = math.hypot(x - self.start[0], y - self.start[1])
        due = travelled >= float(self.get_input("distance"))
        if self.first_time or self.child.bt_status is RUNNING or due:
            self.first_time = False
            status = self.child.execute_tick()
            if status is SUCCESS:
                self.start = (x, y)
            return status
        return RUNNING


@registry.register
class SingleTrigger(DecoratorNode):
    """Ticks its child through one run only, until the node is reset.

    From IDLE the child may run: child RUNNING gives RUNNING, SUCCESS or FAILURE is returned
    once. Ticked again without a reset in between, it returns FAILURE without ticking the
    child.
    """

    def __init__(self, name: str | None = None, child: BtNode | None = None,
                 **attributes: Any) -> None:
        super().__init__(name, child, **attributes)
        self.first_time = True

    def tick_node(self) -> NodeStatus:
        if self.bt_status is IDLE:
            self.first_time = True
        self.set_running()
        if self.first_time:
            status = self.child.execute_tick()
            if status is not RUNNING:
                self.first_time = False
            return status
        return FAILURE


@registry.register
class GoalUpdatedController(GoalsReader, DecoratorNode):
    """Ticks its child when the goal (``goal`` / ``goals``, or those blackboard entries) has
    changed, and while the child is RUNNING.

    From IDLE it records the goals and ticks the child. Later ticks tick the child only if it
    is RUNNING or the goals differ from the recorded ones (which are then recorded); it returns
    the child's status when ticked, RUNNING otherwise.
    """

    INPUT_PORTS: dict[str, PortInformation] = GOAL_PORTS

    def __init__(self, name: str | None = None, child: BtNode | None = None,
                 **attributes: Any) -> None:
        super().__init__(name, child, **attributes)
        self.recorded: tuple[Any, Any] = (None, None)
        self.updated = True

    def tick_node(self) -> NodeStatus:
        if self.bt_status in (IDLE, NodeStatus.SKIPPED):
            self.recorded = self.current_goals()
            self.updated = True
        self.set_running()
        now = self.current_goals()
        if now != self.recorded:
            self.recorded = now
            self.updated = True
        if self.child.bt_status is RUNNING or self.updated:
            self.updated = False
            return self.child.execute_tick()
        return RUNNING


@registry.register
class SpeedController(GoalsReader, WorldAccess, DecoratorNode):
    """Ticks its child at a rate that grows with the robot's speed: ``min_rate`` at
    ``min_speed`` and below, ``max_rate`` above ``max_speed``, in proportion between.

    From IDLE, and whenever the goal (``goal`` / ``goals``, or those blackboard entries)
    changes, the child is ticked at once. Otherwise the child is ticked while it is RUNNING or
    once the period (1 / rate, the rate taken from the speed when the child was last ticked)
    has passed; it returns the child's status when ticked, RUNNING otherwise. The speed is the
    base's speed now (Nav2 smooths odometry over ``filter_duration``).
    """

    INPUT_PORTS: dict[str, PortInformation] = {
        "robot": ROBOT_PORT,
        **GOAL_PORTS,
        "min_rate": Port(float, False, "Minimum rate (Hz)", 0.1, POSITIVE),
        "max_rate": Port(float, False, "Maximum rate (Hz)", 1.0, POSITIVE),
        "min_speed": Port(float, False, "Minimum speed (m/s)", 0.0),
        "max_speed": Port(float, False, "Maximum speed (m/s)", 0.5),
        "filter_duration": Port(float, False, "Duration (s) for velocity smoothing filter",
                                0.3),
    }

    def __init__(self, name: str | None = None, child: BtNode | None = None,
                 **attributes: Any) -> None:
        super().__init__(name, child, **attributes)
        self.recorded: tuple[Any, Any] = (None, None)
        self.period = 1.0
        self.started = 0.0
        self.first_tick = True

    def _restart(self, now: float) -> None:
        self.period = 1.0 / float(self.get_input("max_rate"))
        self.started = now
        self.first_tick = True

    def _update_period(self) -> None:
        vx, vy, _ = self.robot().base_velocity()
        speed = math.hypot(vx, vy)
        lo_rate, hi_rate = float(self.get_input("min_rate")), float(self.get_input("max_rate"))
        lo, hi = float(self.get_input("min_speed")), float(self.get_input("max_speed"))
        if speed < lo or speed > hi or hi <= lo:
            self.period = 1.0 / (lo_rate if speed < lo else hi_rate)
            return
        self.period = 1.0 / (lo_rate + (hi_rate - lo_rate) * (speed - lo) / (hi - lo))

    def tick_node(self) -> NodeStatus:
        now = self.now()
        if self.bt_status in (IDLE, NodeStatus.SKIPPED):
            self.recorded = self.current_goals()
            self._restart(now)
        goals = self.current_goals()
        if goals != self.recorded:
            self.recorded = goals
            self._restart(now)
        self.set_running()
        due = now - self.started >= self.period - 1e-9
        if self.first_tick or self.child.bt_status is RUNNING or due:
            self.first_tick = False
            try:
                self._update_period()
            except ActionFailed as exc:
                self.feedback_message = str(exc)
                return FAILURE
            self.started = now
            return self.child.execute_tick()
        return RUNNING
