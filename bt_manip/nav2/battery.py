"""Nav2's IsBatteryLow, on a robot's simulated battery.

A robot's battery is given in the world file (``robots[].battery``: ``percentage`` 0..1,
``voltage``, ``drain`` per second of sim time; see ``worlds/README.md``); without one the
robot's battery is full (1.0, 12 V) and does not drain.

Nav2 reads the battery from a ``sensor_msgs/BatteryState`` topic (``battery_topic``). Here the
blackboard entry named like the topic (without its leading ``/``: ``battery_status`` for
Nav2's default ``/battery_status``) stands in for the topic: when it holds a value, that value
is the battery state and the robot's simulated battery is not read. The value is a number (the
percentage, 0..1) or text ``percentage;voltage``, so ``--bb battery_status=0.1`` or a script
(``battery_status := 0.1``) makes the battery low.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from py_trees.common import Status
from py_trees.ports import PortInformation

from bt_manip.behaviours.base import ROBOT_PORT, ActionFailed, WorldCondition
from bt_manip.bt.ports import NON_NEGATIVE, Port
from bt_manip.bt.registry import registry


@dataclass(frozen=True)
class BatteryState:
    """What IsBatteryLow reads of a battery (Nav2's ``sensor_msgs/BatteryState`` fields)."""

    percentage: float
    voltage: float


def battery_from_value(value: Any) -> BatteryState:
    """A battery state from a blackboard value: a number (the percentage, voltage unknown:
    NaN) or text ``percentage;voltage``."""
    if isinstance(value, BatteryState):
        return value
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        state = BatteryState(float(value), math.nan)
    else:
        parts = [p.strip() for p in str(value).split(";")]
        try:
            numbers = [float(p) for p in parts]
        except ValueError:
            numbers = []
        if len(numbers) not in (1, 2):
            raise ActionFailed(
                f"battery state {value!r} is neither a percentage (0..1) nor "
                "'percentage;voltage'")
        state = BatteryState(numbers[0], numbers[1] if len(numbers) == 2 else math.nan)
    if not 0.0 <= state.percentage <= 1.0:
        raise ActionFailed(f"battery percentage {state.percentage:g} is not within 0..1")
    if not (math.isnan(state.voltage) or 0.0 <= state.voltage < math.inf):
        raise ActionFailed(f"battery voltage {state.voltage:g} is not a voltage")
    return state


def robot_battery(world: Any, robot_name: str) -> BatteryState:
    """The simulated battery of the world's robot ``robot_name`` now (sim time)."""
    for spec in world.spec.robots:
        if spec.name == robot_name:
            battery = spec.battery
            return BatteryState(battery.percentage_at(world.clock.now()), battery.voltage)
    raise ActionFailed(f"no robot named '{robot_name}' in the world file")


@registry.register
class IsBatteryLow(WorldCondition):
    """Whether the robot's battery is low.

    - SUCCESS when the battery's percentage (0..1), or its voltage with ``is_voltage``, is at
      or below ``min_battery`` (the feedback message gives the reading);
    - FAILURE when it is above, or when there is no battery state to read (the reason says
      why; a voltage that was not given counts as unknown).

    The battery state is the blackboard entry named like ``battery_topic`` (without the
    leading ``/``) when it holds a value, else the robot's simulated battery (module
    docstring).
    """

    INPUT_PORTS: dict[str, PortInformation] = {
        "robot": ROBOT_PORT,
        "min_battery": Port(float, False, "Min battery percentage or voltage before triggering "
                            "(fraction or V, see is_voltage)",
                            0.0, NON_NEGATIVE),
        "battery_topic": PortInformation(str, False, "Topic for battery info",
                                         "/battery_status"),
        "is_voltage": PortInformation(bool, False,
                                      "If true voltage will be used to check for low battery",
                                      False),
    }

    def battery(self) -> BatteryState:
        """The battery state: the topic's blackboard entry, else the robot's battery."""
        key = str(self.get_input("battery_topic")).strip().lstrip("/")
        if key:
            try:
                value = self.blackboard.get(key)
            except KeyError:
                value = None
            if value is not None:
                return battery_from_value(value)
        return robot_battery(self.world, self.robot_name())

    def check(self) -> tuple[bool, str]:
        state = self.battery()
        limit = float(self.get_input("min_battery"))
        if bool(self.get_input("is_voltage")):
            if math.isnan(state.voltage):
                return False, "the battery state gives no voltage"
            low, reading = state.voltage <= limit, f"{state.voltage:.2f} V"
        else:
            low, reading = state.percentage <= limit, f"{state.percentage:.3f}"
        self.reading = f"battery at {reading} {'<=' if low else '>'} {limit:g}"
        return low, self.reading

    reading = ""

    def update(self) -> Status:
        self.reading = ""
        status = super().update()
        if status == Status.SUCCESS:
            self.feedback_message = self.reading  # low: say how low (an Inverter may fail on it)
        return status
